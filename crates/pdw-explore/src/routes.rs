//! The page, its assets and the JSON API (see docs/explore.md for every endpoint), behind the
//! checks of [`crate::guard`].

use crate::error::ApiError;
use crate::grid::Grid;
use crate::jobs::{CancelAnswer, Status};
use crate::source::Window;
use crate::{AppState, MAX_BODY, MAX_WINDOW_CELLS};
use axum::body::Bytes;
use axum::extract::{DefaultBodyLimit, Path, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use serde::Deserialize;
use serde_json::{json, Value};
use std::sync::Arc;

type St = State<Arc<AppState>>;
type ApiResult = Result<Json<Value>, ApiError>;

const INDEX_HTML: &str = include_str!("assets/index.html");
const APP_JS: &str = include_str!("assets/app.js");
const APP_CSS: &str = include_str!("assets/app.css");

/// Every route, the body cap, the JSON 404, and in front of them all the guard.
pub fn router(state: Arc<AppState>, guard: Arc<crate::guard::Guard>) -> Router {
    Router::new()
        .route("/", get(|| asset(INDEX_HTML, "text/html; charset=utf-8")))
        .route(
            "/app.js",
            get(|| asset(APP_JS, "text/javascript; charset=utf-8")),
        )
        .route(
            "/app.css",
            get(|| asset(APP_CSS, "text/css; charset=utf-8")),
        )
        .route("/api/files", get(files))
        .route("/api/basin/{i}", get(basin))
        .route("/api/walk", post(walk))
        .route("/api/sweep/{i}", get(sweep))
        .route("/api/gait", post(gait))
        .route("/api/design/{i}", get(design))
        .route("/api/design_walk", post(design_walk))
        .route("/api/refine", post(refine))
        .route("/api/job/{id}", get(job))
        .route("/api/job/{id}/cancel", post(cancel))
        .route("/api/save", post(save))
        .route("/api/stats", get(stats))
        .fallback(|| async { ApiError::not_found("no such page or API endpoint") })
        .layer(DefaultBodyLimit::max(MAX_BODY))
        .layer(axum::middleware::from_fn_with_state(
            guard,
            crate::guard::check,
        ))
        .with_state(state)
}

async fn asset(body: &'static str, mime: &'static str) -> Response {
    ([(header::CONTENT_TYPE, mime)], body).into_response()
}

/// Runs `f` on the blocking pool (computations never run on the runtime's two workers).
async fn blocking<T: Send + 'static>(
    f: impl FnOnce() -> Result<T, ApiError> + Send + 'static,
) -> Result<T, ApiError> {
    tokio::task::spawn_blocking(f)
        .await
        .map_err(|_| ApiError::internal("the computation panicked"))?
}

/// A request body as received, or why it was not (too large: 413).
type Body = Result<Bytes, axum::extract::rejection::BytesRejection>;

/// A JSON body of type `T`, or an error saying what is wrong with it (413 for a body over
/// [`MAX_BODY`], 400 for one that is not the JSON asked for).
fn parse<T: serde::de::DeserializeOwned>(body: Body) -> Result<T, ApiError> {
    let body = body.map_err(|r| ApiError {
        status: r.status(),
        message: format!("request body: {} (at most {MAX_BODY} bytes)", r.body_text()),
    })?;
    serde_json::from_slice(&body).map_err(|e| ApiError::bad_request(format!("request body: {e}")))
}

/// A path number, or a 400.
fn number(s: &str, what: &str) -> Result<u64, ApiError> {
    s.parse()
        .map_err(|_| ApiError::bad_request(format!("{what} '{s}' is not a whole number")))
}

/// `GET /api/files`: index, file name (no directories), kind (or the error reading it).
async fn files(State(s): St) -> ApiResult {
    let s2 = s.clone();
    let list = blocking(move || {
        Ok(s2
            .entries
            .iter()
            .enumerate()
            .map(|(i, e)| {
                let name = e
                    .path
                    .file_name()
                    .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
                file_kind(e, i, name)
            })
            .collect::<Vec<_>>())
    })
    .await?;
    Ok(Json(json!({ "files": list })))
}

/// File `i`'s list entry: a basin, sweep or design file, or the error reading it as a basin.
fn file_kind(e: &crate::Entry, i: usize, name: String) -> Value {
    let err = match e.source() {
        Ok(src) => {
            return json!({"index": i, "name": name, "kind": "basin",
                          "model": src.data.header.model})
        }
        Err(err) => err,
    };
    if let Ok(sw) = e.sweep() {
        return json!({"index": i, "name": name, "kind": "sweep", "model": sw.model});
    }
    if let Ok(d) = e.design() {
        let model = crate::design::to_json(&d).map_or(Value::Null, |v| v["model"].clone());
        return json!({"index": i, "name": name, "kind": "design", "model": model});
    }
    json!({"index": i, "name": name, "kind": "error", "error": err.message})
}

/// `GET /api/design/{i}`: the designs table of design file i ([`crate::design::to_json`]).
async fn design(State(s): St, Path(i): Path<String>) -> ApiResult {
    let i = number(&i, "file")? as usize;
    s.entry(i)?;
    let v = blocking(move || {
        let d = s.entry(i)?.design()?;
        let mut v = crate::design::to_json(&d)?;
        v["file"] = json!(i);
        Ok(v)
    })
    .await?;
    Ok(Json(v))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DesignWalkRequest {
    file: usize,
    design: usize,
}

/// `POST /api/design_walk {file, design}`: a design's gait walked ([`crate::design::walk`]).
async fn design_walk(State(s): St, body: Body) -> ApiResult {
    let req: DesignWalkRequest = parse(body)?;
    s.entry(req.file)?;
    let v = blocking(move || {
        let d = s.entry(req.file)?.design()?;
        crate::design::walk(&d, req.design)
    })
    .await?;
    Ok(Json(v))
}

/// `GET /api/basin/{i}`: the basin of file i ([`Grid::to_json_bytes`]) with its model; one of
/// the large responses [`crate::heavy`] bounds.
async fn basin(State(s): St, Path(i): Path<String>) -> Result<Response, ApiError> {
    let i = number(&i, "file")? as usize;
    s.entry(i)?;
    let permit = s.heavy.enter().await?;
    let bytes = blocking(move || {
        let src = s.entry(i)?.source()?;
        let h = &src.data.header;
        let params: Vec<(String, f64)> =
            serde_json::from_str::<serde_json::Map<String, Value>>(&h.params)
                .unwrap_or_default()
                .into_iter()
                .filter_map(|(n, v)| Some((n, v.as_f64()?)))
                .collect();
        let mut extra = serde_json::Map::new();
        extra.insert("file".into(), json!(i));
        extra.insert("model".into(), json!(h.model));
        extra.insert("slope".into(), json!(h.slope));
        extra.insert("max_strides".into(), json!(h.max_strides));
        extra.insert("coordinates".into(), src.coordinates.clone());
        Grid::of_file(&src).to_json_bytes(&params, extra)
    })
    .await?;
    Ok(crate::heavy::response(bytes, permit))
}

/// `GET /api/sweep/{i}`: the branches of sweep file i ([`crate::sweep::to_json`]).
async fn sweep(State(s): St, Path(i): Path<String>) -> ApiResult {
    let i = number(&i, "file")? as usize;
    s.entry(i)?;
    let v = blocking(move || {
        let d = s.entry(i)?.sweep()?;
        let mut v = crate::sweep::to_json(&d);
        v["file"] = json!(i);
        Ok(v)
    })
    .await?;
    Ok(Json(v))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GaitRequest {
    file: usize,
    branch: usize,
    point: usize,
}

/// `POST /api/gait {file, branch, point}`: a branch point's multipliers and a walk of its gait.
async fn gait(State(s): St, body: Body) -> ApiResult {
    let req: GaitRequest = parse(body)?;
    s.entry(req.file)?;
    let v = blocking(move || {
        let e = s.entry(req.file)?;
        let d = e.sweep()?;
        let spec = pdw::store::provenance::read_model_spec(&e.path)
            .ok()
            .flatten();
        crate::sweep::gait(&d, spec.as_deref(), req.branch, req.point)
    })
    .await?;
    Ok(Json(v))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct WalkRequest {
    file: usize,
    /// `[row, column]`: row = y index.
    cell: [usize; 2],
    /// The z-slice of a 3-D file.
    #[serde(default)]
    slice: usize,
    /// A refined window's job: the cell is of that window.
    #[serde(default)]
    job: Option<u64>,
}

/// `POST /api/walk`: the cell's label by the basin engine, the file's label, and the walk.
async fn walk(State(s): St, body: Body) -> ApiResult {
    let req: WalkRequest = parse(body)?;
    s.entry(req.file)?;
    let v = blocking(move || walk_cell(&s, &req)).await?;
    Ok(Json(v))
}

fn walk_cell(s: &AppState, req: &WalkRequest) -> Result<Value, ApiError> {
    let t0 = std::time::Instant::now();
    match req.job {
        Some(id) => {
            let r = s
                .jobs
                .result(id)
                .ok_or_else(|| ApiError::not_found(format!("no finished window {id}")))?;
            walk_json(s, &r.rebuilt, &r.grid, req, t0)
        }
        None => {
            let e = s.entry(req.file)?;
            let r = e.rebuilt(&s.pool)?;
            let src = e.source()?;
            walk_json(s, &r, &Grid::of_file(&src), req, t0)
        }
    }
}

/// The cell of `req` on `grid` walked with run `r`.
fn walk_json(
    s: &AppState,
    r: &crate::source::Rebuilt,
    grid: &Grid,
    req: &WalkRequest,
    t0: std::time::Instant,
) -> Result<Value, ApiError> {
    let (nx, ny, nz) = (grid.nx(), grid.ny(), grid.nz());
    let [row, col] = req.cell;
    if row >= ny || col >= nx || req.slice >= nz {
        return Err(ApiError::bad_request(format!(
            "cell [{row}, {col}] slice {} is outside the {nx}x{ny}x{nz} grid",
            req.slice
        )));
    }
    let grid_row = req.slice * ny + row;
    let cell = r.plan.row_cells(&[grid_row]).swap_remove(col);
    let res = crate::walk::classify(r, &cell, &s.pool)?;
    let label = crate::walk::outcome_name(r, res.outcome);
    let stored_code = grid.outcome[grid_row * nx + col];
    let stored = grid
        .legend
        .iter()
        .find(|(c, _)| *c == stored_code)
        .map_or_else(
            || pdw::store::basin::NOT_COMPUTED_NAME.to_string(),
            |(_, n)| n.clone(),
        );
    let steps = (usize::from(res.strides) + 1)
        .clamp(crate::walk::MIN_WALK_STEPS, crate::walk::MAX_WALK_STEPS);
    let tr = crate::walk::walk(r, &cell, steps)?;
    Ok(json!({
        "cell": {"row": row, "col": col, "slice": req.slice, "state": cell,
                 "names": r.m.info.section_names},
        "outcome": label,
        "stored": stored,
        "strides": res.strides,
        "stored_strides": grid.strides[grid_row * nx + col],
        "walk": crate::walk::walk_json(&r.m, &tr),
        "ms": t0.elapsed().as_secs_f64() * 1e3,
    }))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RefineRequest {
    file: usize,
    /// `{"x": [lo, hi], "y": [lo, hi]}` in the axes' units.
    #[serde(rename = "box")]
    bx: BoxBounds,
    nx: usize,
    ny: usize,
    #[serde(default)]
    slice: usize,
    /// Parameter overrides (the sliders).
    #[serde(default)]
    set: std::collections::BTreeMap<String, f64>,
    /// Hold the request open until the window is computed (a disconnect cancels it).
    #[serde(default)]
    wait: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxBounds {
    x: [f64; 2],
    y: [f64; 2],
}

impl RefineRequest {
    fn check(&self) -> Result<(), ApiError> {
        let cells = self.nx.saturating_mul(self.ny);
        if self.nx < 2 || self.ny < 2 || cells > MAX_WINDOW_CELLS {
            return Err(ApiError::bad_request(format!(
                "nx x ny = {}x{}: each at least 2, at most {MAX_WINDOW_CELLS} cells in all",
                self.nx, self.ny
            )));
        }
        for (n, [lo, hi]) in [("x", self.bx.x), ("y", self.bx.y)] {
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(ApiError::bad_request(format!(
                    "box {n}: {lo}:{hi} is empty, inverted or not finite"
                )));
            }
        }
        if let Some((n, v)) = self.set.iter().find(|(_, v)| !v.is_finite()) {
            return Err(ApiError::bad_request(format!("set {n}: {v} is not finite")));
        }
        Ok(())
    }
}

/// `POST /api/refine`: queues the window (cancelling older ones); `{job}`, or with `wait` the
/// job's status once finished.
async fn refine(State(s): St, body: Body) -> Result<Response, ApiError> {
    let req: RefineRequest = parse(body)?;
    req.check()?;
    s.entry(req.file)?;
    let s2 = s.clone();
    let file = req.file;
    let src = blocking(move || s2.entry(file)?.source()).await?;
    let z = src.data.header.z.as_ref().map(|z| &z.values);
    let nz = z.map_or(1, |z| z.len());
    if req.slice >= nz {
        return Err(ApiError::bad_request(format!(
            "slice {}: the file has {nz} slice(s), numbered from 0",
            req.slice
        )));
    }
    let z_fixed = z.map(|z| z[req.slice]);
    let axes = Grid::axes_of(&src);
    let w = Window {
        bounds: Some((req.bx.x[0], req.bx.x[1], req.bx.y[0], req.bx.y[1])),
        grid: Some((req.nx, req.ny)),
        z_fixed,
        overrides: req.set.iter().map(|(n, v)| (n.clone(), *v)).collect(),
    };
    let key = serde_json::to_string(&json!([
        file, req.bx.x, req.bx.y, req.nx, req.ny, req.slice, req.set
    ]))
    .unwrap_or_default();
    let id = s.jobs.submit(key, file, src, w, axes);
    if !req.wait {
        return Ok(Json(json!({ "job": id })).into_response());
    }
    let guard = CancelOnDrop {
        s: s.clone(),
        id,
        armed: true,
    };
    loop {
        tokio::time::sleep(std::time::Duration::from_millis(20)).await;
        match s.jobs.status(id) {
            Some((Status::Queued | Status::Running, ..)) => continue,
            _ => break,
        }
    }
    let mut guard = guard;
    guard.armed = false;
    job(State(s), Path(id.to_string())).await
}

/// Cancels its job when dropped armed: a client that disconnects while waiting drops the
/// request's future, and with it the computation.
struct CancelOnDrop {
    s: Arc<AppState>,
    id: u64,
    armed: bool,
}

impl Drop for CancelOnDrop {
    fn drop(&mut self) {
        if self.armed {
            self.s.jobs.cancel(self.id);
        }
    }
}

/// `GET /api/job/{id}`: status, progress and phase, and the window once done (a large
/// response, bounded by [`crate::heavy`]).
async fn job(State(s): St, Path(id): Path<String>) -> Result<Response, ApiError> {
    let id = number(&id, "job")?;
    let (st, done, total, phase) = s
        .jobs
        .status(id)
        .ok_or_else(|| ApiError::not_found(format!("no job {id}")))?;
    let name = crate::jobs::status_name(&st);
    let v = match st {
        Status::Queued | Status::Running => json!({"job": id, "status": name, "done": done,
                                                   "total": total, "phase": phase.name()}),
        Status::Cancelled(p) => json!({"job": id, "status": name, "done": done, "total": total,
                                       "phase": p.name()}),
        Status::Failed(e) => json!({"job": id, "status": name, "error": e.message}),
        Status::Evicted => json!({"job": id, "status": name, "error": format!(
            "job {id}'s window was dropped from the cache (at most {} MiB of windows are \
             kept, the least recently used leave first): refine it again",
            s.jobs.cache_cap >> 20)}),
        Status::Done(r) => {
            let permit = s.heavy.enter().await?;
            let params = r.rebuilt.m.params.clone();
            let mut extra = serde_json::Map::new();
            extra.insert("job".into(), json!(id));
            extra.insert("status".into(), json!("done"));
            extra.insert("done".into(), json!(total));
            extra.insert("total".into(), json!(total));
            let bytes = blocking(move || r.grid.to_json_bytes(&params, extra)).await?;
            return Ok(crate::heavy::response(bytes, permit));
        }
    };
    Ok(Json(v).into_response())
}

/// `POST /api/job/{id}/cancel`: `cancelled: true` for a job queued or running; a job that had
/// ended says so (`cancelled: false` and its status).
async fn cancel(State(s): St, Path(id): Path<String>) -> ApiResult {
    let id = number(&id, "job")?;
    match s.jobs.cancel(id) {
        CancelAnswer::Unknown => Err(ApiError::not_found(format!("no job {id}"))),
        CancelAnswer::Cancelled => Ok(Json(json!({"job": id, "cancelled": true}))),
        CancelAnswer::Finished(st) => Ok(Json(json!({
            "job": id, "cancelled": false, "status": st,
            "message": format!("job {id} had already finished ({st}): nothing to cancel"),
        }))),
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SaveRequest {
    job: u64,
}

/// `POST /api/save {job}`: the window written as a basin file in the save directory; the
/// file name is the server's.
async fn save(State(s): St, body: Body) -> ApiResult {
    let req: SaveRequest = parse(body)?;
    let r = s
        .jobs
        .result(req.job)
        .ok_or_else(|| ApiError::not_found(format!("no finished window {}", req.job)))?;
    let path = blocking(move || {
        let src = s.entry(r.file)?.source()?;
        crate::save::save(&src, &r, &s.save_dir)
    })
    .await?;
    let name = path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    Ok(Json(json!({"saved": name})))
}

/// `GET /api/stats`: refine jobs started, completed and evicted; the cache's bytes and cap.
async fn stats(State(s): St) -> ApiResult {
    use std::sync::atomic::Ordering;
    let c = &s.jobs.counters;
    Ok(Json(json!({
        "refines_started": c.started.load(Ordering::SeqCst),
        "refines_completed": c.completed.load(Ordering::SeqCst),
        "windows_evicted": c.evicted.load(Ordering::SeqCst),
        "cache_bytes": s.jobs.cache_bytes(),
        "cache_cap": s.jobs.cache_cap,
        "jobs_kept": s.jobs.records(),
    })))
}
