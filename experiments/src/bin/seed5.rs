//! The seed thesis' walker (Table 3.1: shanks 2 kg, thighs 3 kg, segments 2 m, no hip mass):
//! everything the engine can say about it — period-one gaits against the slope for both knee
//! variants (pseudo-arclength continuation), Floquet multipliers and stability, validity of each
//! gait along one stride (stance-foot normal force, friction needed, knee-lock torques; seed
//! §3.4: a locked knee's torque must push towards extension), the ground-reaction and knee-torque
//! profiles over one stride at γ = 0.05, an added hip mass as a search parameter, and the basin
//! of the stable gait.

use pdw_experiments::{command, fmt_multipliers, results_dir, sci, time_once, write_text, Table};
use pdw_hybrid::{GuardKind, Integrator, Options, Scratch, StopReason};
use pdw_limit::{
    basin_metrics, classify_cells, continue_branch, find_fixed_point, grid_cells, legend, linspace,
    BasinOptions, BasinProblem, Branch, ContinuationOptions, FixedPoint, NewtonOptions, Outcome,
    StrideMap,
};
use pdw_walkers::{Walker, WalkerError};
use std::fmt::Write as _;
use std::path::Path;

const G0: f64 = 0.05;

fn build(slope: f64, free: bool, hip: f64) -> Result<Box<dyn Walker>, WalkerError> {
    pdw_walkers::build(
        "seed5",
        &[
            ("slope", slope),
            ("free_swing_knee", if free { 1.0 } else { 0.0 }),
            ("hip_mass", hip),
        ],
    )
}

/// Constraint forces along one stride from section state `s`.
#[derive(Clone, Debug)]
struct Validity {
    min_normal: f64,
    max_friction: f64,
    min_knee: f64,
    flags: [bool; 3],
    /// `(t, normal, tangential, stance-knee torque, swing-knee torque or NaN)`.
    profile: Vec<[f64; 5]>,
}

/// The table cells of a stride's validity: least normal force, most friction needed, least
/// knee torque, and the flags ("—" and "stride failed" where the stride failed).
fn validity_cells(v: Option<&Validity>) -> [String; 4] {
    match v {
        Some(v) => [
            format!("{:.2}", v.min_normal),
            format!("{:.3}", v.max_friction),
            format!("{:.3}", v.min_knee),
            v.flag_text(),
        ],
        None => ["—".into(), "—".into(), "—".into(), "stride failed".into()],
    }
}

impl Validity {
    fn valid(&self) -> bool {
        !self.flags.iter().any(|f| *f)
    }
    fn flag_text(&self) -> String {
        let names = ["normal force < 0", "knee unlocks", "swing foot scuffs"];
        let v: Vec<&str> = names
            .iter()
            .zip(self.flags)
            .filter(|(_, f)| *f)
            .map(|(n, _)| *n)
            .collect();
        if v.is_empty() {
            "all clear".into()
        } else {
            v.join("; ")
        }
    }
}

/// Samples the constraint forces and validity flags at every accepted step of one stride from
/// `s` (DOP853 1e-10, steps at most `h_max`).
fn validity(w: &dyn Walker, s: &[f64], h_max: f64) -> Option<Validity> {
    let mut v = Validity {
        min_normal: f64::INFINITY,
        max_friction: 0.0,
        min_knee: f64::INFINITY,
        flags: [false; 3],
        profile: Vec::new(),
    };
    let opts = Options {
        h_max,
        ..Options::dop853(1e-10)
    };
    let mut integ = Integrator::new(w.dim(), opts).ok()?;
    let mut x = vec![0.0; w.dim()];
    w.lift(s, &mut x);
    let (mut t, mut mode) = (0.0, w.section_mode());
    let mut buf = vec![0.0; x.len()];
    for _ in 0..8 {
        let m0 = mode;
        let stop = integ.integrate_observed(w, mode, &mut t, &mut x, 20.0, &mut |tt, xs| {
            if let (Some(cf), Some(fl)) = (w.constraint_forces(m0, xs), w.step_flags(m0, xs)) {
                v.min_normal = v.min_normal.min(cf.normal);
                v.max_friction = v.max_friction.max(cf.friction_required);
                for k in cf.knee_torque.iter().flatten() {
                    v.min_knee = v.min_knee.min(*k);
                }
                v.flags[0] |= fl.normal_force_negative;
                v.flags[1] |= fl.knee_unlocks;
                v.flags[2] |= fl.swing_foot_scuffs;
                v.profile.push([
                    tt,
                    cf.normal,
                    cf.tangential,
                    cf.knee_torque[0].unwrap_or(f64::NAN),
                    cf.knee_torque[1].unwrap_or(f64::NAN),
                ]);
            }
        });
        match stop {
            StopReason::Guard { guard } if w.guards(mode)[guard].kind == GuardKind::Reset => {
                if (mode, guard) == w.section_guard() {
                    return Some(v);
                }
                mode = w.reset(&mut Scratch::new(), mode, guard, &x, &mut buf);
                x.copy_from_slice(&buf);
            }
            _ => return None,
        }
    }
    None
}

fn continue_both_ways(free: bool, hip: f64, s0: &[f64]) -> anyhow::Result<(Branch, String)> {
    let family = |g: f64| build(g, free, hip);
    let mut co = ContinuationOptions::new(0.005, 0.15);
    co.integrator = Options::dop853(1e-12);
    co.ds_max = 5e-3;
    co.max_points = 400;
    let mut up = co;
    up.direction = 1.0;
    let mut down = co;
    down.direction = -1.0;
    let bu = continue_branch(&family, s0, G0, 1, &up)?;
    let bd = continue_branch(&family, s0, G0, 1, &down)?;
    let ends = format!("down: {:?}; up: {:?}", bd.end, bu.end);
    let mut points: Vec<_> = bd.points.iter().rev().cloned().collect();
    points.extend(bu.points.iter().skip(1).cloned());
    let mut bifurcations = bd.bifurcations.clone();
    bifurcations.extend(bu.bifurcations.iter().cloned());
    Ok((
        Branch {
            period_strides: 1,
            points,
            bifurcations,
            end: bu.end,
        },
        ends,
    ))
}

/// A period-one gait at γ = [`G0`]: `(free swing knee, section state, stable)`.
type Gait = (bool, Vec<f64>, bool);

/// A chart's named polyline.
type Series = (String, Vec<(f64, f64)>);

/// The charts against the slope, one series of each per branch.
#[derive(Default)]
struct SlopeSeries {
    /// Smallest knee-lock torque over a stride (N m).
    knee: Vec<Series>,
    /// Largest multiplier modulus.
    lam: Vec<Series>,
    /// Smallest normal force over a stride (N).
    norm: Vec<Series>,
}

fn main() -> anyhow::Result<()> {
    faer::set_global_parallelism(faer::Par::Seq);
    let dir = results_dir("seed5")?;
    let mut md = String::new();
    let _ = writeln!(md, "# The seed thesis' walker (Table 3.1)\n");
    let _ = writeln!(md, "Reproduce: `{}`.\n", command("seed5"));
    let locked = build(G0, false, 0.0)?;
    let gaits = gaits_at_g0(locked.as_ref(), &mut md)?;
    slope_branches(&dir, &gaits, &mut md)?;
    let stable_gait = gaits.iter().find(|g| !g.0 && g.2).cloned();
    if let Some((_, s, _)) = &stable_gait {
        profile(&dir, locked.as_ref(), s, &mut md)?;
    }
    let valid_hip = hip_mass(stable_gait.as_ref().map(|g| g.1.as_slice()), &mut md)?;
    if let Some((_, s, _)) = &stable_gait {
        basin(&dir, locked.as_ref(), s, &mut md)?;
    }
    if let Some((hip, _)) = &valid_hip {
        let _ = writeln!(
            md,
            "First hip mass with a stable gait and all flags clear: {hip} kg.\n"
        );
    }
    write_text(&dir, "table.md", &md)?;
    Ok(())
}

/// The variant's name in the gaits table.
fn variant(free: bool) -> &'static str {
    if free {
        "free swing knee"
    } else {
        "knees locked"
    }
}

/// Step 1: Gaits at γ = 0.05 for both variants: Newton (DOP853 1e-14) from the model's gait
/// guesses (`locked`'s), and for the free swing knee from a small grid around them too; distinct
/// gaits kept (1e-7), failed starts listed (the free knee's first 3 only). Writes section 1 to
/// `md`.
fn gaits_at_g0(locked: &dyn Walker, md: &mut String) -> anyhow::Result<Vec<Gait>> {
    let no = NewtonOptions::default();
    let mut t = Table::new(&[
        "variant",
        "guess",
        "result",
        "s* = (q₁, q̇₁, q̇₃)",
        "period (s)",
        "step (m)",
        "multipliers",
        "stable",
    ]);
    let guesses: Vec<(String, Vec<f64>)> = locked
        .gait_guesses()
        .into_iter()
        .map(|g| (g.gait.to_string(), g.section))
        .collect();
    let mut gaits: Vec<Gait> = Vec::new();
    for free in [false, true] {
        let w = build(G0, free, 0.0)?;
        let map = StrideMap::new(w.as_ref(), Options::dop853(1e-14))?;
        let mut starts = guesses.clone();
        if free {
            // A small grid of starts around the locked-knee gaits as well.
            for q in [0.15, 0.2, 0.25] {
                for qd in [-0.8, -0.6, -0.4] {
                    for hd in [0.0, 0.3, 0.6] {
                        starts.push((format!("grid ({q}, {qd}, {hd})"), vec![q, qd, hd]));
                    }
                }
            }
        }
        let mut seen: Vec<Vec<f64>> = Vec::new();
        let mut failures = 0;
        for (label, g) in &starts {
            match find_fixed_point(&map, g, &no) {
                Ok(fp) => {
                    if seen
                        .iter()
                        .any(|s| s.iter().zip(&fp.section).all(|(a, b)| (a - b).abs() < 1e-7))
                    {
                        continue;
                    }
                    seen.push(fp.section.clone());
                    gaits.push((free, fp.section.clone(), fp.stable));
                    t.row(gait_row(free, label, &fp, &map, w.as_ref()));
                }
                Err(e) => {
                    failures += 1;
                    if !free || failures <= 3 {
                        t.row(failure_row(free, label, &e));
                    }
                }
            }
        }
        eprintln!(
            "free = {free}: {} gaits, {failures} failed starts of {}",
            seen.len(),
            starts.len()
        );
        if free {
            let _ = writeln!(
                md,
                "Free swing knee: {} distinct gaits from {} starts ({} starts failed; the \
                 first 3 failures are listed).\n",
                seen.len(),
                starts.len(),
                failures
            );
        }
    }
    let _ = writeln!(md, "## 1. Period-one gaits at γ = {G0}\n\n{}", t.markdown());
    Ok(gaits)
}

/// The gaits table's row of a gait found from start `label`.
fn gait_row(
    free: bool,
    label: &str,
    fp: &FixedPoint,
    map: &StrideMap,
    w: &dyn Walker,
) -> Vec<String> {
    vec![
        variant(free).into(),
        label.to_string(),
        format!(
            "converged ({} it., residual {})",
            fp.iterations,
            sci(fp.residual)
        ),
        format!(
            "({:.9}, {:.9}, {:.9})",
            fp.section[0], fp.section[1], fp.section[2]
        ),
        format!("{:.6}", fp.metrics.period),
        map.stride(&fp.section).ok().map_or("—".into(), |st| {
            format!("{:.5}", w.step_length(&st.pre_event))
        }),
        fmt_multipliers(&fp.multipliers, 4),
        fp.stable.to_string(),
    ]
}

/// The gaits table's row of a start `label` from which Newton failed with `e`.
fn failure_row(free: bool, label: &str, e: &impl std::fmt::Display) -> Vec<String> {
    let msg = e.to_string().replace('\n', " ").replace('|', "/");
    vec![
        variant(free).into(),
        label.to_string(),
        format!(
            "no convergence: {}",
            msg.chars().take(160).collect::<String>()
        ),
        "—".into(),
        "—".into(),
        "—".into(),
        "—".into(),
        "—".into(),
    ]
}

/// Step 2: Continuation in the slope, validity along each branch: every gait continued both ways
/// over γ ∈ [0.005, 0.15], one stride's constraint forces checked at each point (about 12 rows
/// per branch in the table); writes section 2 to `md` and its two charts.
fn slope_branches(dir: &Path, gaits: &[Gait], md: &mut String) -> anyhow::Result<()> {
    let mut tb = Table::new(&[
        "branch",
        "γ",
        "q₁*",
        "q̇₁*",
        "q̇₃*",
        "period (s)",
        "|λ|max",
        "stable",
        "min normal (N)",
        "max |f_t/f_n|",
        "min knee torque (N m)",
        "flags",
    ]);
    let mut series = SlopeSeries::default();
    let mut ends_txt = String::new();
    for (free, s, stable) in gaits {
        let name = format!(
            "{} {}",
            if *free { "free knee" } else { "locked" },
            if *stable {
                "stable@0.05"
            } else {
                "unstable@0.05"
            }
        );
        let (r, tc) = time_once(|| continue_both_ways(*free, 0.0, s));
        let (br, ends) = match r {
            Ok(x) => x,
            Err(e) => {
                let _ = writeln!(ends_txt, "- {name}: continuation failed: {e}");
                continue;
            }
        };
        let _ = writeln!(
            ends_txt,
            "- {name}: {} points over γ ∈ [{:.4}, {:.4}] in {tc:.1} s; ends {ends}; bifurcations: {}",
            br.points.len(),
            br.points.iter().map(|p| p.param).fold(f64::INFINITY, f64::min),
            br.points.iter().map(|p| p.param).fold(f64::NEG_INFINITY, f64::max),
            br.bifurcations
                .iter()
                .map(|b| format!("{:?} at γ = {:.6}", b.kind, b.param))
                .collect::<Vec<_>>()
                .join(", ")
        );
        branch_validity(&name, *free, &br, &mut tb, &mut series)?;
    }
    let _ = writeln!(
        md,
        "\n## 2. Gaits against the slope (pseudo-arclength, γ ∈ [0.005, 0.15])\n\n{ends_txt}\n\
         Validity sampled at every accepted DOP853 step (1e-10, h ≤ 0.02 s) of one stride. \
         Knee torque sign as in `ConstraintForces`: the hyper-extension stop can only push, so \
         a **negative** locking torque means the knee would unlock (flex).\n\n{}",
        tb.markdown()
    );
    plot_slope_series(dir, &series, md)
}

/// One branch's validity: each point's stride checked (h ≤ 0.02 s), its series added to
/// `series`, about 12 of its points (and the last) added to `tb`.
fn branch_validity(
    name: &str,
    free: bool,
    br: &Branch,
    tb: &mut Table,
    series: &mut SlopeSeries,
) -> anyhow::Result<()> {
    let mut kn = Vec::new();
    let mut la = Vec::new();
    let mut nf = Vec::new();
    let every = (br.points.len() / 12).max(1);
    for (i, p) in br.points.iter().enumerate() {
        if !(0.005..=0.15).contains(&p.param) {
            continue;
        }
        let w = build(p.param, free, 0.0)?;
        let v = validity(w.as_ref(), &p.section, 0.02);
        let lmax = p
            .multipliers
            .iter()
            .map(|m| m.modulus())
            .fold(0.0, f64::max);
        la.push((p.param, lmax));
        if let Some(v) = &v {
            kn.push((p.param, v.min_knee));
            nf.push((p.param, v.min_normal));
        }
        if i % every == 0 || i + 1 == br.points.len() {
            tb.row(
                vec![
                    name.to_string(),
                    format!("{:.4}", p.param),
                    format!("{:.6}", p.section[0]),
                    format!("{:.6}", p.section[1]),
                    format!("{:.6}", p.section[2]),
                    format!("{:.5}", p.period),
                    format!("{lmax:.4}"),
                    p.stable.to_string(),
                ]
                .into_iter()
                .chain(validity_cells(v.as_ref()))
                .collect(),
            );
        }
    }
    series
        .knee
        .push((format!("{name}: min knee-lock torque (N m)"), kn));
    series.lam.push((format!("{name}: |λ|max"), la));
    series
        .norm
        .push((format!("{name}: min normal force / 100 N"), nf));
    Ok(())
}

/// Section 2's charts (validity and multipliers against the slope), unless every series is
/// empty; their image links are added to `md`.
fn plot_slope_series(dir: &Path, s: &SlopeSeries, md: &mut String) -> anyhow::Result<()> {
    let mut series = s.knee.clone();
    for (n, v) in &s.norm {
        series.push((n.clone(), v.iter().map(|(a, b)| (*a, b / 100.0)).collect()));
    }
    if !series.iter().all(|s| s.1.is_empty()) {
        pdw_store::plot_lines(
            dir.join("validity_vs_slope.png"),
            "Seed walker: smallest knee-lock torque and normal force over a stride",
            "slope γ (rad)",
            "N m  |  N / 100",
            &series,
            false,
            false,
        )?;
        pdw_store::plot_lines(
            dir.join("multipliers_vs_slope.png"),
            "Seed walker: largest Floquet multiplier modulus",
            "slope γ (rad)",
            "|λ|max",
            &s.lam,
            false,
            false,
        )?;
        let _ = writeln!(
            md,
            "![validity](validity_vs_slope.png) ![multipliers](multipliers_vs_slope.png)\n"
        );
    }
    Ok(())
}

/// Step 3: Profiles over one stride at γ = 0.05 (stable locked-knee gait `s`): the chart and
/// section 3 of `md`.
fn profile(dir: &Path, locked: &dyn Walker, s: &[f64], md: &mut String) -> anyhow::Result<()> {
    let v = validity(locked, s, 0.005).ok_or_else(|| anyhow::anyhow!("stride"))?;
    let col = |i: usize| -> Vec<(f64, f64)> { v.profile.iter().map(|p| (p[0], p[i])).collect() };
    pdw_store::plot_lines(
        dir.join("profile_005.png"),
        "Seed walker, knees locked, γ = 0.05: one stride of the gait",
        "time since heel strike (s)",
        "N  |  N m",
        &[
            ("stance-foot normal force (N)".into(), col(1)),
            ("stance-foot tangential force (N, +downhill)".into(), col(2)),
            ("stance-knee lock torque (N m)".into(), col(3)),
            ("swing-knee lock torque (N m)".into(), col(4)),
        ],
        false,
        false,
    )?;
    let (imin, tmin) = v
        .profile
        .iter()
        .map(|p| (p[0], p[3].min(p[4])))
        .fold((0.0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
    let frac_neg = v
        .profile
        .iter()
        .filter(|p| p[3] < 0.0 || p[4] < 0.0)
        .count() as f64
        / v.profile.len() as f64;
    let _ = writeln!(
        md,
        "\n## 3. Ground reaction and knee-lock torques over one stride (γ = 0.05, knees \
         locked, stable gait)\n\n\
         {} samples (DOP853 1e-10, h ≤ 5 ms). Normal force {:.1} … {:.1} N (weight {:.1} N), \
         friction needed ≤ {:.3}; knee-lock torque minimum {:.3} N m at t = {:.3} s; a \
         negative torque in {:.0} % of the samples. Flags: **{}**.\n\n\
         ![profile](profile_005.png)\n",
        v.profile.len(),
        v.min_normal,
        v.profile
            .iter()
            .map(|p| p[1])
            .fold(f64::NEG_INFINITY, f64::max),
        10.0 * 9.81,
        v.max_friction,
        tmin,
        imin,
        100.0 * frac_neg,
        v.flag_text()
    );
    eprintln!(
        "profile: min knee {tmin} at {imin}, flags {}",
        v.flag_text()
    );
    Ok(())
}

/// Step 4: An added hip mass: pseudo-arclength in the hip mass from the stable gait `s` (if any),
/// each point's stride checked; writes section 4 to `md` and returns the first hip mass (and
/// gait) that is stable with every flag clear.
fn hip_mass(s: Option<&[f64]>, md: &mut String) -> anyhow::Result<Option<(f64, Vec<f64>)>> {
    let mut th = Table::new(&[
        "hip mass (kg)",
        "|λ|max",
        "s*",
        "multipliers",
        "stable",
        "min normal (N)",
        "max |f_t/f_n|",
        "min knee torque (N m)",
        "flags",
    ]);
    let mut valid_hip: Option<(f64, Vec<f64>)> = None;
    let mut hip_end = String::new();
    if let Some(s) = s {
        let family = |h: f64| build(G0, false, h);
        let mut co = ContinuationOptions::new(0.005, 60.0);
        co.integrator = Options::dop853(1e-12);
        co.ds_init = 0.05;
        co.ds_max = 1.0;
        co.max_points = 300;
        co.direction = 1.0;
        // Start at 0.01 kg: the corrector's parameter differences must not reach a negative mass.
        let (r, tc) = time_once(|| continue_branch(&family, s, 0.01, 1, &co));
        match r {
            Ok(br) => {
                hip_end = format!(
                    "Continuation in the hip mass from the stable gait: {} points in {tc:.1} s, \
                     ends {:?}; bifurcations: {}.",
                    br.points.len(),
                    br.end,
                    br.bifurcations
                        .iter()
                        .map(|b| format!("{:?} at m_hip = {:.4} kg", b.kind, b.param))
                        .collect::<Vec<_>>()
                        .join(", ")
                );
                valid_hip = hip_validity(&br, &mut th)?;
            }
            Err(e) => hip_end = format!("Continuation in the hip mass failed: {e}"),
        }
    }
    let _ = writeln!(
        md,
        "\n## 4. An added hip mass (γ = 0.05, knees locked; pseudo-arclength in the hip mass)\n\n\
         {hip_end}\n\n{}",
        th.markdown()
    );
    Ok(valid_hip)
}

/// The hip-mass branch's validity: each point's stride checked (h ≤ 0.02 s), about 16 of its
/// points (and the last) added to `th`; returns the first stable point with every flag clear.
fn hip_validity(br: &Branch, th: &mut Table) -> anyhow::Result<Option<(f64, Vec<f64>)>> {
    let mut valid_hip = None;
    let every = (br.points.len() / 16).max(1);
    for (i, p) in br.points.iter().enumerate() {
        let w = build(G0, false, p.param.max(0.0))?;
        let v = validity(w.as_ref(), &p.section, 0.02);
        if let Some(v) = &v {
            if v.valid() && p.stable && valid_hip.is_none() {
                valid_hip = Some((p.param, p.section.clone()));
            }
        }
        if i % every == 0 || i + 1 == br.points.len() {
            th.row(
                vec![
                    format!("{:.3}", p.param),
                    format!(
                        "|λ|max {:.4}",
                        p.multipliers
                            .iter()
                            .map(|m| m.modulus())
                            .fold(0.0, f64::max)
                    ),
                    format!(
                        "({:.6}, {:.6}, {:.6})",
                        p.section[0], p.section[1], p.section[2]
                    ),
                    fmt_multipliers(&p.multipliers, 4),
                    p.stable.to_string(),
                ]
                .into_iter()
                .chain(validity_cells(v.as_ref()))
                .collect(),
            );
        }
    }
    Ok(valid_hip)
}

/// Step 5: Basin of the stable gait `s` at γ = 0.05 (knees locked): 60 × 60 cells around it, 60
/// strides, 2 threads; the picture and section 5 of `md`.
fn basin(dir: &Path, locked: &dyn Walker, s: &[f64], md: &mut String) -> anyhow::Result<()> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    let n = 60;
    let xs = linspace(s[0] - 0.08, s[0] + 0.08, n);
    let ys = linspace(s[1] - 0.3, s[1] + 0.3, n);
    let fall = Outcome::of_fall;
    let problem = BasinProblem::new(locked, s.to_vec(), &fall);
    let cells = grid_cells(s, 0, &xs, 1, &ys);
    let bo = BasinOptions {
        max_strides: 60,
        ..BasinOptions::default()
    };
    let (res, tb) = time_once(|| classify_cells(&problem, &cells, &bo, &pool, &|_| {}));
    let labels: Vec<u8> = res?.iter().map(|c| c.outcome).collect();
    let m = basin_metrics(&labels, n, n, 5)?;
    let header = pdw_store::BasinHeader {
        command: command("seed5"),
        model: "seed5".into(),
        slope: G0,
        params: "{}".into(),
        model_resolved: String::new(),
        integrator: "dop853".into(),
        tolerances: "{\"rtol\":1e-9,\"atol\":1e-9}".into(),
        max_strides: 60,
        x_name: "stance q₁ (rad)".into(),
        x: xs.clone(),
        y_name: "stance rate q̇₁ (rad/s)".into(),
        y: ys.clone(),
        z: None,
        state_names: vec!["stance".into(), "stance_rate".into(), "hip_rate".into()],
        legend: legend()
            .into_iter()
            .map(|(c, nm)| (c, nm.to_string()))
            .collect(),
        shard: None,
    };
    let arr = ndarray::Array2::from_shape_vec((n, n), labels)?;
    pdw_store::plot_basin(
        dir.join("basin_005.png"),
        &header,
        arr.view(),
        Some((s[0], s[1])),
        &format!("Seed walker, knees locked, γ = 0.05 (q̇₃ = {:.4})", s[2]),
    )?;
    let _ = writeln!(
        md,
        "\n## 5. Basin of the stable locked-knee gait (γ = 0.05)\n\n{n} × {n} cells over \
         q₁ ∈ s*₀ ± 0.08, q̇₁ ∈ s*₁ ± 0.3 (q̇₃ fixed at s*₂), DOP853 1e-9, 60 strides, \
         {tb:.1} s on 2 threads. Fractions: {}; basin entropy {:.4}, boundary entropy \
         {:.4}.\n\n![basin](basin_005.png)\n",
        m.fractions
            .iter()
            .filter(|f| f.2 > 0.0)
            .map(|f| format!("{} {:.4}", f.1, f.2))
            .collect::<Vec<_>>()
            .join(", "),
        m.basin_entropy,
        m.boundary_entropy
    );
    eprintln!("basin {tb:.1} s");
    Ok(())
}
