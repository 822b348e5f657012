//! A small, fixed workload for profilers (`valgrind --tool=callgrind`, `perf record`):
//!
//! - `profile basin N [THREADS] [LANES] [CHUNK] [cold]`: the simplest walker's basin at
//!   γ = 0.009 on an N × N grid over θ ∈ [0.15, 0.25], θ̇ ∈ [−0.25, −0.15], 100 strides, default
//!   engine options (or that many lanes per lockstep batch and cells per chunk; `cold`: every
//!   stride starts with the starting-step heuristic, `Options::warm_restart = false`;
//!   `profile basin-dyn …`: the same model behind `Box<dyn Walker>`, as the CLI);
//! - `profile stride N [TOL] [dopri5|dopri5-elementary|dop853] [general|register] [H0]`: N
//!   scalar strides of the simplest walker from its stable fixed point, one reused integrator
//!   (default DOP853 at 1e-10); `dopri5-elementary` is DOPRI5 with
//!   `Controller::Elementary`; `general` runs the integrator's general step loop instead of
//!   its register loop (same bits); `H0` starts every stride with that step instead of the
//!   starting-step heuristic;
//! - `profile batch N [TOL] [dopri5|dop853] [LANES] [THREADS CHUNK [REPEAT]]`: N strides from
//!   perturbed copies of the fixed point through the serial lockstep engine (default 64 lanes),
//!   or in blocks of CHUNK states on a pool of THREADS threads, REPEAT calls on the same states;
//!   built with `--features pdw-hybrid/phase-timing`, it also prints where the lockstep loop's
//!   time goes, phase by phase ([`pdw_hybrid::phases`]), as nanoseconds per lane-stride: each
//!   phase's share of the counted ticks times the wall-clock time per lane-stride (so does
//!   `profile basin`);
//! - `profile rhs N [SPREAD]`: N calls of the simplest walker's batched right-hand side on 256
//!   lanes around the fixed point (SPREAD: the half-width of θ's spread; 0.5 puts some angles
//!   beyond the trigonometric shortcut);
//! - `profile fixedpoint N`: N fixed points of the simplest walker to 1e-12 from Garcia's
//!   guess (DOP853 at 1e-14, the CLI's settings), with the cost of its parts: one stride and one
//!   variational stride at the same tolerance;
//! - `profile compass-stride N [TOL] [METHOD]`, `profile compass-batch N [TOL] [METHOD] [LANES]`:
//!   the same for the compass gait (Goswami preset, 3°) from its fixed point.
//!
//! Prints the work done, so that an instruction count can be turned into a per-stride cost, and
//! for a basin a checksum of every cell's outcome, stride count and final-state bits (two builds
//! with equal checksums computed the same basin bit for bit).

use std::time::Instant;

use pdw_hybrid::Section;
use pdw_hybrid::{Integrator, Options};
use pdw_limit::{
    classify_cells, find_fixed_point, grid_cells, linspace, BasinOptions, BasinProblem,
    NewtonOptions, Outcome, StrideMap,
};
use pdw_walkers::simplest::{GarciaGait, Simplest, SimplestParams};
use pdw_walkers::Walker;

const GAMMA: f64 = 0.009;

fn arg<T: std::str::FromStr>(args: &[String], i: usize, default: T) -> T {
    args.get(i).and_then(|s| s.parse().ok()).unwrap_or(default)
}

fn method(args: &[String], i: usize, tol: f64) -> Options {
    match args.get(i).map(String::as_str) {
        Some("dopri5") => Options::dopri5(tol),
        Some("dopri5-elementary") => Options {
            controller: pdw_hybrid::Controller::Elementary,
            ..Options::dopri5(tol)
        },
        _ => Options::dop853(tol),
    }
}

/// Where the batched runs since the last [`pdw_hybrid::phases::reset`] spent their time, as
/// nanoseconds per lane-stride (`per`: wall-clock nanoseconds per lane-stride of `n`); nothing
/// without the `phase-timing` feature.
fn print_phases(per: f64, n: usize) {
    use pdw_hybrid::phases;
    if !phases::ENABLED {
        return;
    }
    let p = phases::take();
    let total: u64 = p.ticks.iter().sum();
    if total == 0 {
        return;
    }
    println!("phase                                          ns/lane-stride   share");
    for (name, &t) in phases::NAMES.iter().zip(&p.ticks) {
        let share = t as f64 / total as f64;
        println!("{name:<46} {:>10.1} {:>9.1} %", share * per, 100.0 * share);
    }
    println!(
        "located steps per stride {:.3}, dense outputs per stride {:.3}",
        p.located as f64 / n as f64,
        p.dense as f64 / n as f64
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let sys = Simplest::new(SimplestParams {
        slope: GAMMA,
        ..SimplestParams::default()
    })
    .expect("valid parameters");
    let fp_map = StrideMap::new(&sys, Options::dop853(1e-14)).expect("valid options");
    let fp = find_fixed_point(
        &fp_map,
        &GarciaGait::LongPeriod.section_guess(GAMMA),
        &NewtonOptions::default(),
    )
    .expect("fixed point")
    .section;
    let what = args.first().map(String::as_str).unwrap_or("basin");
    let t0 = Instant::now();
    match what {
        "stride" => {
            let n: usize = arg(&args, 1, 2000);
            let mut opts = method(&args, 3, arg(&args, 2, 1e-10));
            opts.h_init = args.get(5).and_then(|s| s.parse().ok());
            let map = StrideMap::new(&sys, opts).expect("valid options");
            let mut integ = Integrator::new(4, opts).expect("valid options");
            let general = args.get(4).is_some_and(|a| a == "general");
            integ.set_register_loop(!general);
            let mut acc = 0.0;
            for _ in 0..n {
                acc += map.stride_with(&mut integ, &fp).expect("stride").period;
            }
            let s = integ.stats();
            println!(
                "{n} scalar strides ({:?}, {} loop): {:.3} µs/stride, mean period {:.6}, {} accepted, {} rejected, {} rhs, {} sampled",
                opts.method,
                if general { "general" } else { "register" },
                t0.elapsed().as_secs_f64() * 1e6 / n as f64,
                acc / n as f64,
                s.accepted,
                s.rejected,
                s.rhs_evals,
                s.sampled
            );
        }
        "fixedpoint" => {
            let n: usize = arg(&args, 1, 200);
            let guess = GarciaGait::LongPeriod.section_guess(GAMMA);
            let mut fp1 = None;
            for _ in 0..n {
                fp1 = Some(
                    find_fixed_point(&fp_map, &guess, &NewtonOptions::default())
                        .expect("fixed point"),
                );
            }
            let t_fp = t0.elapsed().as_secs_f64() * 1e3 / n as f64;
            let fp1 = fp1.expect("n >= 1");
            let t1 = Instant::now();
            for _ in 0..n {
                fp_map.stride(&guess).expect("stride");
            }
            let t_stride = t1.elapsed().as_secs_f64() * 1e6 / n as f64;
            let t2 = Instant::now();
            for _ in 0..n {
                pdw_limit::dp_variational(&fp_map, &guess).expect("variational stride");
            }
            let t_var = t2.elapsed().as_secs_f64() * 1e6 / n as f64;
            // Work of one stride and one variational stride from the guess.
            let work = |sys: &dyn pdw_hybrid::HybridSystem, z0: &[f64]| {
                let mut integ =
                    Integrator::new(sys.dim(), *fp_map.options()).expect("valid options");
                pdw_hybrid::run_scalar_with(&mut integ, sys, &fp_map.driver(), &z0.to_vec())
                    .expect("stride");
                let s = integ.stats();
                (s.accepted + s.rejected, s.rhs_evals)
            };
            let x0 = fp_map.lift(&guess);
            let (sm, sg) = sys.section_guard();
            let var = pdw_limit::Variational::new(&sys, 2).poincare_at(sm, sg);
            let mut z0 = x0.clone();
            z0.extend_from_slice(&pdw_limit::richardson_jacobian(
                |a, b| sys.lift(a, b),
                &guess,
                4,
            ));
            let (steps_s, evals_s) = work(&sys, &x0);
            let (steps_v, evals_v) = work(&var, &z0);
            println!(
                "{n} fixed points (DOP853 1e-14, tol 1e-12): {t_fp:.4} ms each, {} iterations, \
                 residual {:.2e}; one stride {t_stride:.2} µs ({steps_s} steps, {evals_s} \
                 evaluations), one variational stride {t_var:.2} µs ({steps_v} steps, {evals_v} \
                 evaluations)",
                fp1.iterations, fp1.residual
            );
        }
        "compass-stride" | "compass-batch" => {
            let n: usize = arg(&args, 1, 2000);
            let opts = method(&args, 3, arg(&args, 2, 1e-10));
            let lanes: usize = arg(&args, 4, 64);
            let sys = pdw_walkers::presets::compass(&[]).expect("valid parameters");
            let fp_map = StrideMap::new(&sys, Options::dop853(1e-14)).expect("valid options");
            let guess = sys.gait_guesses()[0].section.clone();
            let s0 = find_fixed_point(&fp_map, &guess, &NewtonOptions::default())
                .expect("fixed point")
                .section;
            let map = StrideMap::new(&sys, opts).expect("valid options");
            pdw_hybrid::phases::reset();
            let t0 = Instant::now();
            if what == "compass-stride" {
                let mut integ = Integrator::new(4, opts).expect("valid options");
                for _ in 0..n {
                    map.stride_with(&mut integ, &s0).expect("stride");
                }
            } else {
                let states = vec![s0.clone(); n];
                map.strides(&states, lanes).expect("strides");
            }
            let per = t0.elapsed().as_secs_f64() * 1e9 / n as f64;
            println!(
                "{n} compass strides ({what}, {:?}): {:.3} µs/stride",
                opts.method,
                per * 1e-3
            );
            print_phases(per, n);
        }
        "rhs" => {
            // `profile rhs N [SPREAD]`: N calls of the batched right-hand side on 256 lanes,
            // states θ = θ* + SPREAD·u, φ = 2θ with u uniform in [−1, 1] (SPREAD 0: all near
            // the gait; larger: some angles beyond the trigonometric shortcut).
            use pdw_hybrid::HybridSystem;
            let n: usize = arg(&args, 1, 200_000);
            let spread: f64 = arg(&args, 2, 0.0);
            let lanes = 256;
            let mut x = faer::Mat::<f64>::zeros(lanes, 4);
            for l in 0..lanes {
                let u = 2.0 * (l as f64 * 0.618_034).fract() - 1.0;
                let th = fp[0] + spread * u;
                x[(l, 0)] = th;
                x[(l, 1)] = fp[1];
                x[(l, 2)] = 2.0 * th;
                x[(l, 3)] = 0.1 * u;
            }
            let mut k = faer::Mat::<f64>::zeros(lanes, 4);
            let mut ws = pdw_hybrid::Scratch::default();
            let t0 = Instant::now();
            for _ in 0..n {
                sys.flow_batch(&mut ws, 0, x.as_ref(), k.as_mut());
                x[(0, 1)] += k[(0, 0)] * 1e-300;
            }
            println!(
                "{n} calls of flow_batch on {lanes} lanes (spread {spread}): {:.3} ns per lane",
                t0.elapsed().as_secs_f64() * 1e9 / (n * lanes) as f64
            );
        }
        "batch" => {
            let mut n: usize = arg(&args, 1, 8192);
            let opts = method(&args, 3, arg(&args, 2, 1e-10));
            let lanes: usize = arg(&args, 4, 64);
            let map = StrideMap::new(&sys, opts).expect("valid options");
            let states: Vec<Vec<f64>> = (0..n)
                .map(|i| {
                    let e = 1e-4 * ((i as f64 * 0.618_034).fract() - 0.5);
                    vec![fp[0] * (1.0 + e), fp[1] * (1.0 - e)]
                })
                .collect();
            pdw_hybrid::phases::reset();
            let t0 = Instant::now();
            let res = match args.get(5).and_then(|s| s.parse::<usize>().ok()) {
                Some(threads) => {
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .expect("thread pool");
                    let chunk: usize = arg(&args, 6, 256);
                    // REPEAT: the same states again that many times (as the engine experiment,
                    // which times repeated calls on 1024 states); the time is per lane-stride.
                    let repeat: usize = arg(&args, 7, 1);
                    for _ in 1..repeat {
                        map.strides_par(&states, lanes, &pool, chunk, &|_| {})
                            .expect("strides");
                    }
                    n *= repeat;
                    map.strides_par(&states, lanes, &pool, chunk, &|_| {})
                }
                None => map.strides(&states, lanes),
            }
            .expect("strides");
            let per = t0.elapsed().as_secs_f64() * 1e9 / n as f64;
            println!(
                "{n} batched strides ({:?}, {lanes} lanes): {:.3} µs/lane-stride, {} ok",
                opts.method,
                per * 1e-3,
                res.iter().filter(|s| s.outcome.is_ok()).count()
            );
            print_phases(per, n);
        }
        _ => {
            let n: usize = arg(&args, 1, 60);
            let threads: usize = arg(&args, 2, 1);
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool");
            // `basin-dyn`: the model behind `Box<dyn Walker>` from the registry (as the CLI).
            let boxed = pdw_walkers::build("simplest", &[("slope", GAMMA)]).expect("model");
            let fall = Outcome::of_fall;
            let problem = BasinProblem::new(&sys, fp.clone(), &fall);
            let problem_dyn = BasinProblem::new(&*boxed, fp.clone(), &fall);
            let cells = grid_cells(
                &fp,
                0,
                &linspace(0.15, 0.25, n),
                1,
                &linspace(-0.25, -0.15, n),
            );
            let mut opts = BasinOptions::default();
            opts.lanes = arg(&args, 3, opts.lanes);
            opts.chunk = arg(&args, 4, opts.chunk);
            opts.integrator.warm_restart = args.get(5).is_none_or(|a| a != "cold");
            pdw_hybrid::phases::reset();
            let res = if what == "basin-dyn" {
                classify_cells(&problem_dyn, &cells, &opts, &pool, &|_| {})
            } else {
                classify_cells(&problem, &cells, &opts, &pool, &|_| {})
            }
            .expect("basin");
            let secs = t0.elapsed().as_secs_f64();
            let strides: usize = res.iter().map(|c| usize::from(c.strides)).sum();
            println!(
                "{what} {n}x{n} on {threads} threads: {:.3} s, {:.0} cells/s, {strides} lane-strides, \
                 {:.0} lane-strides/s, {} gait cells",
                secs,
                cells.len() as f64 / secs,
                strides as f64 / secs,
                res.iter().filter(|c| c.outcome() == Outcome::Gait).count()
            );
            // FNV-1a over every cell's outcome, stride count and final-state bits: equal
            // checksums, the same basin bit for bit.
            let mut hash = 0xcbf2_9ce4_8422_2325u64;
            let mut eat = |v: u64| {
                for b in v.to_le_bytes() {
                    hash = (hash ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
                }
            };
            for c in &res {
                eat(u64::from(c.outcome));
                eat(u64::from(c.strides));
                c.final_state.iter().for_each(|v| eat(v.to_bits()));
            }
            println!("checksum {hash:016x}");
            print_phases(secs * 1e9 / strides as f64, strides);
        }
    }
}
