//! Refine jobs: a dragged box recomputed by the basin engine, one job at a time.
//!
//! A new request cancels every older one (the page only wants the window last asked for), so
//! rapid drags never pile up: one worker thread takes the newest job waiting, skipping the
//! others. A running job stops between row chunks when its cancel flag is set (its own flag:
//! the process-wide interrupt of `pdw_hybrid` would stop every other computation too).
//! Results are cached by request, so asking again for a window already computed answers at
//! once.

use crate::error::ApiError;
use crate::grid::Grid;
use crate::source::{rebuild, BasinSource, Rebuilt, Window};
use pdw_limit::basin::{classify_cells, Outcome};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::Duration;

/// Most cells per engine call: a cancel is honoured between calls.
const CELLS_PER_CALL: usize = 4096;
/// Time the worker waits for a newer request before it starts a job (rapid drags).
const SETTLE: Duration = Duration::from_millis(30);

/// A finished window: the rebuilt run and its labelled grid.
pub struct Refined {
    pub rebuilt: Rebuilt,
    pub grid: Grid,
    /// Final section state of every cell (cells × d), for saving.
    pub final_state: Vec<f64>,
    pub file: usize,
    pub seconds: f64,
}

/// Where a job is.
#[derive(Clone)]
pub enum Status {
    Queued,
    Running,
    Done(Arc<Refined>),
    Cancelled,
    Failed(ApiError),
}

/// One job: what it computes and how far it is.
pub struct Job {
    pub key: String,
    pub status: Status,
    pub cancel: Arc<AtomicBool>,
    pub done: Arc<AtomicUsize>,
    pub total: usize,
    src: Option<(Arc<BasinSource>, Window, usize, Grid)>,
}

/// Counters of the jobs the worker ran: `started` (a computation began), `completed`.
#[derive(Default)]
pub struct Counters {
    pub started: AtomicUsize,
    pub completed: AtomicUsize,
}

/// The jobs, the cache and the worker's queue.
pub struct Jobs {
    jobs: Mutex<HashMap<u64, Job>>,
    next: AtomicUsize,
    cache: Mutex<HashMap<String, u64>>,
    tx: Mutex<mpsc::Sender<u64>>,
    pub counters: Counters,
}

impl Jobs {
    /// The job table and its worker thread, computing on `pool`.
    pub fn start(pool: Arc<rayon::ThreadPool>) -> Arc<Jobs> {
        let (tx, rx) = mpsc::channel::<u64>();
        let jobs = Arc::new(Jobs {
            jobs: Mutex::new(HashMap::new()),
            next: AtomicUsize::new(1),
            cache: Mutex::new(HashMap::new()),
            tx: Mutex::new(tx),
            counters: Counters::default(),
        });
        let weak = Arc::downgrade(&jobs);
        std::thread::Builder::new()
            .name("pdw-explore-refine".into())
            .spawn(move || worker(weak, rx, pool))
            .expect("the refine worker thread starts");
        jobs
    }

    /// Queues a window of file `file` (grid `base` drawn from `src`), cancelling every older
    /// job; a window already computed (or being computed) answers with its job. Returns the id.
    pub fn submit(
        &self,
        key: String,
        file: usize,
        src: Arc<BasinSource>,
        w: Window,
        base: Grid,
    ) -> u64 {
        let mut jobs = self.jobs.lock().expect("jobs lock");
        if let Some(&id) = self.cache.lock().expect("cache lock").get(&key) {
            if let Some(j) = jobs.get(&id) {
                if matches!(j.status, Status::Done(_) | Status::Running | Status::Queued) {
                    return id;
                }
            }
        }
        for j in jobs.values_mut() {
            if matches!(j.status, Status::Queued | Status::Running) {
                j.cancel.store(true, Ordering::SeqCst);
                if matches!(j.status, Status::Queued) {
                    j.status = Status::Cancelled;
                }
            }
        }
        let id = self.next.fetch_add(1, Ordering::SeqCst) as u64;
        let total = w.grid.map_or(0, |(nx, ny)| nx * ny);
        jobs.insert(
            id,
            Job {
                key: key.clone(),
                status: Status::Queued,
                cancel: Arc::new(AtomicBool::new(false)),
                done: Arc::new(AtomicUsize::new(0)),
                total,
                src: Some((src, w, file, base)),
            },
        );
        self.cache.lock().expect("cache lock").insert(key, id);
        let _ = self.tx.lock().expect("queue lock").send(id);
        id
    }

    /// The status of job `id` and its progress `(done, total)` cells.
    pub fn status(&self, id: u64) -> Option<(Status, usize, usize)> {
        let jobs = self.jobs.lock().expect("jobs lock");
        jobs.get(&id)
            .map(|j| (j.status.clone(), j.done.load(Ordering::Relaxed), j.total))
    }

    /// Cancels job `id` (if queued or running); whether there was such a job.
    pub fn cancel(&self, id: u64) -> bool {
        let mut jobs = self.jobs.lock().expect("jobs lock");
        let Some(j) = jobs.get_mut(&id) else {
            return false;
        };
        j.cancel.store(true, Ordering::SeqCst);
        if matches!(j.status, Status::Queued) {
            j.status = Status::Cancelled;
        }
        true
    }

    /// The finished window of job `id`.
    pub fn result(&self, id: u64) -> Option<Arc<Refined>> {
        match self.status(id)?.0 {
            Status::Done(r) => Some(r),
            _ => None,
        }
    }

    fn set_status(&self, id: u64, s: Status) {
        if let Some(j) = self.jobs.lock().expect("jobs lock").get_mut(&id) {
            if matches!(s, Status::Cancelled | Status::Failed(_)) {
                let key = j.key.clone();
                let mut cache = self.cache.lock().expect("cache lock");
                if cache.get(&key) == Some(&id) {
                    cache.remove(&key);
                }
            }
            j.status = s;
        }
    }
}

/// The worker: takes the newest job queued, skips those cancelled, computes it.
fn worker(jobs: std::sync::Weak<Jobs>, rx: mpsc::Receiver<u64>, pool: Arc<rayon::ThreadPool>) {
    while let Ok(mut id) = rx.recv() {
        std::thread::sleep(SETTLE);
        while let Ok(newer) = rx.try_recv() {
            id = newer;
        }
        let Some(jobs) = jobs.upgrade() else { return };
        let taken = {
            let mut table = jobs.jobs.lock().expect("jobs lock");
            match table.get_mut(&id) {
                Some(j) if !j.cancel.load(Ordering::SeqCst) => {
                    j.status = Status::Running;
                    j.src.take().map(|s| (s, j.cancel.clone(), j.done.clone()))
                }
                _ => None,
            }
        };
        let Some(((src, w, file, base), cancel, done)) = taken else {
            continue;
        };
        jobs.counters.started.fetch_add(1, Ordering::SeqCst);
        let t0 = std::time::Instant::now();
        match compute(&src, &w, &pool, &cancel, &done) {
            Ok(None) => jobs.set_status(id, Status::Cancelled),
            Ok(Some((rebuilt, outcome, strides, final_state))) => {
                let grid = Grid::of_window(&rebuilt, outcome, strides, &base);
                let refined = Refined {
                    rebuilt,
                    grid,
                    final_state,
                    file,
                    seconds: t0.elapsed().as_secs_f64(),
                };
                jobs.counters.completed.fetch_add(1, Ordering::SeqCst);
                jobs.set_status(id, Status::Done(Arc::new(refined)));
            }
            Err(e) => jobs.set_status(id, Status::Failed(e)),
        }
    }
}

/// What a window computes to: the run, outcome codes, strides, final states.
pub type Computed = (Rebuilt, Vec<u8>, Vec<u16>, Vec<f64>);

/// Window `w` of `src` labelled as `pdw-sweep basin` labels that box: the same plan, gaits and
/// attractor discovery ([`rebuild`]), the cells classified row chunk by row chunk and
/// relabelled by the attractors. `None` when `cancel` was set.
pub fn compute(
    src: &BasinSource,
    w: &Window,
    pool: &rayon::ThreadPool,
    cancel: &AtomicBool,
    done: &AtomicUsize,
) -> Result<Option<Computed>, ApiError> {
    let r = rebuild(src, w, pool)?;
    let (nx, ny) = (r.plan.bx.nx, r.plan.bx.ny);
    let fall = Outcome::of_fall;
    let problem = r.set.problem(r.m.walker.as_ref(), &fall);
    let rows_per_call = (CELLS_PER_CALL / nx).max(1);
    let (mut outcome, mut strides, mut fin) = (Vec::new(), Vec::new(), Vec::new());
    let rows: Vec<usize> = (0..ny).collect();
    for chunk in rows.chunks(rows_per_call) {
        if cancel.load(Ordering::SeqCst) {
            return Ok(None);
        }
        let before = outcome.len();
        let mut res = classify_cells(
            &problem,
            &r.plan.row_cells(chunk),
            &r.plan.opts,
            pool,
            &|n| done.store(before + n, Ordering::Relaxed),
        )
        .map_err(|e| ApiError::internal(format!("classifying the window: {e}")))?;
        r.set.relabel(&mut res);
        outcome.extend(res.iter().map(|c| c.outcome));
        strides.extend(res.iter().map(|c| c.strides));
        fin.extend(res.iter().flat_map(|c| c.final_state.iter().copied()));
        done.store(outcome.len(), Ordering::Relaxed);
    }
    Ok(Some((r, outcome, strides, fin)))
}
