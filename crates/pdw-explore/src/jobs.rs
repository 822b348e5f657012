//! Refine jobs: a dragged box recomputed by the basin engine, one job at a time.
//!
//! A new request cancels every older one (the page only wants the window last asked for), so
//! rapid drags never pile up: one worker thread takes the newest job waiting, skipping the
//! others. A running job stops at its next step when cancelled: between its phases (after
//! the gait search, after the attractor discovery) and between row chunks of its cells; the
//! gait search and the attractor discovery themselves run to their end (the integrator's stop
//! request is process-wide: it would stop the walks too). The worker computes on a rayon pool
//! of its own, so that walks never wait behind a window.
//!
//! Finished windows are cached by request, so asking again for a window already computed
//! answers at once; the cache holds at most [`CACHE_BYTES`] of windows (their arrays: outcome,
//! strides, final states, axes) and drops the least recently used beyond (its job then answers
//! `evicted`). At most [`MAX_RECORDS`] jobs are remembered in all; the oldest finished ones are
//! forgotten first.

use crate::error::ApiError;
use crate::grid::{Grid, GridAxis};
use crate::source::{rebuild_with, BasinSource, Rebuilt, Window};
use pdw::limit::basin::{classify_cells, Outcome};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicU8, AtomicUsize, Ordering};
use std::sync::{mpsc, Arc, Condvar, Mutex};
use std::time::Duration;

/// Most cells per engine call: a cancel is honoured between calls.
const CELLS_PER_CALL: usize = 4096;
/// Time the worker waits for a newer request before it starts a job (rapid drags).
const SETTLE: Duration = Duration::from_millis(30);
/// Bytes of finished windows the cache keeps by default (256 MiB: a 1000x1000 window of a
/// two-coordinate section is about 19 MB).
pub const CACHE_BYTES: usize = 256 << 20;
/// Jobs remembered in all (finished, cancelled, failed, evicted, and those under way).
pub const MAX_RECORDS: usize = 1024;

/// The phase a job is in (or was in when it stopped).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Building the model and the box.
    Model = 0,
    /// The gait search of the model (with the sliders' values).
    GaitSearch = 1,
    /// The attractor discovery on the box.
    Attractors = 2,
    /// Classifying the cells.
    Cells = 3,
}

impl Phase {
    fn of(v: u8) -> Phase {
        match v {
            1 => Phase::GaitSearch,
            2 => Phase::Attractors,
            3 => Phase::Cells,
            _ => Phase::Model,
        }
    }

    /// The phase's name in the API (`gait search`, …).
    pub fn name(self) -> &'static str {
        match self {
            Phase::Model => "model",
            Phase::GaitSearch => "gait search",
            Phase::Attractors => "attractor discovery",
            Phase::Cells => "cells",
        }
    }
}

/// A finished window: the rebuilt run and its labelled grid.
pub struct Refined {
    pub rebuilt: Rebuilt,
    pub grid: Grid,
    /// Final section state of every cell (cells × d), for saving.
    pub final_state: Vec<f64>,
    pub file: usize,
    pub seconds: f64,
}

impl Refined {
    /// Bytes of the window's arrays (what the cache counts).
    pub fn bytes(&self) -> usize {
        let g = &self.grid;
        g.outcome.len()
            + 2 * g.strides.len()
            + 8 * (self.final_state.len() + g.x.values.len() + g.y.values.len())
    }
}

/// Where a job is.
#[derive(Clone)]
pub enum Status {
    Queued,
    Running,
    Done(Arc<Refined>),
    /// Stopped in this phase.
    Cancelled(Phase),
    Failed(ApiError),
    /// Finished, then dropped from the cache.
    Evicted,
}

/// What a cancel found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CancelAnswer {
    /// The job was queued or running and is being stopped.
    Cancelled,
    /// The job had already ended, with this status.
    Finished(&'static str),
    /// No such job.
    Unknown,
}

/// What a queued job computes: the file, the window, the file's index, its axes (units).
type Source = (Arc<BasinSource>, Window, usize, (GridAxis, GridAxis));

/// One job: what it computes and how far it is.
pub struct Job {
    pub key: String,
    pub status: Status,
    pub cancel: Arc<AtomicBool>,
    pub done: Arc<AtomicUsize>,
    pub phase: Arc<AtomicU8>,
    pub total: usize,
    /// When last asked for (the cache's order).
    used: u64,
    src: Option<Source>,
}

impl Job {
    fn active(&self) -> bool {
        matches!(self.status, Status::Queued | Status::Running)
    }
}

/// Counters of the jobs the worker ran: `started` (a computation began), `completed`.
#[derive(Default)]
pub struct Counters {
    pub started: AtomicUsize,
    pub completed: AtomicUsize,
    pub evicted: AtomicUsize,
}

/// The table of jobs and the cache's byte count, under one lock.
#[derive(Default)]
struct Table {
    jobs: HashMap<u64, Job>,
    cache: HashMap<String, u64>,
    bytes: usize,
    tick: u64,
}

/// The jobs, the cache and the worker's queue.
pub struct Jobs {
    table: Mutex<Table>,
    next: AtomicUsize,
    tx: Mutex<mpsc::Sender<u64>>,
    /// Byte cap of the cache.
    pub cache_cap: usize,
    /// Whether the worker is held before its next job ([`Jobs::hold`]).
    held: (Mutex<usize>, Condvar),
    pub counters: Counters,
}

/// The worker held: it takes no job until this is dropped.
pub struct Hold<'a>(&'a Jobs);

impl Drop for Hold<'_> {
    fn drop(&mut self) {
        let (m, cv) = &self.0.held;
        *m.lock().expect("hold lock") -= 1;
        cv.notify_all();
    }
}

impl Jobs {
    /// The job table and its worker thread, computing on a pool built by `b`; the cache keeps
    /// at most `cache_cap` bytes.
    pub fn start(b: rayon::ThreadPoolBuilder, cache_cap: usize) -> Result<Arc<Jobs>, String> {
        let (tx, rx) = mpsc::channel::<u64>();
        let pool = b.build().map_err(|e| e.to_string())?;
        let jobs = Arc::new(Jobs {
            table: Mutex::new(Table::default()),
            next: AtomicUsize::new(1),
            tx: Mutex::new(tx),
            cache_cap,
            held: (Mutex::new(0), Condvar::new()),
            counters: Counters::default(),
        });
        let weak = Arc::downgrade(&jobs);
        std::thread::Builder::new()
            .name("pdw-explore-refine".into())
            .spawn(move || worker(weak, rx, pool))
            .map_err(|e| format!("the refine worker thread: {e}"))?;
        Ok(jobs)
    }

    /// Holds the worker before its next job until the guard is dropped (a job it computes
    /// goes on): requests sent meanwhile queue, and the newest is the one computed.
    pub fn hold(&self) -> Hold<'_> {
        *self.held.0.lock().expect("hold lock") += 1;
        Hold(self)
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Table> {
        self.table.lock().expect("jobs lock")
    }

    /// Queues a window of file `file` (axes `axes` of `src`), cancelling every older job; a
    /// window already computed (or being computed) answers with its job. Returns the id.
    pub fn submit(
        &self,
        key: String,
        file: usize,
        src: Arc<BasinSource>,
        w: Window,
        axes: (GridAxis, GridAxis),
    ) -> u64 {
        let mut t = self.lock();
        t.tick += 1;
        let tick = t.tick;
        if let Some(&id) = t.cache.get(&key) {
            if let Some(j) = t.jobs.get_mut(&id) {
                if matches!(j.status, Status::Done(_) | Status::Running | Status::Queued) {
                    j.used = tick;
                    return id;
                }
            }
        }
        for j in t.jobs.values_mut() {
            if j.active() {
                j.cancel.store(true, Ordering::SeqCst);
                if matches!(j.status, Status::Queued) {
                    j.status = Status::Cancelled(Phase::Model);
                    j.src = None;
                }
            }
        }
        let id = self.next.fetch_add(1, Ordering::SeqCst) as u64;
        let total = w.grid.map_or(0, |(nx, ny)| nx * ny);
        t.jobs.insert(
            id,
            Job {
                key: key.clone(),
                status: Status::Queued,
                cancel: Arc::new(AtomicBool::new(false)),
                done: Arc::new(AtomicUsize::new(0)),
                phase: Arc::new(AtomicU8::new(0)),
                total,
                used: tick,
                src: Some((src, w, file, axes)),
            },
        );
        t.cache.insert(key, id);
        forget_oldest(&mut t);
        let _ = self.tx.lock().expect("queue lock").send(id);
        id
    }

    /// The status of job `id`, its progress `(done, total)` cells and its phase.
    pub fn status(&self, id: u64) -> Option<(Status, usize, usize, Phase)> {
        let mut t = self.lock();
        t.tick += 1;
        let tick = t.tick;
        t.jobs.get_mut(&id).map(|j| {
            j.used = tick;
            (
                j.status.clone(),
                j.done.load(Ordering::Relaxed),
                j.total,
                Phase::of(j.phase.load(Ordering::Relaxed)),
            )
        })
    }

    /// Cancels job `id` if queued or running; says what it found.
    pub fn cancel(&self, id: u64) -> CancelAnswer {
        let mut t = self.lock();
        let Some(j) = t.jobs.get_mut(&id) else {
            return CancelAnswer::Unknown;
        };
        match &j.status {
            Status::Queued => {
                j.cancel.store(true, Ordering::SeqCst);
                j.status = Status::Cancelled(Phase::Model);
                j.src = None;
                CancelAnswer::Cancelled
            }
            Status::Running => {
                j.cancel.store(true, Ordering::SeqCst);
                CancelAnswer::Cancelled
            }
            s => CancelAnswer::Finished(status_name(s)),
        }
    }

    /// The finished window of job `id`.
    pub fn result(&self, id: u64) -> Option<Arc<Refined>> {
        match self.status(id)?.0 {
            Status::Done(r) => Some(r),
            _ => None,
        }
    }

    /// Bytes of windows the cache holds now.
    pub fn cache_bytes(&self) -> usize {
        self.lock().bytes
    }

    /// Jobs remembered now.
    pub fn records(&self) -> usize {
        self.lock().jobs.len()
    }

    /// Ends job `id` with status `s`: a window joins the cache (the least recently used leave
    /// beyond the cap), a cancel or failure leaves the request's cache entry.
    fn finish(&self, id: u64, s: Status) {
        let mut t = self.lock();
        let Some(j) = t.jobs.get_mut(&id) else {
            return;
        };
        let key = j.key.clone();
        let added = match &s {
            Status::Done(r) => Some(r.bytes()),
            _ => None,
        };
        j.status = s;
        match added {
            Some(b) => {
                t.bytes += b;
                let evicted = evict(&mut t, self.cache_cap, id);
                self.counters.evicted.fetch_add(evicted, Ordering::SeqCst);
            }
            None => {
                if t.cache.get(&key) == Some(&id) {
                    t.cache.remove(&key);
                }
            }
        }
    }
}

/// The name of a status in the API.
pub fn status_name(s: &Status) -> &'static str {
    match s {
        Status::Queued => "queued",
        Status::Running => "running",
        Status::Done(_) => "done",
        Status::Cancelled(_) => "cancelled",
        Status::Failed(_) => "failed",
        Status::Evicted => "evicted",
    }
}

/// Drops the least recently used windows (never `keep`, the one just finished) until the
/// cache holds at most `cap` bytes; how many were dropped.
fn evict(t: &mut Table, cap: usize, keep: u64) -> usize {
    let mut n = 0;
    while t.bytes > cap {
        let lru = t
            .jobs
            .iter()
            .filter(|(id, j)| **id != keep && matches!(j.status, Status::Done(_)))
            .min_by_key(|(_, j)| j.used)
            .map(|(id, _)| *id);
        let Some(id) = lru else { break };
        let j = t.jobs.get_mut(&id).expect("the job found");
        if let Status::Done(r) = &j.status {
            t.bytes -= r.bytes();
        }
        j.status = Status::Evicted;
        let key = j.key.clone();
        if t.cache.get(&key) == Some(&id) {
            t.cache.remove(&key);
        }
        n += 1;
    }
    n
}

/// Forgets the oldest jobs that are not under way beyond [`MAX_RECORDS`] (a window forgotten
/// leaves the cache too).
fn forget_oldest(t: &mut Table) {
    if t.jobs.len() <= MAX_RECORDS {
        return;
    }
    let mut ended: Vec<u64> = t
        .jobs
        .iter()
        .filter(|(_, j)| !j.active())
        .map(|(id, _)| *id)
        .collect();
    ended.sort_unstable();
    let excess = t.jobs.len() - MAX_RECORDS;
    for id in ended.into_iter().take(excess) {
        if let Some(j) = t.jobs.remove(&id) {
            if let Status::Done(r) = &j.status {
                t.bytes -= r.bytes();
            }
            if t.cache.get(&j.key) == Some(&id) {
                t.cache.remove(&j.key);
            }
        }
    }
}

/// The worker: takes the newest job queued, skips those cancelled, computes it.
fn worker(jobs: std::sync::Weak<Jobs>, rx: mpsc::Receiver<u64>, pool: rayon::ThreadPool) {
    while let Ok(mut id) = rx.recv() {
        std::thread::sleep(SETTLE);
        let Some(jobs) = jobs.upgrade() else { return };
        {
            let (m, cv) = &jobs.held;
            let mut held = m.lock().expect("hold lock");
            while *held > 0 {
                held = cv.wait(held).expect("hold lock");
            }
        }
        while let Ok(newer) = rx.try_recv() {
            id = newer;
        }
        let taken = {
            let mut t = jobs.lock();
            match t.jobs.get_mut(&id) {
                Some(j) if !j.cancel.load(Ordering::SeqCst) => {
                    j.status = Status::Running;
                    j.src
                        .take()
                        .map(|s| (s, j.cancel.clone(), j.done.clone(), j.phase.clone()))
                }
                _ => None,
            }
        };
        let Some(((src, w, file, axes), cancel, done, phase)) = taken else {
            continue;
        };
        jobs.counters.started.fetch_add(1, Ordering::SeqCst);
        let t0 = std::time::Instant::now();
        let on_phase = |p: Phase| phase.store(p as u8, Ordering::Relaxed);
        match compute(&src, &w, &pool, &cancel, &done, &on_phase) {
            Ok(Computed::Cancelled(p)) => jobs.finish(id, Status::Cancelled(p)),
            Ok(Computed::Done(rebuilt, outcome, strides, final_state)) => {
                let grid = Grid::of_window(&rebuilt, outcome, strides, &axes);
                let refined = Refined {
                    rebuilt: *rebuilt,
                    grid,
                    final_state,
                    file,
                    seconds: t0.elapsed().as_secs_f64(),
                };
                jobs.counters.completed.fetch_add(1, Ordering::SeqCst);
                jobs.finish(id, Status::Done(Arc::new(refined)));
            }
            Err(e) => jobs.finish(id, Status::Failed(e)),
        }
    }
}

/// What a window computes to: the run, outcome codes, strides, final states; or the phase a
/// cancel stopped it in.
pub enum Computed {
    Done(Box<Rebuilt>, Vec<u8>, Vec<u16>, Vec<f64>),
    Cancelled(Phase),
}

/// Window `w` of `src` labelled as `pdw-sweep basin` labels that box: the same plan, gaits and
/// attractor discovery ([`rebuild_with`]), the cells classified row chunk by row chunk and
/// relabelled by the attractors, on `pool`. `on_phase` is told each phase as it starts; a
/// `cancel` set is seen between phases and between row chunks, and inside a phase under way
/// (the gait search, the attractor discovery, a chunk of cells) at its next integration call:
/// every thread of `pool` watches it as a stop request ([`pdw::hybrid::interrupt::watch`]) for
/// the call, so the walks the server serves meanwhile on other threads go on.
pub fn compute(
    src: &BasinSource,
    w: &Window,
    pool: &rayon::ThreadPool,
    cancel: &Arc<AtomicBool>,
    done: &AtomicUsize,
    on_phase: &(dyn Fn(Phase) + Sync),
) -> Result<Computed, ApiError> {
    /// Unwatches the flag on every thread of the pool when the call ends, however it ends.
    struct Watching<'a>(&'a rayon::ThreadPool);
    impl Drop for Watching<'_> {
        fn drop(&mut self) {
            self.0.broadcast(|_| pdw::hybrid::interrupt::watch(None));
        }
    }
    pool.broadcast(|_| pdw::hybrid::interrupt::watch(Some(cancel.clone())));
    let _watching = Watching(pool);
    let phase = AtomicU8::new(Phase::Model as u8);
    let computed = compute_watched(src, w, pool, cancel, done, on_phase, &phase);
    // a phase stopped inside by the cancel ends in an error (an interrupted search) or in a
    // result that means nothing: either is the cancel's
    if cancel.load(Ordering::SeqCst) {
        return Ok(match computed {
            Ok(Computed::Cancelled(p)) => Computed::Cancelled(p),
            _ => Computed::Cancelled(Phase::of(phase.load(Ordering::SeqCst))),
        });
    }
    computed
}

#[allow(clippy::too_many_arguments)]
fn compute_watched(
    src: &BasinSource,
    w: &Window,
    pool: &rayon::ThreadPool,
    cancel: &AtomicBool,
    done: &AtomicUsize,
    on_phase: &(dyn Fn(Phase) + Sync),
    phase: &AtomicU8,
) -> Result<Computed, ApiError> {
    let go_on = |p: Phase| {
        if cancel.load(Ordering::SeqCst) {
            return false;
        }
        phase.store(p as u8, Ordering::SeqCst);
        on_phase(p);
        !cancel.load(Ordering::SeqCst)
    };
    let stopped = || Computed::Cancelled(Phase::of(phase.load(Ordering::SeqCst)));
    let Some(r) = pool.install(|| rebuild_with(src, w, pool, &go_on))? else {
        return Ok(stopped());
    };
    if !go_on(Phase::Cells) {
        return Ok(stopped());
    }
    let (nx, ny) = (r.plan.bx.nx, r.plan.bx.ny);
    let fall = Outcome::of_fall;
    let problem = r.set.problem(r.m.walker.as_ref(), &fall);
    let rows_per_call = (CELLS_PER_CALL / nx).max(1);
    let (mut outcome, mut strides, mut fin) = (Vec::new(), Vec::new(), Vec::new());
    let rows: Vec<usize> = (0..ny).collect();
    for chunk in rows.chunks(rows_per_call) {
        if cancel.load(Ordering::SeqCst) {
            return Ok(stopped());
        }
        let before = outcome.len();
        let res = classify_cells(
            &problem,
            &r.plan.row_cells(chunk),
            &r.plan.opts,
            pool,
            &|n| done.store(before + n, Ordering::Relaxed),
        );
        let mut res =
            res.map_err(|e| ApiError::internal(format!("classifying the window: {e}")))?;
        r.set.relabel(&mut res);
        outcome.extend(res.iter().map(|c| c.outcome));
        strides.extend(res.iter().map(|c| c.strides));
        fin.extend(res.iter().flat_map(|c| c.final_state.iter().copied()));
        done.store(outcome.len(), Ordering::Relaxed);
    }
    Ok(Computed::Done(Box::new(r), outcome, strides, fin))
}
