//! Batched lockstep integration over lanes, with lane refill from a queue of work items.
//!
//! **Lockstep.** All active lanes make one step attempt together: the stage inputs
//! `x₀ + h ⊙ Σ a_{qp} k_p` are column kernels over lanes (h is a column: every lane has its own
//! t, h and controller state), the flow is one [`HybridSystem::flow_batch`] call per mode and
//! stage, and the error norm is a column kernel. Then every lane, one after another, accepts or
//! rejects its attempt, locates events on an accepted step, and commits. A lane that stops
//! (guard, end time, failure) is handed to the [`LaneDriver`]: it applies a reset and continues
//! the same work item, or finishes it, in which case the lane is refilled with the next item of
//! the queue, so lanes stay busy until the queue is empty. A continued segment starts with the
//! step the controller proposed at the stop ([`Options::warm_restart`]), as the scalar
//! [`Integrator::resume`] does; an item's first segment never inherits anything from the lane.
//!
//! **Modes.** Lanes are kept grouped by mode: the rows of the batch are partitioned into
//! contiguous ranges, one per mode (plus a last range of idle lanes), and each stage calls
//! `flow_batch` once per non-empty range on a row-range view. A lane whose mode changes at an
//! event is moved to its new range by row swaps (an in-place bucket partition, O(lanes) per
//! lockstep iteration in which some lane changed mode), so no flow is ever evaluated in a mode a
//! lane is not in and no gather/scatter is needed per stage.
//!
//! **Reproducibility.** A lane's arithmetic is the scalar integrator's arithmetic (see the
//! `engine` module): a work item gives bit-for-bit the same output whichever lane runs it, with
//! whichever neighbours, for any lane count, chunk size or thread count, and the same as
//! [`run_scalar`] — provided the model's `flow_batch` agrees with its `flow` bit for bit, as the
//! trait requires.
//!
//! **Work queue.** The items of a run are one queue, claimed in blocks of consecutive indices.
//! [`run_batch`] is one batch that claims them all; [`run_batch_par`] runs one batch per thread
//! of the pool, all drawing blocks from the same queue, so a batch refills its lanes until the
//! whole queue is empty. (A batch per block of items, as before, left its lanes idle at the end
//! of every block while its longest item — a basin cell that walks — finished: 19 % of the
//! default 1000 × 1000 basin's time on two threads.) Which lane and batch run an item changes
//! nothing in its result (above).
//!
//! **Memory.** All buffers are allocated once per batch (sized `lanes × dim`); the lockstep
//! loop allocates nothing but room for the outputs of each block of items it claims (drivers
//! may allocate, in `start`/`on_stop`/`finish`).

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use faer::{MatMut, MatRef};
use rayon::prelude::*;

use crate::engine::{self, After, Ctl, LaneScratch, Store};
use crate::options::{Options, Stats, StopReason};
use crate::phases::{self, lap};
use crate::tableau::Tableau;
use crate::{HybridError, HybridSystem, Integrator, Scratch};

/// What a lane does after a stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Control {
    /// Integrate on in `mode` (the driver has written the post-reset state) until `t_end`. The
    /// segment continues the work item: with [`Options::warm_restart`] its first step is the
    /// one the controller proposed at the stop.
    Continue { mode: usize, t_end: f64 },
    /// The work item is done: [`LaneDriver::finish`] is called and the lane is refilled.
    Finish,
}

/// Per-work-item logic of a batched run: initial state, resets, and the result.
pub trait LaneDriver<S: HybridSystem + ?Sized>: Sync {
    type Item: Sync;
    type Output: Send;
    /// Per-lane bookkeeping owned by the driver (reset to `Default` for every item).
    type Lane: Send + Default;
    /// Set up a lane for `item`: write the initial state into x; return (mode, t_end). t starts at 0.
    fn start(
        &self,
        sys: &S,
        item: &Self::Item,
        lane: &mut Self::Lane,
        x: &mut [f64],
    ) -> (usize, f64);
    /// Called when the lane stops (`ws`: the lane's model scratch, for resets). The driver may rewrite x (apply a reset) and return
    /// Control::Continue, or return Control::Finish after which `finish` is called.
    #[allow(clippy::too_many_arguments)]
    fn on_stop(
        &self,
        sys: &S,
        ws: &mut Scratch,
        item: &Self::Item,
        lane: &mut Self::Lane,
        stop: StopReason,
        mode: usize,
        t: f64,
        x: &mut [f64],
    ) -> Control;
    /// Produce the item's result from the final lane state.
    fn finish(
        &self,
        sys: &S,
        item: &Self::Item,
        lane: Self::Lane,
        t: f64,
        x: &[f64],
    ) -> Self::Output;
}

/// Options of a batched run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BatchOptions {
    /// Lanes stepped in lockstep (the batch never uses more lanes than there are items).
    pub lanes: usize,
    pub integrator: Options,
}

impl BatchOptions {
    /// Reject invalid options.
    pub fn validate(&self) -> Result<(), HybridError> {
        if self.lanes == 0 {
            return Err(HybridError::NoLanes { lanes: 0 });
        }
        self.integrator.validate()
    }
}

fn check_mode<S: HybridSystem + ?Sized>(sys: &S, mode: usize) -> Result<(), HybridError> {
    let n_modes = sys.n_modes();
    if mode < n_modes {
        Ok(())
    } else {
        Err(HybridError::ModeOutOfRange { mode, n_modes })
    }
}

/// Run one work item through the scalar [`Integrator`] (the reference path of [`run_batch`]).
pub fn run_scalar<S, D>(
    sys: &S,
    driver: &D,
    item: &D::Item,
    opts: &Options,
) -> Result<D::Output, HybridError>
where
    S: HybridSystem + ?Sized,
    D: LaneDriver<S>,
{
    let mut integ = Integrator::new(sys.dim(), *opts)?;
    run_scalar_with(&mut integ, sys, driver, item)
}

/// [`run_scalar`] with a caller-owned integrator (no allocation but the state vector).
pub fn run_scalar_with<S, D>(
    integ: &mut Integrator,
    sys: &S,
    driver: &D,
    item: &D::Item,
) -> Result<D::Output, HybridError>
where
    S: HybridSystem + ?Sized,
    D: LaneDriver<S>,
{
    let d = integ.dim();
    if sys.dim() != d {
        return Err(HybridError::DimensionMismatch {
            expected: d,
            got: sys.dim(),
        });
    }
    let mut lane = D::Lane::default();
    let mut x = vec![0.0; d];
    let (mut mode, mut t_end) = driver.start(sys, item, &mut lane, &mut x);
    let mut t = 0.0;
    let mut resume = false;
    loop {
        check_mode(sys, mode)?;
        if crate::interrupt::requested() {
            return Err(HybridError::Interrupted);
        }
        let stop = if resume {
            integ.resume(sys, mode, &mut t, &mut x, t_end)
        } else {
            integ.integrate(sys, mode, &mut t, &mut x, t_end)
        };
        if crate::interrupt::requested() {
            return Err(HybridError::Interrupted);
        }
        resume = true;
        match driver.on_stop(sys, integ.scratch(), item, &mut lane, stop, mode, t, &mut x) {
            Control::Continue { mode: m, t_end: te } => {
                mode = m;
                t_end = te;
            }
            Control::Finish => return Ok(driver.finish(sys, item, lane, t, &x)),
        }
    }
}

/// Serial lockstep batch over all items with lane refill; outputs in item order.
pub fn run_batch<S, D>(
    sys: &S,
    driver: &D,
    items: &[D::Item],
    opts: &BatchOptions,
) -> Result<Vec<D::Output>, HybridError>
where
    S: HybridSystem + ?Sized,
    D: LaneDriver<S>,
{
    run_batch_counted(sys, driver, items, opts).map(|(out, _)| out)
}

/// [`run_batch`], also returning the work counters summed over all lanes.
pub fn run_batch_counted<S, D>(
    sys: &S,
    driver: &D,
    items: &[D::Item],
    opts: &BatchOptions,
) -> Result<(Vec<D::Output>, Stats), HybridError>
where
    S: HybridSystem + ?Sized,
    D: LaneDriver<S>,
{
    opts.validate()?;
    let d = sys.dim();
    if d == 0 {
        return Err(HybridError::ZeroDimension { dim: 0 });
    }
    if items.is_empty() {
        return Ok((Vec::new(), Stats::default()));
    }
    let queue = Queue::new(items.len(), items.len());
    let mut b = Batch::new(sys, driver, items, &queue, opts, &|_| {});
    b.run()?;
    let stats = b.stats;
    Ok((in_item_order(items.len(), vec![b.outputs]), stats))
}

/// Outputs tagged with their item index, from any number of workers, in item order. Every
/// item is finished before a worker's loop ends: a lane only goes idle when the queue is empty,
/// and the loop runs until no lane is active.
fn in_item_order<O>(n: usize, parts: Vec<Vec<(usize, O)>>) -> Vec<O> {
    let mut out: Vec<Option<O>> = (0..n).map(|_| None).collect();
    for (i, o) in parts.into_iter().flatten() {
        out[i] = Some(o);
    }
    out.into_iter()
        .map(|o| o.expect("every item is finished"))
        .collect()
}

/// The shared work queue of a run: items are claimed in blocks of `block` consecutive indices.
struct Queue {
    next: AtomicUsize,
    len: usize,
    block: usize,
    /// Items finished and reported to the progress callback.
    done: AtomicUsize,
    /// A worker failed: the others stop claiming.
    abort: AtomicBool,
}

impl Queue {
    fn new(len: usize, block: usize) -> Self {
        Self {
            next: AtomicUsize::new(0),
            len,
            block: block.max(1),
            done: AtomicUsize::new(0),
            abort: AtomicBool::new(false),
        }
    }

    /// The next block of item indices (empty when the queue is exhausted or aborted).
    fn claim(&self) -> std::ops::Range<usize> {
        if self.abort.load(Ordering::Relaxed) {
            return 0..0;
        }
        let a = self
            .next
            .fetch_add(self.block, Ordering::Relaxed)
            .min(self.len);
        a..(a + self.block).min(self.len)
    }
}

/// Parallel: one lockstep batch per thread of the given rayon pool, all drawing items from one
/// queue in blocks of `chunk` consecutive items, so that a batch refills its lanes until the
/// whole queue is empty and no lane waits at the end of a block for the longest item in it.
/// Fewer items than four blocks per thread are claimed in smaller blocks (a quarter of each
/// thread's share): a call of fewer than `chunk` items — a slow model's basin rows, which the
/// front ends hand over a fraction of a second at a time — would otherwise be one block, and
/// every thread but one would wait. `progress(n_done_items)` is called each
/// time a batch has finished `chunk` more items, and once at its end. Results in item order,
/// identical for any thread count, lane count and chunk size. If a batch fails, the others stop
/// claiming items and the first failed batch's error (in pool order) is returned.
pub fn run_batch_par<S, D>(
    sys: &S,
    driver: &D,
    items: &[D::Item],
    opts: &BatchOptions,
    pool: &rayon::ThreadPool,
    chunk: usize,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Vec<D::Output>, HybridError>
where
    S: HybridSystem + ?Sized,
    D: LaneDriver<S>,
{
    if chunk == 0 {
        return Err(HybridError::ZeroChunk { chunk });
    }
    opts.validate()?;
    if sys.dim() == 0 {
        return Err(HybridError::ZeroDimension { dim: 0 });
    }
    if items.is_empty() {
        return Ok(Vec::new());
    }
    let threads = pool.current_num_threads().max(1);
    let block = chunk.min(items.len().div_ceil(4 * threads)).max(1);
    let queue = Queue::new(items.len(), block);
    let workers = threads.min(items.len().div_ceil(block));
    type Part<O> = Result<Vec<(usize, O)>, HybridError>;
    let parts: Vec<Part<D::Output>> = pool.install(|| {
        (0..workers)
            .into_par_iter()
            .with_max_len(1)
            .map(|_| {
                let mut b = Batch::new(sys, driver, items, &queue, opts, progress);
                let r = b.run();
                b.flush_progress();
                if r.is_err() {
                    queue.abort.store(true, Ordering::Relaxed);
                }
                r.map(|()| b.outputs)
            })
            .collect()
    });
    let parts = parts.into_iter().collect::<Result<Vec<_>, _>>()?;
    Ok(in_item_order(items.len(), parts))
}

/// State of one [`run_batch`] call.
struct Batch<'a, S: HybridSystem + ?Sized, D: LaneDriver<S>> {
    sys: &'a S,
    driver: &'a D,
    items: &'a [D::Item],
    opts: Options,
    tab: &'static Tableau,
    n_modes: usize,
    st: Store,
    sc: LaneScratch,
    /// `(lanes)` driver-facing state vector of the lane being handled.
    xd: Vec<f64>,
    /// Per-row controller state.
    ctl: Vec<Ctl>,
    /// Per-row driver bookkeeping.
    lane: Vec<D::Lane>,
    /// Per-row index of the work item.
    item_of: Vec<usize>,
    /// Per-row target range: the lane's mode, or `n_modes` for an idle lane.
    target: Vec<usize>,
    /// Row ranges: rows `range[m]..range[m+1]` are in mode m; the last range is idle.
    range: Vec<usize>,
    /// Scratch of the partition (`n_modes + 1`).
    next: Vec<usize>,
    dirty: bool,
    /// The run's shared queue and the block of it this batch has claimed.
    queue: &'a Queue,
    claimed: std::ops::Range<usize>,
    /// The queue returned an empty block: no more claims (each would be an atomic operation on
    /// the queue's shared cache line, once per lane left idle at the end of the run).
    drained: bool,
    /// Finished items, tagged with their index.
    outputs: Vec<(usize, D::Output)>,
    /// Items finished since the last progress report.
    unreported: usize,
    progress: &'a (dyn Fn(usize) + Sync),
    stats: Stats,
}

impl<'a, S: HybridSystem + ?Sized, D: LaneDriver<S>> Batch<'a, S, D> {
    fn new(
        sys: &'a S,
        driver: &'a D,
        items: &'a [D::Item],
        queue: &'a Queue,
        opts: &BatchOptions,
        progress: &'a (dyn Fn(usize) + Sync),
    ) -> Self {
        let d = sys.dim();
        let n_modes = sys.n_modes();
        let ng = (0..n_modes).map(|m| sys.guards(m).len()).max().unwrap_or(0);
        let nl = opts.lanes.min(items.len());
        let tab = engine::tableau_for(&opts.integrator);
        let mut st = Store::new(d, nl, ng, tab);
        st.err_dim = sys.error_dim().clamp(1, d);
        Self {
            sys,
            driver,
            items,
            opts: opts.integrator,
            tab,
            n_modes,
            st,
            sc: LaneScratch::new(d, ng),
            xd: vec![0.0; d],
            ctl: vec![Ctl::default(); nl],
            lane: (0..nl).map(|_| D::Lane::default()).collect(),
            item_of: vec![usize::MAX; nl],
            target: vec![n_modes; nl],
            range: vec![0; n_modes + 2],
            next: vec![0; n_modes + 1],
            dirty: true,
            queue,
            claimed: 0..0,
            drained: false,
            outputs: Vec::new(),
            unreported: 0,
            progress,
            stats: Stats::default(),
        }
    }

    /// The lockstep loop, compiled per instruction set (pdw-simd): the column kernels are
    /// inlined into each copy; every copy gives the same bits.
    fn run(&mut self) -> Result<(), HybridError> {
        pdw_simd::dispatch(
            #[inline(always)]
            || self.run_lockstep(),
        )
    }

    /// The lockstep loop: step sizes, stages, error norms, guards at x₁ as column passes over the
    /// active lanes, then the per-lane pass (accept or reject, events, the driver) and the
    /// commits left to columns, until no lane is active.
    #[inline(always)]
    fn run_lockstep(&mut self) -> Result<(), HybridError> {
        // Phase clock (`phases`; no code without the `phase-timing` feature).
        let mut tt = phases::now();
        let nl = self.st.lanes;
        for l in 0..nl {
            if let Some(r) = self.assign(l)? {
                self.handle_stop(l, r)?;
            }
        }
        self.partition();
        lap(phases::DRIVER, &mut tt);
        loop {
            if crate::interrupt::requested() {
                return Err(HybridError::Interrupted);
            }
            self.step_sizes()?;
            if self.dirty {
                self.partition();
            }
            lap(phases::STEP_SIZES, &mut tt);
            let n_active = self.range[self.n_modes];
            if n_active == 0 {
                break;
            }
            self.stages(n_active);
            lap(phases::STAGES, &mut tt);
            engine::error_norm(
                &mut self.st,
                self.opts.method,
                self.tab,
                &self.opts,
                n_active,
            );
            lap(phases::ERROR_NORM, &mut tt);
            self.guards_at_end();
            lap(phases::GUARDS, &mut tt);
            // Per-lane accept/reject, events, commit; stopped lanes go to the driver.
            for l in 0..n_active {
                let r = engine::after_attempt::<S, true>(
                    self.sys,
                    self.opts.method,
                    self.tab,
                    &self.opts,
                    &mut self.st,
                    l,
                    &mut self.ctl[l],
                    &mut self.sc,
                );
                if let After::Stop(r) = r {
                    lap(phases::PASS, &mut tt);
                    self.handle_stop(l, r)?;
                    lap(phases::DRIVER, &mut tt);
                }
            }
            // The commits the per-lane pass left to columns (rows keep their places until the
            // next partition; a lane that stopped and restarted above is not marked).
            for m in 0..self.n_modes {
                let (a, b) = (self.range[m], self.range[m + 1]);
                if b > a {
                    engine::commit_columns(&mut self.st, self.tab, a, b, self.sys.guards(m).len());
                }
            }
            lap(phases::PASS, &mut tt);
        }
        phases::flush();
        for c in &self.ctl {
            self.stats += c.stats;
        }
        Ok(())
    }

    /// Next step size of every active lane into `st.h` (0 for an idle lane); lanes that cannot
    /// step are stopped here and handed to the driver.
    #[inline(always)]
    fn step_sizes(&mut self) -> Result<(), HybridError> {
        let n_active = self.range[self.n_modes];
        for l in 0..n_active {
            loop {
                if self.target[l] == self.n_modes {
                    self.st.h[l] = 0.0;
                    break;
                }
                match engine::prepare(&self.opts, &mut self.ctl[l]) {
                    Ok(h) => {
                        self.st.h[l] = h;
                        break;
                    }
                    Err(r) => self.handle_stop(l, r)?,
                }
            }
        }
        Ok(())
    }

    /// The stages of one attempt of the first `n_active` lanes: column kernels over the lanes
    /// for the stage inputs, one `flow_batch` per mode range and stage.
    #[inline(always)]
    fn stages(&mut self, n_active: usize) {
        let (stride, d, blk) = (self.st.stride, self.st.dim, self.st.blk());
        let n_stages = self.tab.n_stages;
        for q in 1..n_stages {
            engine::stage_input(&mut self.st, self.tab, n_active, q);
            let st = &mut self.st;
            let input: &[f64] = if q + 1 == n_stages { &st.xn } else { &st.y };
            let kq = &mut st.k[q * blk..(q + 1) * blk];
            for m in 0..self.n_modes {
                let (a, b) = (self.range[m], self.range[m + 1]);
                if b > a {
                    let xv =
                        MatRef::from_column_major_slice_with_stride(&input[a..], b - a, d, stride);
                    let kv = MatMut::from_column_major_slice_with_stride_mut(
                        &mut kq[a..],
                        b - a,
                        d,
                        stride,
                    );
                    self.sys.flow_batch(&mut self.sc.ev.model, m, xv, kv);
                }
            }
        }
    }

    /// Guard values and rates at x₁, one call per mode range, then the column test of which
    /// lanes may see a crossing inside the step (`engine::mark_near`).
    #[inline(always)]
    fn guards_at_end(&mut self) {
        let (stride, d, blk) = (self.st.stride, self.st.dim, self.st.blk());
        let last = self.tab.n_stages - 1;
        for m in 0..self.n_modes {
            let (a, b) = (self.range[m], self.range[m + 1]);
            let ng = self.sys.guards(m).len();
            if b > a && ng > 0 {
                let Store { xn, k, g1, r1, .. } = &mut self.st;
                fn view(v: &[f64], a: usize, n: usize, d: usize, s: usize) -> MatRef<'_, f64> {
                    MatRef::from_column_major_slice_with_stride(&v[a..], n, d, s)
                }
                let gv = MatMut::from_column_major_slice_with_stride_mut(
                    &mut g1[a..],
                    b - a,
                    ng,
                    stride,
                );
                let rv = MatMut::from_column_major_slice_with_stride_mut(
                    &mut r1[a..],
                    b - a,
                    ng,
                    stride,
                );
                self.sys.guards_with_rates_batch(
                    &mut self.sc.ev.model,
                    m,
                    view(xn, a, b - a, d, stride),
                    view(&k[last * blk..(last + 1) * blk], a, b - a, d, stride),
                    gv,
                    rv,
                );
                engine::mark_near(&mut self.st, self.sys.guards(m), a, b);
            }
        }
    }

    /// Put the next item of the queue into lane `l` and start its first segment; `Ok(None)` if
    /// the queue is empty (the lane becomes idle) or the segment started.
    fn assign(&mut self, l: usize) -> Result<Option<StopReason>, HybridError> {
        if self.claimed.is_empty() && !self.drained {
            self.claimed = self.queue.claim();
            self.drained = self.claimed.is_empty();
            self.outputs.reserve(self.claimed.len());
        }
        let Some(i) = self.claimed.next() else {
            self.set_target(l, self.n_modes);
            return Ok(None);
        };
        self.item_of[l] = i;
        self.lane[l] = D::Lane::default();
        self.xd.fill(0.0);
        let (mode, t_end) =
            self.driver
                .start(self.sys, &self.items[i], &mut self.lane[l], &mut self.xd);
        self.begin(l, mode, 0.0, t_end, false)
    }

    /// Write the driver's state into lane `l` and start a segment there (`resume`: the segment
    /// continues the lane's work item, see [`engine::start_segment`]).
    fn begin(
        &mut self,
        l: usize,
        mode: usize,
        t: f64,
        t_end: f64,
        resume: bool,
    ) -> Result<Option<StopReason>, HybridError> {
        check_mode(self.sys, mode)?;
        let stride = self.st.stride;
        Store::scatter(&mut self.st.x, stride, l, &self.xd);
        self.set_target(l, mode);
        Ok(engine::start_segment(
            self.sys,
            &self.opts,
            self.tab,
            &mut self.st,
            l,
            &mut self.ctl[l],
            mode,
            t,
            t_end,
            resume,
            &mut self.sc,
        ))
    }

    /// Report the items finished since the last report to the progress callback.
    fn flush_progress(&mut self) {
        if self.unreported > 0 {
            let n = self.unreported;
            self.unreported = 0;
            (self.progress)(self.queue.done.fetch_add(n, Ordering::Relaxed) + n);
        }
    }

    fn set_target(&mut self, l: usize, b: usize) {
        if self.target[l] != b {
            self.target[l] = b;
            self.dirty = true;
        }
    }

    /// Hand a stopped lane to the driver until it is running again or idle.
    fn handle_stop(&mut self, l: usize, mut reason: StopReason) -> Result<(), HybridError> {
        let stride = self.st.stride;
        loop {
            Store::gather(&self.st.x, stride, l, &mut self.xd);
            let i = self.item_of[l];
            let (mode, t) = (self.ctl[l].mode, self.ctl[l].t);
            let item = &self.items[i];
            let ctrl = self.driver.on_stop(
                self.sys,
                &mut self.sc.ev.model,
                item,
                &mut self.lane[l],
                reason,
                mode,
                t,
                &mut self.xd,
            );
            let next = match ctrl {
                Control::Continue { mode, t_end } => self.begin(l, mode, t, t_end, true)?,
                Control::Finish => {
                    let lane = std::mem::take(&mut self.lane[l]);
                    let out = self.driver.finish(self.sys, item, lane, t, &self.xd);
                    self.outputs.push((i, out));
                    self.unreported += 1;
                    if self.unreported >= self.queue.block {
                        self.flush_progress();
                    }
                    self.assign(l)?
                }
            };
            match next {
                None => return Ok(()),
                Some(r) => reason = r,
            }
        }
    }

    /// Regroup rows by target range (in-place bucket partition by row swaps).
    fn partition(&mut self) {
        let nb = self.n_modes + 1;
        self.range.fill(0);
        for &t in &self.target {
            self.range[t + 1] += 1;
        }
        for b in 0..nb {
            self.range[b + 1] += self.range[b];
        }
        self.next.copy_from_slice(&self.range[..nb]);
        for b in 0..nb {
            while self.next[b] < self.range[b + 1] {
                let r = self.next[b];
                let tb = self.target[r];
                if tb == b {
                    self.next[b] += 1;
                } else {
                    let dst = self.next[tb];
                    self.swap_rows(r, dst);
                    self.next[tb] += 1;
                }
            }
        }
        self.dirty = false;
    }

    fn swap_rows(&mut self, a: usize, b: usize) {
        self.st.swap_lanes(a, b);
        self.st.h.swap(a, b);
        self.ctl.swap(a, b);
        self.lane.swap(a, b);
        self.item_of.swap(a, b);
        self.target.swap(a, b);
    }
}
