//! Model economy: the same question answered with the smallest adequate model and a larger one.
//!
//! (a) The simplest walker (Garcia 1998: massless legs, `m/M → 0`) against the compass gait
//! (Goswami 1998) with the leg mass at the foot (`a = 0`, `b = l`) and a small mass ratio
//! `μ = m / m_H`, both at γ = 0.009 rad. The compass fixed point is converted to Garcia's scaling
//! (angles unchanged, rates divided by `√(g/l)`, period multiplied by it); Garcia's walker is the
//! `μ → 0` limit, so the difference should shrink like `μ`. Cost per stride of each model:
//! wall time and right-hand-side evaluations (`Integrator::stats`).
//!
//! (b) The seed walker's exact knee lock (pseudo joints, seed §3.4; impulsive heel strike)
//! against the thesis' PI latch and compliant ground (`PiLatchWalker`, seed ch. 4) at
//! increasing gains, over one step of the exact model's locked-knee gait at γ = 0.05: work of
//! DOP853 (accepted / rejected steps, wall time), the largest RK4 step that still completes the
//! step, and the error of the knee angles and the swing foot against the exact model. A latch
//! of stiffness `K` on an inertia `I` adds a mode `ω = √(K/I)`: an explicit method is stable only
//! for `h ω ≲ c` (HNW II, stability regions), so its step count grows like `√K`.

use anyhow::Context;
use pdw_experiments::seed5_pi::{PiGains, PiLatchWalker, COMPLIANT_DOUBLE, COMPLIANT_SINGLE};
use pdw_experiments::{
    command, fmt_multipliers, results_dir, sci, time_mean, time_once, write_text, Table,
};
use pdw_hybrid::{
    GuardKind, HybridSystem, Integrator, Options, Scratch, Section, Stats, StopReason,
};
use pdw_limit::{find_fixed_point, Multiplier, NewtonOptions, StrideMap};
use pdw_walkers::simplest::GarciaGait;
use pdw_walkers::ChainWalker;
use std::fmt::Write as _;

const GAMMA_A: f64 = 0.009;
const G: f64 = 9.81;

/// Distance from each multiplier of `small` to the nearest unused one of `big`; returns the
/// largest such distance and the multipliers of `big` left unmatched.
fn match_multipliers(small: &[Multiplier], big: &[Multiplier]) -> (f64, Vec<Multiplier>) {
    let mut used = vec![false; big.len()];
    let mut worst: f64 = 0.0;
    for x in small {
        let mut best = (f64::INFINITY, usize::MAX);
        for (j, y) in big.iter().enumerate() {
            let d = (x.re - y.re).hypot(x.im - y.im);
            if !used[j] && d < best.0 {
                best = (d, j);
            }
        }
        if best.1 < big.len() {
            used[best.1] = true;
        }
        worst = worst.max(best.0);
    }
    let rest = big
        .iter()
        .zip(&used)
        .filter(|(_, u)| !**u)
        .map(|(m, _)| *m)
        .collect();
    (worst, rest)
}

/// Wall time and work of one stride from `s` with `opts`.
fn stride_cost(map: &StrideMap<'_>, s: &[f64]) -> (f64, Stats) {
    let dim = map.system().dim();
    let mut integ = Integrator::new(dim, *map.options()).expect("valid options");
    let (_, t) = time_mean(0.3, || map.stride_with(&mut integ, s));
    integ.reset_stats();
    let _ = map.stride_with(&mut integ, s);
    (t, integ.stats())
}

fn part_a(md: &mut String, dir: &std::path::Path) -> anyhow::Result<()> {
    let no = NewtonOptions {
        tol: 1e-13,
        ..NewtonOptions::default()
    };
    let opts = Options::dop853(1e-13);
    let simp = pdw_walkers::build("simplest", &[("slope", GAMMA_A)])?;
    let smap = StrideMap::new(simp.as_ref(), opts)?;
    let sfp = find_fixed_point(&smap, &GarciaGait::LongPeriod.section_guess(GAMMA_A), &no)?;
    let (th, thd) = (sfp.section[0], sfp.section[1]);
    let cost_opts = Options::dop853(1e-10);
    let smap_c = StrideMap::new(simp.as_ref(), cost_opts)?;
    let (s_time, s_stats) = stride_cost(&smap_c, &sfp.section);
    eprintln!(
        "simplest: s* = {:?}, period {}, λ = {}",
        sfp.section,
        sfp.metrics.period,
        fmt_multipliers(&sfp.multipliers, 6)
    );

    let l = 1.0;
    let w = (G / l).sqrt();
    let mut t = Table::new(&[
        "model",
        "θ*",
        "θ̇*/√(g/l)",
        "period·√(g/l)",
        "multipliers",
        "|Δθ*|",
        "|Δθ̇*| (scaled)",
        "|Δperiod| (scaled)",
        "max |Δλ| (matched)",
        "extra multiplier",
        "µs / stride",
        "rhs evals / stride",
        "steps (acc/rej)",
    ]);
    t.row(vec![
        "simplest (Garcia)".into(),
        format!("{th:.10}"),
        format!("{thd:.10}"),
        format!("{:.8}", sfp.metrics.period),
        fmt_multipliers(&sfp.multipliers, 6),
        "—".into(),
        "—".into(),
        "—".into(),
        "—".into(),
        "—".into(),
        format!("{:.1}", s_time * 1e6),
        s_stats.rhs_evals.to_string(),
        format!("{}/{}", s_stats.accepted, s_stats.rejected),
    ]);
    let mut ser: Vec<(String, Vec<(f64, f64)>)> = vec![
        ("|Δθ*|".into(), vec![]),
        ("|Δθ̇*| (units √(g/l))".into(), vec![]),
        ("|Δperiod| (units √(l/g))".into(), vec![]),
        ("max |Δλ| (matched)".into(), vec![]),
    ];
    let guess = vec![th, thd * w, -(1.0 - (2.0 * th).cos()) * thd * w];
    let mut last_ratio = Vec::new();
    let mut found: Vec<(f64, Vec<f64>)> = Vec::new();
    for mu in [1e-4, 1e-3, 1e-2, 3e-2, 1e-1] {
        let c = pdw_walkers::build(
            "compass",
            &[
                ("slope", GAMMA_A),
                ("leg_mass", mu),
                ("hip_mass", 1.0),
                ("a", 0.0),
                ("b", l),
                ("gravity", G),
                ("max_stride_time", 20.0),
            ],
        )?;
        let cmap = StrideMap::new(c.as_ref(), opts)?;
        // The differences grow linearly in μ: extrapolate the guess from the last two points.
        let g: Vec<f64> = match found.as_slice() {
            [.., (m0, s0), (m1, s1)] => s0
                .iter()
                .zip(s1)
                .map(|(a, b)| b + (b - a) * (mu - m1) / (m1 - m0))
                .collect(),
            [.., (_, s1)] => s1.clone(),
            [] => guess.clone(),
        };
        let cfp = find_fixed_point(&cmap, &g, &no).with_context(|| format!("μ = {mu}"))?;
        found.push((mu, cfp.section.clone()));
        let (ct, ctd, cper) = (cfp.section[0], cfp.section[1] / w, cfp.metrics.period * w);
        let (dl, rest) = match_multipliers(&sfp.multipliers, &cfp.multipliers);
        let d = [
            (ct - th).abs(),
            (ctd - thd).abs(),
            (cper - sfp.metrics.period).abs(),
            dl,
        ];
        for (s, v) in ser.iter_mut().zip(d) {
            s.1.push((mu, v));
        }
        last_ratio.push((mu, d));
        let cmap_c = StrideMap::new(c.as_ref(), cost_opts)?;
        let (c_time, c_stats) = stride_cost(&cmap_c, &cfp.section);
        eprintln!(
            "compass μ = {mu}: s* = {:?}, λ = {}, Δ = {d:?}, {:.1} µs",
            cfp.section,
            fmt_multipliers(&cfp.multipliers, 6),
            c_time * 1e6
        );
        t.row(vec![
            format!("compass, m/m_H = {mu:.0e}"),
            format!("{ct:.10}"),
            format!("{ctd:.10}"),
            format!("{cper:.8}"),
            fmt_multipliers(&cfp.multipliers, 6),
            sci(d[0]),
            sci(d[1]),
            sci(d[2]),
            sci(d[3]),
            rest.iter()
                .map(|m| format!("{:.2e}{:+.1e}i", m.re, m.im))
                .collect::<Vec<_>>()
                .join(", "),
            format!("{:.1}", c_time * 1e6),
            c_stats.rhs_evals.to_string(),
            format!("{}/{}", c_stats.accepted, c_stats.rejected),
        ]);
    }
    // Reference line ∝ μ through the first |Δθ̇*| point.
    let k = last_ratio[0].1[1] / last_ratio[0].0;
    ser.push((
        "∝ μ (reference slope)".into(),
        last_ratio.iter().map(|(m, _)| (*m, k * m)).collect(),
    ));
    pdw_store::plot_lines(
        dir.join("simplest_vs_compass.png"),
        "Compass gait (leg mass at the foot) minus simplest walker, γ = 0.009",
        "mass ratio μ = m / m_H",
        "difference in Garcia's scaling",
        &ser,
        true,
        true,
    )?;
    let slope_of = |i: usize| {
        let (a, b) = (last_ratio[0], last_ratio[last_ratio.len() - 1]);
        (b.1[i] / a.1[i]).log10() / (b.0 / a.0).log10()
    };
    let _ = writeln!(
        md,
        "## (a) Simplest walker vs compass gait with a small leg mass (γ = {GAMMA_A})\n\n\
         Compass: leg mass at the foot (`a = 0`, `b = l = 1 m`), `m_H = 1 kg`, `g = {G}`; \
         simplest walker: Garcia's exact equations (time unit √(l/g)). Fixed points by Newton \
         to 1e-13 on DOP853 1e-13 maps; compass rates divided by √(g/l) and its period \
         multiplied by √(g/l). Multipliers: each of the simplest walker's two matched to the \
         nearest compass multiplier; the compass has a third one (swing-leg rate after impact, \
         fixed by the impact in the μ → 0 limit), listed separately. Cost: one stride from the \
         fixed point with DOP853 at 1e-10, mean wall time of repeated strides (one thread).\n\n\
         {}\nLog-log slopes of the differences between μ = 1e-1 and 1e-4: θ* {:.3}, θ̇* {:.3}, \
         period {:.3}, multipliers {:.3}.\n\n![simplest vs compass](simplest_vs_compass.png)\n",
        t.markdown(),
        slope_of(0),
        slope_of(1),
        slope_of(2),
        slope_of(3),
    );
    Ok(())
}

/// One step of the compliant model: single support to touchdown, then double support to the
/// switch (or `ds_budget` seconds).
#[derive(Clone, Debug, Default)]
struct CompliantStep {
    ok: bool,
    why: String,
    t_touchdown: f64,
    foot_touchdown: [f64; 2],
    max_knee_single: f64,
    t_double: f64,
    max_penetration: f64,
    max_knee_double: f64,
    /// Section coordinates `(q₁, q̇₁, q̇₃)` after the switch rule.
    post: [f64; 3],
    stats: Stats,
}

fn compliant_step(
    w: &PiLatchWalker,
    opts: Options,
    x0: &[f64; 13],
    ds_budget: f64,
) -> CompliantStep {
    let mut r = CompliantStep::default();
    let mut integ = match Integrator::new(13, opts) {
        Ok(i) => i,
        Err(e) => {
            r.why = e.to_string();
            return r;
        }
    };
    let mut x = *x0;
    let mut t = 0.0;
    let mut mk: f64 = 0.0;
    let stop = integ.integrate_observed(w, COMPLIANT_SINGLE, &mut t, &mut x, 5.0, &mut |_, z| {
        mk = mk.max(z[1].abs()).max(z[3].abs());
    });
    r.max_knee_single = mk;
    if stop != (StopReason::Guard { guard: 0 }) {
        r.why = format!("single support ended with {stop:?}");
        r.stats = integ.stats();
        return r;
    }
    r.t_touchdown = t;
    r.foot_touchdown = w.model().swing_foot(&x);
    let mut y = [0.0; 13];
    let mode = w.reset(&mut Scratch::new(), COMPLIANT_SINGLE, 0, &x, &mut y);
    debug_assert_eq!(mode, COMPLIANT_DOUBLE);
    let t0 = t;
    let (mut mk2, mut pen): (f64, f64) = (0.0, 0.0);
    let stop = integ.integrate_observed(
        w,
        COMPLIANT_DOUBLE,
        &mut t,
        &mut y,
        t0 + ds_budget,
        &mut |_, z| {
            mk2 = mk2.max(z[1].abs()).max(z[3].abs());
            pen = pen.max(-w.model().swing_foot(z)[1]);
        },
    );
    r.stats = integ.stats();
    r.t_double = t - t0;
    r.max_knee_double = mk2;
    r.max_penetration = pen;
    let finite = y.iter().all(|v| v.is_finite());
    match stop {
        StopReason::Guard { guard }
            if w.guards(COMPLIANT_DOUBLE)[guard].kind == GuardKind::Reset =>
        {
            r.ok = finite;
            r.why = "switch".into();
            let mut z = [0.0; 13];
            w.reset(&mut Scratch::new(), COMPLIANT_DOUBLE, guard, &y, &mut z);
            r.post = [z[0], z[4], z[6]];
        }
        StopReason::EndTime => {
            r.ok = finite;
            r.why = "no switch within the budget".into();
        }
        other => r.why = format!("double support ended with {other:?}"),
    }
    r
}

/// Does RK4 with step `h` complete the step close to the DOP853 result `reference`?
fn rk4_ok(w: &PiLatchWalker, h: f64, x0: &[f64; 13], reference: &CompliantStep) -> bool {
    let r = compliant_step(w, Options::rk4(h), x0, reference.t_double.max(1e-3));
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-3 + 0.1 * b;
    r.ok && close(r.max_knee_single, reference.max_knee_single)
        && close(r.max_knee_double, reference.max_knee_double)
        && (r.t_touchdown - reference.t_touchdown).abs() < 1e-3
        && (r.foot_touchdown[0] - reference.foot_touchdown[0]).abs() < 1e-3
        && (r.max_penetration - reference.max_penetration).abs()
            < 0.1 * reference.max_penetration.max(1e-6)
}

/// Largest step in `[1e-7, 0.2]` for which `ok(h)` holds, by halving then log-bisection
/// (assumes `ok` is monotone in `h`); `None` if it fails down to 1e-7.
fn largest_step(ok: impl Fn(f64) -> bool) -> Option<f64> {
    let mut hi = 0.2;
    if ok(hi) {
        return Some(hi);
    }
    let mut lo = hi / 2.0;
    while !ok(lo) {
        hi = lo;
        lo /= 2.0;
        if lo < 1e-7 {
            return None;
        }
    }
    for _ in 0..6 {
        let mid = (lo * hi).sqrt();
        if ok(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(lo)
}

/// The exact model's step from the gait, measured: the reference (DOP853 1e-13), the work of
/// DOP853 at `tol` and the largest RK4 step that still reaches the heel strike.
struct ExactStep {
    /// Heel-strike time of the reference (s).
    t_ref: f64,
    /// Swing foot at the reference's heel strike (m).
    foot_ref: [f64; 2],
    /// Swing foot at heel strike with DOP853 at `tol` (m).
    foot_e: [f64; 2],
    /// DOP853's work at `tol`.
    st_e: Stats,
    /// DOP853's mean wall time at `tol` (s).
    wall_e: f64,
    /// Largest RK4 step within 1 ms / 1 mm of the reference.
    ex_rk4: Option<f64>,
}

/// The charts' series over the PI latch's gains: `(K_p, value)`.
#[derive(Default)]
struct LatchSeries {
    /// DOP853 step attempts.
    steps: Vec<(f64, f64)>,
    /// RK4 steps at the largest working step.
    rk4: Vec<(f64, f64)>,
    /// Largest foot penetration (m).
    pen: Vec<(f64, f64)>,
    /// Double-support duration (s).
    tds: Vec<(f64, f64)>,
}

/// Exact model: single support to heel strike from section state `s`; how it stopped, when,
/// where the swing foot is, and the integrator's work.
fn exact_ss(exact: &ChainWalker, s: &[f64], opts: Options) -> (StopReason, f64, [f64; 2], Stats) {
    let mut integ = Integrator::new(8, opts).expect("options");
    let mut x = [0.0; 8];
    exact.lift(s, &mut x);
    let mut t = 0.0;
    let stop = integ.integrate(exact, exact.locked_mode(), &mut t, &mut x, 5.0);
    (stop, t, exact.swing_foot(&x), integ.stats())
}

/// Part (b): the exact knee lock against the PI latch over one step of the seed walker's gait
/// at γ = 0.05, at increasing gains; writes the table, the two charts and section (b) of `md`.
fn part_b(md: &mut String, dir: &std::path::Path) -> anyhow::Result<()> {
    let exact = pdw_walkers::presets::seed5(&[])?;
    let emap = StrideMap::new(&exact, Options::dop853(1e-13))?;
    let fp = find_fixed_point(
        &emap,
        &pdw_walkers::Walker::gait_guesses(&exact)[0].section,
        &NewtonOptions::default(),
    )?;
    let s = &fp.section;
    eprintln!("seed5 locked-knee gait at 0.05: {s:?}");
    let tol = 1e-8;
    let e = exact_step(&exact, s, tol);
    let mut t = Table::new(&[
        "knee K_p (N m/rad)",
        "ground K_p (N/m)",
        "DOP853 accepted",
        "rejected",
        "rhs evals",
        "wall (ms)",
        "largest RK4 step (s)",
        "RK4 steps for the step",
        "RK4 at h = 1e-3",
        "max knee |q| single support (rad)",
        "touchdown time − exact (s)",
        "touchdown foot y − exact (m)",
        "double support (s)",
        "max foot penetration (m)",
        "max knee |q| double support (rad)",
        "post-switch (q₁, q̇₁, q̇₃) − s* (∞-norm)",
    ]);
    t.row(exact_row(&exact, s, &e));
    let mut series = LatchSeries::default();
    for kp in [1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9] {
        t.row(pi_latch_row(&exact, s, tol, &e, kp, &mut series)?);
    }
    plot_latch(dir, series, &e)?;
    let ExactStep {
        t_ref, foot_ref, ..
    } = e;
    let _ = writeln!(
        md,
        "## (b) Exact knee lock vs the thesis' PI latch and compliant ground\n\n\
         Seed walker (Table 3.1, both knees locked, γ = 0.05), one step from the exact model's \
         period-one gait s* = ({:.9}, {:.9}, {:.9}) (Newton to 1e-12 on DOP853 1e-14). Exact \
         model: pseudo-joint knees, single support to heel strike (t = {t_ref:.9} s, swing foot \
         at y = {:.9} m), impulsive double support. PI model (`PiLatchWalker`): latch torque \
         `τ_lock − K_p q − K_i ∫q` on both knees (K_i = K_p/100, no derivative term, as in the \
         thesis), single support to touchdown, then compliant ground `R = −K_p,g e − K_i,g ∫e` \
         (K_p,g = 10 K_p, K_i,g = K_p/10) until the old stance foot unloads (switch) or 0.5 s. \
         DOP853 at rtol = atol = {tol:.0e} for both. \"Largest RK4 step\": largest fixed step \
         (halving from 0.2 s, then 6 log-bisections) whose result stays within 1 ms / 1 mm of \
         the DOP853 result, knees within 0.01 rad, penetration within 10 %.\n\n{}\n\
         ![cost](latch_cost.png) ![error](latch_error.png)\n",
        s[0],
        s[1],
        s[2],
        foot_ref[0],
        t.markdown()
    );
    Ok(())
}

/// The exact model's step from `s`, measured (DOP853 1e-13 as the reference, DOP853 at `tol`,
/// the largest RK4 step).
fn exact_step(exact: &ChainWalker, s: &[f64], tol: f64) -> ExactStep {
    let (_, t_ref, foot_ref, _) = exact_ss(exact, s, Options::dop853(1e-13));
    let ((_, _, foot_e, st_e), _) = time_once(|| exact_ss(exact, s, Options::dop853(tol)));
    let (_, wall_e) = time_mean(0.3, || exact_ss(exact, s, Options::dop853(tol)));
    let ex_rk4 = largest_step(|h| {
        let (stop, t, f, _) = exact_ss(exact, s, Options::rk4(h));
        stop == StopReason::Guard { guard: 0 }
            && (t - t_ref).abs() < 1e-3
            && (f[0] - foot_ref[0]).abs() < 1e-3
    });
    eprintln!(
        "exact: t_hs {t_ref}, foot {foot_ref:?}, DOP853 {tol}: {st_e:?} {wall_e:.2e} s, RK4 h_max {ex_rk4:?}"
    );
    ExactStep {
        t_ref,
        foot_ref,
        foot_e,
        st_e,
        wall_e,
        ex_rk4,
    }
}

/// The table's row of the exact lock (its RK4 run at h = 1e-3 made here).
fn exact_row(exact: &ChainWalker, s: &[f64], e: &ExactStep) -> Vec<String> {
    let ExactStep {
        t_ref,
        foot_ref,
        foot_e,
        st_e,
        wall_e,
        ex_rk4,
    } = *e;
    vec![
        "exact lock".into(),
        "impulse".into(),
        st_e.accepted.to_string(),
        st_e.rejected.to_string(),
        st_e.rhs_evals.to_string(),
        format!("{:.3}", wall_e * 1e3),
        ex_rk4.map_or("none".into(), |h| {
            if h >= 0.2 {
                "≥ 0.2 (search cap)".into()
            } else {
                format!("{h:.3e}")
            }
        }),
        ex_rk4.map_or("—".into(), |h| format!("{:.0}", (t_ref / h).ceil())),
        {
            let (stop, tt, _, _) = exact_ss(exact, s, Options::rk4(1e-3));
            if stop == (StopReason::Guard { guard: 0 }) {
                format!("completes, Δt = {}", sci((tt - t_ref).abs()))
            } else {
                format!("{stop:?}")
            }
        },
        "0 (by construction)".into(),
        sci(0.0),
        sci(foot_e[0] - foot_ref[0]),
        "0 (impulse)".into(),
        "0".into(),
        "0".into(),
        "0 (s* is a fixed point)".into(),
    ]
}

/// One gain of the PI latch (knee K_p = `kp`, ground K_p = 10 `kp`): one step from the gait `s`
/// with DOP853 at `tol`, the largest RK4 step and RK4 at h = 1e-3, against the exact step `e`;
/// returns the table's row and adds to `series`.
fn pi_latch_row(
    exact: &ChainWalker,
    s: &[f64],
    tol: f64,
    e: &ExactStep,
    kp: f64,
    series: &mut LatchSeries,
) -> anyhow::Result<Vec<String>> {
    let (t_ref, foot_ref) = (e.t_ref, e.foot_ref);
    let mut x0 = [0.0; 13];
    let s10 = [s[0], 0.0, -2.0 * s[0], 0.0, s[1], 0.0, s[2], 0.0, 0.0, 0.0];
    let gains = PiGains {
        knee_kp: kp,
        knee_ki: kp / 100.0,
        knee_kd: 0.0,
        ground_kp: 10.0 * kp,
        ground_ki: kp / 10.0,
        ground_kd: 0.0,
    };
    let w = PiLatchWalker::new(exact.clone(), gains)?;
    w.lift(&s10, &mut x0);
    let ((r, wall), _) =
        time_once(|| time_once(|| compliant_step(&w, Options::dop853(tol), &x0, 0.5)));
    let h = if r.ok {
        largest_step(|h| rk4_ok(&w, h, &x0, &r))
    } else {
        None
    };
    let rk4_steps = h.map(|h| ((r.t_touchdown + r.t_double) / h).ceil());
    let fixed = compliant_step(&w, Options::rk4(1e-3), &x0, r.t_double.max(1e-3));
    let fixed_txt = if fixed.ok && rk4_ok(&w, 1e-3, &x0, &r) {
        "completes".to_string()
    } else if fixed.ok {
        format!(
            "wrong: knee {} rad, penetration {} m",
            sci(fixed.max_knee_single.max(fixed.max_knee_double)),
            sci(fixed.max_penetration)
        )
    } else {
        format!(
            "blows up: {} (knee reached {} rad)",
            fixed.why,
            sci(fixed.max_knee_single)
        )
    };
    eprintln!(
        "K = {kp:e}: ok {} ({}), {:?}, {wall:.3} s, RK4 h {h:?}, td {} foot {:?} pen {:e} Tds {} knee {:e}/{:e}; RK4 1e-3: {fixed_txt}",
        r.ok, r.why, r.stats, r.t_touchdown, r.foot_touchdown, r.max_penetration, r.t_double,
        r.max_knee_single, r.max_knee_double
    );
    let n = r.stats.accepted + r.stats.rejected;
    series.steps.push((kp, n as f64));
    if let Some(k) = rk4_steps {
        series.rk4.push((kp, k));
    }
    if r.ok {
        series.pen.push((kp, r.max_penetration));
        series.tds.push((kp, r.t_double));
    }
    Ok(vec![
        format!("{kp:.0e}"),
        format!("{:.0e}", 10.0 * kp),
        r.stats.accepted.to_string(),
        r.stats.rejected.to_string(),
        r.stats.rhs_evals.to_string(),
        format!("{:.2}", wall * 1e3),
        h.map_or("none ≥ 1e-7".into(), |h| format!("{h:.3e}")),
        rk4_steps.map_or("—".into(), |k| format!("{k:.0}")),
        fixed_txt,
        sci(r.max_knee_single),
        sci(r.t_touchdown - t_ref),
        sci(r.foot_touchdown[0] - foot_ref[0]),
        format!("{} ({})", sci(r.t_double), r.why),
        sci(r.max_penetration),
        sci(r.max_knee_double),
        if r.why == "switch" {
            sci(r
                .post
                .iter()
                .zip(s.iter())
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max))
        } else {
            "no switch".into()
        },
    ])
}

/// The two charts of part (b): integration work against the latch gain (with the exact lock's
/// and a √K reference) and the compliant ground's error.
fn plot_latch(dir: &std::path::Path, s: LatchSeries, e: &ExactStep) -> anyhow::Result<()> {
    let LatchSeries {
        steps: s_steps,
        rk4: s_rk4,
        pen: s_pen,
        tds: s_tds,
    } = s;
    let exact_steps = e.st_e.accepted + e.st_e.rejected;
    let exact_rk4 = e.ex_rk4.map(|h| (e.t_ref / h).ceil());
    // √K reference through the highest-gain DOP853 point.
    let (kl, nl) = *s_steps.last().context("no gains")?;
    let sqrt_ref: Vec<(f64, f64)> = s_steps
        .iter()
        .map(|(k, _)| (*k, nl * (k / kl).sqrt()))
        .collect();
    let mut series = vec![
        (
            "PI latch: DOP853 1e-8 step attempts".to_string(),
            s_steps.clone(),
        ),
        (
            "PI latch: RK4 steps at the largest working step".to_string(),
            s_rk4,
        ),
        ("∝ √K (reference)".to_string(), sqrt_ref),
        (
            "exact lock: DOP853 1e-8 step attempts".to_string(),
            s_steps
                .iter()
                .map(|(k, _)| (*k, exact_steps as f64))
                .collect(),
        ),
    ];
    if let Some(e) = exact_rk4 {
        series.push((
            "exact lock: RK4 steps at the largest working step".to_string(),
            s_steps.iter().map(|(k, _)| (*k, e)).collect(),
        ));
    }
    pdw_store::plot_lines(
        dir.join("latch_cost.png"),
        "Seed walker, one step at γ = 0.05: integration work vs PI-latch gain",
        "knee latch K_p (N m/rad); ground K_p = 10 K_p",
        "integrator steps for one step of the gait",
        &series,
        true,
        true,
    )?;
    pdw_store::plot_lines(
        dir.join("latch_error.png"),
        "Compliant ground: error against the impulsive (exact) heel strike",
        "knee latch K_p (N m/rad); ground K_p = 10 K_p",
        "m or s",
        &[
            ("max foot penetration (m)".to_string(), s_pen),
            ("double-support duration (s)".to_string(), s_tds),
        ],
        true,
        true,
    )?;
    Ok(())
}

fn main() -> anyhow::Result<()> {
    faer::set_global_parallelism(faer::Par::Seq);
    let dir = results_dir("economy")?;
    let mut md = String::new();
    let _ = writeln!(md, "# Model economy\n");
    let _ = writeln!(md, "Reproduce: `{}`.\n", command("economy"));
    part_a(&mut md, &dir)?;
    part_b(&mut md, &dir)?;
    write_text(&dir, "table.md", &md)?;
    Ok(())
}
