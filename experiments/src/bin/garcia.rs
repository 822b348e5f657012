//! Garcia, Chatterjee, Ruina & Coleman (1998) reproduced: both period-one gaits of the simplest
//! walker against the slope γ (pseudo-arclength continuation), the small-slope scaling laws of
//! their Appendix A.2 overlaid, the Floquet multipliers against γ, and the period-doubling
//! cascade (located bifurcations, Feigenbaum-type ratios δ_k = (γ_k − γ_{k−1}) / (γ_{k+1} − γ_k))
//! with a brute-force orbit diagram.
//!
//! Scaling laws (Garcia 1998 App. A.2): θ* ≈ Θ₀ γ^{1/3} + Θ₁ γ, θ̇* ≈ α Θ₀ γ^{1/3} + (α Θ₁ + c₁) γ,
//! τ ≈ τ₀ + τ₁ γ^{2/3} + τ₂ γ^{4/3}. The coefficients are measured here by least squares of
//! θ*/γ^{1/3}, θ̇*/γ^{1/3} and τ against x = γ^{2/3} (quadratic in x) over fixed points at
//! 10⁻⁹ ≤ γ ≤ 10⁻⁴, solved directly from the asymptotic guess with DOP853 at 1e-14.

use anyhow::Context;
use pdw_experiments::{command, fmt_multipliers, results_dir, sci, time_once, write_text, Table};
use pdw_hybrid::Options;
use pdw_limit::{
    continue_branch, find_fixed_point, orbit_diagram, period_doubling_cascade, Bifurcation,
    BifurcationKind, Branch, ContinuationOptions, FixedPoint, Multiplier, NewtonOptions,
    OrbitOptions, OrbitStart, StrideMap,
};
use pdw_walkers::simplest::GarciaGait;
use pdw_walkers::{Walker, WalkerError};
use std::fmt::Write as _;
use std::path::Path;

fn family(g: f64) -> Result<Box<dyn Walker>, WalkerError> {
    pdw_walkers::build("simplest", &[("slope", g)])
}

/// Least squares `y ≈ c₀ + c₁ x + c₂ x²` (normal equations, 3 × 3, Cramer's rule).
fn quad_fit(x: &[f64], y: &[f64]) -> [f64; 3] {
    let mut a = [[0.0; 3]; 3];
    let mut b = [0.0; 3];
    for (&xi, &yi) in x.iter().zip(y) {
        let p = [1.0, xi, xi * xi];
        for i in 0..3 {
            b[i] += p[i] * yi;
            for j in 0..3 {
                a[i][j] += p[i] * p[j];
            }
        }
    }
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(a);
    let mut c = [0.0; 3];
    for (k, ck) in c.iter_mut().enumerate() {
        let mut m = a;
        for i in 0..3 {
            m[i][k] = b[i];
        }
        *ck = det3(m) / d;
    }
    c
}

/// `pdw_limit` branch → `pdw_store` branch.
fn store_branch(name: &str, b: &Branch) -> pdw_store::Branch {
    pdw_store::Branch {
        name: name.to_string(),
        period_strides: b.period_strides as u32,
        parameter: b.points.iter().map(|p| p.param).collect(),
        section: b.points.iter().map(|p| p.section.clone()).collect(),
        multipliers: b
            .points
            .iter()
            .map(|p| p.multipliers.iter().map(|m| (m.re, m.im)).collect())
            .collect(),
        stable: b.points.iter().map(|p| p.stable).collect(),
        ..Default::default()
    }
}

fn kind_name(k: BifurcationKind) -> &'static str {
    match k {
        BifurcationKind::PeriodDoubling => "period-doubling",
        BifurcationKind::Fold => "fold",
        BifurcationKind::BranchPoint => "branch-point",
        BifurcationKind::NeimarkSacker => "neimark-sacker",
    }
}

/// Joins two half-branches continued from the same start point in opposite directions.
fn join(down: &Branch, up: &Branch) -> Branch {
    let mut points: Vec<_> = down.points.iter().rev().cloned().collect();
    points.extend(up.points.iter().skip(1).cloned());
    let mut bifurcations = down.bifurcations.clone();
    bifurcations.extend(up.bifurcations.iter().cloned());
    Branch {
        period_strides: up.period_strides,
        points,
        bifurcations,
        end: up.end.clone(),
    }
}

/// The slope both gaits are found at and continued from.
const G0: f64 = 0.009;
/// The cascade's window: the orbit diagram's slopes and the zoomed diagram's range.
const WINDOW: (f64, f64) = (0.0145, 0.0192);

/// The period-doubling cascade on the long-period gait.
struct Cascade {
    /// The located period doublings, in order.
    pds: Vec<Bifurcation>,
    /// The branches followed: the period-one start, then each doubled one.
    branches: Vec<Branch>,
    /// Wall time (s).
    seconds: f64,
}

/// The brute-force orbit diagram over [`WINDOW`].
struct Orbit {
    diagram: pdw_store::OrbitDiagram,
    /// Number of slopes.
    n: usize,
    opts: OrbitOptions,
    /// Slopes without a detected period (chaotic or not converged).
    chaotic: usize,
    /// Slopes where the walker fell.
    fell: usize,
    /// Wall time (s).
    seconds: f64,
}

/// One direct solve of the small-slope scaling: `(gait, γ, θ, θ̇, τ, λ)`.
type ScalingRow = (GarciaGait, f64, f64, f64, f64, Vec<Multiplier>);

/// The scaling laws fitted for one gait: `(gait, θ*/γ^{1/3} fit, α, c₁, τ fit, points)`; each
/// fit is `[c₀, c₁, c₂]` of `c₀ + c₁ x + c₂ x²` in x = γ^{2/3}.
type Fit = (GarciaGait, [f64; 3], f64, f64, [f64; 3], usize);

fn main() -> anyhow::Result<()> {
    faer::set_global_parallelism(faer::Par::Seq);
    let dir = results_dir("garcia")?;
    let no = NewtonOptions {
        tol: 1e-13,
        ..NewtonOptions::default()
    };
    let gaits = gaits_at_g0(&no)?;
    let (branches, t_cont) = continue_gaits(&gaits)?;
    let cascade = cascade(&branches)?;
    let orbit = orbit_diagram_over_cascade(&branches)?;
    store(&dir, &branches, &cascade, &orbit)?;
    let scaling = scaling_solves(&no)?;
    let fits = fit_window(&scaling, 1e-4);
    let fits_small = fit_window(&scaling, 1e-6);
    plot_scaling(&dir, &scaling, &fits)?;
    let md = report(
        &gaits,
        &branches,
        t_cont,
        &cascade,
        &orbit,
        &fits,
        &fits_small,
    );
    write_text(&dir, "scaling.csv", &scaling_csv(&scaling))?;
    write_text(&dir, "table.md", &md)?;
    Ok(())
}

/// Step 1: Both gaits at γ = [`G0`] (DOP853 1e-14, Newton to `no`'s tolerance): long period first.
fn gaits_at_g0(no: &NewtonOptions) -> anyhow::Result<Vec<FixedPoint>> {
    let w0 = family(G0)?;
    let map0 = StrideMap::new(w0.as_ref(), Options::dop853(1e-14))?;
    let mut gaits = Vec::new();
    for g in [GarciaGait::LongPeriod, GarciaGait::ShortPeriod] {
        let fp = find_fixed_point(&map0, &g.section_guess(G0), no)?;
        gaits.push(fp);
    }
    Ok(gaits)
}

/// Step 1: Both gaits against the slope by pseudo-arclength continuation: each continued down
/// and up from [`G0`] and joined; returns the named branches and the wall time of all four (s).
fn continue_gaits(gaits: &[FixedPoint]) -> anyhow::Result<(Vec<(String, Branch)>, f64)> {
    let mut copts = ContinuationOptions::new(2e-4, 0.0195);
    copts.ds_max = 2e-3;
    let mut branches = Vec::new();
    let mut t_cont = 0.0;
    for (name, fp) in ["long-period (stable at 0.009)", "short-period"]
        .iter()
        .zip(gaits)
    {
        let mut up = copts;
        up.direction = 1.0;
        let mut down = copts;
        down.direction = -1.0;
        let ((bu, bd), t) = time_once(|| {
            (
                continue_branch(&family, &fp.section, G0, 1, &up),
                continue_branch(&family, &fp.section, G0, 1, &down),
            )
        });
        t_cont += t;
        let (bu, bd) = (bu?, bd?);
        eprintln!(
            "{name}: {} + {} points, ends {:?} / {:?}",
            bd.points.len(),
            bu.points.len(),
            bd.end,
            bu.end
        );
        branches.push((name.to_string(), join(&bd, &bu)));
    }
    Ok((branches, t_cont))
}

/// Step 2: Period-doubling cascade on the long-period gait, from its point nearest γ = 0.013.
fn cascade(branches: &[(String, Branch)]) -> anyhow::Result<Cascade> {
    let mut casc = ContinuationOptions::new(0.012, 0.0195);
    casc.ds_max = 5e-4;
    casc.ds_init = 1e-4;
    casc.locate_tol = 1e-12;
    casc.switch_eps = 1e-4;
    let start = &branches[0]
        .1
        .points
        .iter()
        .min_by(|a, b| (a.param - 0.013).abs().total_cmp(&(b.param - 0.013).abs()))
        .context("no point near 0.013")?
        .clone();
    let levels = 6;
    let (cascade, t_casc) =
        time_once(|| period_doubling_cascade(&family, &start.section, start.param, levels, &casc));
    let (pds, cbranches): (Vec<Bifurcation>, Vec<Branch>) = cascade?;
    eprintln!("cascade: {} period doublings in {t_casc:.1} s", pds.len());
    for p in &pds {
        eprintln!(
            "  PD period {} → {} at γ = {:.12}",
            p.period_strides,
            2 * p.period_strides,
            p.param
        );
    }
    Ok(Cascade {
        pds,
        branches: cbranches,
        seconds: t_casc,
    })
}

/// Step 3: Orbit diagram over the cascade ([`WINDOW`], 800 slopes, 2 threads).
fn orbit_diagram_over_cascade(branches: &[(String, Branch)]) -> anyhow::Result<Orbit> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    let n_orbit = 800;
    let mus: Vec<f64> = (0..n_orbit)
        .map(|i| WINDOW.0 + (WINDOW.1 - WINDOW.0) * i as f64 / (n_orbit - 1) as f64)
        .collect();
    // Start each slope from the period-one branch (interpolated), nudged off it.
    let p1 = &branches[0].1.points;
    let starts: Vec<Vec<f64>> = mus
        .iter()
        .map(|&m| {
            let best = p1
                .iter()
                .filter(|p| p.param <= 0.0195)
                .min_by(|a, b| (a.param - m).abs().total_cmp(&(b.param - m).abs()))
                .expect("branch not empty");
            vec![best.section[0] + 1e-5, best.section[1]]
        })
        .collect();
    let oopts = OrbitOptions {
        transient: 1000,
        record: 128,
        chunk: 16,
        ..OrbitOptions::default()
    };
    let (cols, t_orbit) =
        time_once(|| orbit_diagram(&family, &mus, &OrbitStart::PerParam(starts), &oopts, &pool));
    let cols = cols?;
    eprintln!("orbit diagram: {n_orbit} slopes in {t_orbit:.1} s");
    let orbit = pdw_store::OrbitDiagram {
        coordinate: "theta".into(),
        parameter: cols.iter().map(|c| c.param).collect(),
        points: cols
            .iter()
            .map(|c| {
                let mut v: Vec<f64> = c.points.iter().map(|p| p[0]).collect();
                v.resize(oopts.record, f64::NAN);
                v
            })
            .collect(),
    };
    let chaotic = cols
        .iter()
        .filter(|c| c.fall.is_none() && c.period.is_none())
        .count();
    let fell = cols.iter().filter(|c| c.fall.is_some()).count();
    Ok(Orbit {
        diagram: orbit,
        n: n_orbit,
        opts: oopts,
        chaotic,
        fell,
        seconds: t_orbit,
    })
}

/// Store: HDF5 sweep file + bifurcation diagrams (the full one and the cascade's zoom).
fn store(
    dir: &Path,
    branches: &[(String, Branch)],
    cascade: &Cascade,
    orbit: &Orbit,
) -> anyhow::Result<()> {
    let data = sweep_data(branches, &cascade.branches, &orbit.diagram);
    pdw_store::write_sweep(dir.join("garcia.h5"), true, &data)?;
    pdw_store::plot_bifurcation(dir.join("bifurcation_full.png"), &data, 0)?;
    pdw_store::plot_bifurcation(dir.join("cascade.png"), &zoom(&data), 0)?;
    Ok(())
}

/// The sweep file's contents: both period-one branches, then the cascade's doubled branches
/// (its first, the period-one start, left out), each with its bifurcations.
fn sweep_data(
    branches: &[(String, Branch)],
    cbranches: &[Branch],
    orbit: &pdw_store::OrbitDiagram,
) -> pdw_store::SweepData {
    let mut sb = Vec::new();
    let mut sbif = Vec::new();
    for (name, b) in branches {
        for bf in &b.bifurcations {
            sbif.push(pdw_store::Bifurcation {
                kind: kind_name(bf.kind).into(),
                parameter: bf.param,
                branch: sb.len(),
                section: bf.section.clone(),
            });
        }
        sb.push(store_branch(name, b));
    }
    for b in cbranches.iter().skip(1) {
        for bf in &b.bifurcations {
            sbif.push(pdw_store::Bifurcation {
                kind: kind_name(bf.kind).into(),
                parameter: bf.param,
                branch: sb.len(),
                section: bf.section.clone(),
            });
        }
        sb.push(store_branch(&format!("period-{}", b.period_strides), b));
    }
    pdw_store::SweepData {
        command: command("garcia"),
        model: "simplest".into(),
        parameter: "slope".into(),
        params: "{}".into(),
        section_names: vec!["theta".into(), "thetadot".into()],
        branches: sb,
        bifurcations: sbif,
        orbit: Some(orbit.clone()),
        ..Default::default()
    }
}

/// Zoom on the cascade: branch points inside [`WINDOW`] only.
fn zoom(data: &pdw_store::SweepData) -> pdw_store::SweepData {
    let (lo, hi) = WINDOW;
    let zoom = pdw_store::SweepData {
        branches: data
            .branches
            .iter()
            .map(|b| {
                let keep: Vec<usize> = (0..b.parameter.len())
                    .filter(|&i| b.parameter[i] >= lo && b.parameter[i] <= hi)
                    .collect();
                pdw_store::Branch {
                    name: b.name.clone(),
                    period_strides: b.period_strides,
                    parameter: keep.iter().map(|&i| b.parameter[i]).collect(),
                    section: keep.iter().map(|&i| b.section[i].clone()).collect(),
                    multipliers: keep.iter().map(|&i| b.multipliers[i].clone()).collect(),
                    stable: keep.iter().map(|&i| b.stable[i]).collect(),
                    ..Default::default()
                }
            })
            .collect(),
        ..data.clone()
    };
    let zoom = pdw_store::SweepData {
        bifurcations: data
            .bifurcations
            .iter()
            .filter(|b| zoom.branches[b.branch].parameter.len() > 1)
            .cloned()
            .collect(),
        branches: zoom.branches.clone(),
        ..zoom
    };
    // Drop empty branches (re-indexing the bifurcations).
    let mut idx = Vec::new();
    let mut zb = Vec::new();
    for b in &zoom.branches {
        if b.parameter.len() > 1 {
            idx.push(Some(zb.len()));
            zb.push(b.clone());
        } else {
            idx.push(None);
        }
    }
    let zbif = zoom
        .bifurcations
        .iter()
        .filter_map(|b| {
            idx[b.branch].map(|k| pdw_store::Bifurcation {
                branch: k,
                ..b.clone()
            })
        })
        .collect();
    pdw_store::SweepData {
        branches: zb,
        bifurcations: zbif,
        ..zoom
    }
}

/// Step 4: Small-slope scaling, direct solves: both gaits at 41 slopes 10⁻⁹ … 10⁻², each from the
/// asymptotic guess (Newton to `no`'s tolerance), else from the previous solution (to 1e-12).
fn scaling_solves(no: &NewtonOptions) -> anyhow::Result<Vec<ScalingRow>> {
    let gammas: Vec<f64> = (0..=40)
        .map(|i| 10f64.powf(-9.0 + 7.0 * i as f64 / 40.0))
        .collect();
    let mut scaling = Vec::new(); // (gait, γ, θ, θ̇, τ, λ)
    for g in [GarciaGait::LongPeriod, GarciaGait::ShortPeriod] {
        let mut prev: Option<Vec<f64>> = None;
        for &gm in &gammas {
            let w = family(gm)?;
            let map = StrideMap::new(w.as_ref(), Options::dop853(1e-14))?;
            let guess = g.section_guess(gm).to_vec();
            let r = find_fixed_point(&map, &guess, no).or_else(|_| {
                find_fixed_point(
                    &map,
                    prev.as_deref().unwrap_or(&guess),
                    &NewtonOptions {
                        tol: 1e-12,
                        ..NewtonOptions::default()
                    },
                )
            });
            match r {
                Ok(fp) => {
                    prev = Some(fp.section.clone());
                    scaling.push((
                        g,
                        gm,
                        fp.section[0],
                        fp.section[1],
                        fp.metrics.period,
                        fp.multipliers,
                    ));
                }
                Err(e) => eprintln!("scaling {g:?} γ = {gm:e}: {e}"),
            }
        }
    }
    Ok(scaling)
}

/// The scaling laws of both gaits fitted over the solves with γ ≤ `gmax`.
fn fit_window(scaling: &[ScalingRow], gmax: f64) -> Vec<Fit> {
    let mut fits = Vec::new();
    for g in [GarciaGait::LongPeriod, GarciaGait::ShortPeriod] {
        let pts: Vec<_> = scaling.iter().filter(|r| r.0 == g && r.1 <= gmax).collect();
        let x: Vec<f64> = pts.iter().map(|r| r.1.powf(2.0 / 3.0)).collect();
        let yt: Vec<f64> = pts.iter().map(|r| r.2 / r.1.cbrt()).collect();
        let yd: Vec<f64> = pts.iter().map(|r| r.3 / r.1.cbrt()).collect();
        let yp: Vec<f64> = pts.iter().map(|r| r.4).collect();
        let ft = quad_fit(&x, &yt);
        let fd = quad_fit(&x, &yd);
        let fpd = quad_fit(&x, &yp);
        // Θ₀ = ft0, Θ₁ = ft1; α = fd0/Θ₀; c₁ = fd1 − α Θ₁.
        let alpha = fd[0] / ft[0];
        let c1 = fd[1] - alpha * ft[1];
        fits.push((g, ft, alpha, c1, fpd, pts.len()));
    }
    fits
}

/// The charts of the small-slope scaling: θ*/γ^{1/3} and the period against γ^{2/3}, computed,
/// Garcia's laws and (for θ*) the fitted ones.
fn plot_scaling(dir: &Path, scaling: &[ScalingRow], fits: &[Fit]) -> anyhow::Result<()> {
    // Scaling chart: θ*/γ^{1/3} against γ^{2/3}.
    let mut series = Vec::new();
    for (g, ft, _, _, _, _) in fits {
        let name = match g {
            GarciaGait::LongPeriod => "long",
            GarciaGait::ShortPeriod => "short",
        };
        let a = g.asymptotics();
        let pts: Vec<(f64, f64)> = scaling
            .iter()
            .filter(|r| r.0 == *g && r.1 <= 0.012)
            .map(|r| (r.1.powf(2.0 / 3.0), r.2 / r.1.cbrt()))
            .collect();
        let xmax = pts.iter().map(|p| p.0).fold(0.0, f64::max);
        let line = |c0: f64, c1: f64| -> Vec<(f64, f64)> {
            (0..=20)
                .map(|i| {
                    let x = xmax * i as f64 / 20.0;
                    (x, c0 + c1 * x)
                })
                .collect()
        };
        series.push((format!("{name}: computed θ*/γ^(1/3)"), pts));
        series.push((
            format!("{name}: Garcia Θ₀ + Θ₁γ^(2/3), Θ₁ = {:.6}", a.theta1),
            line(a.theta0, a.theta1),
        ));
        series.push((
            format!("{name}: fitted Θ₀ + Θ₁γ^(2/3), Θ₁ = {:.4}", ft[1]),
            line(ft[0], ft[1]),
        ));
    }
    pdw_store::plot_lines(
        dir.join("scaling_theta.png"),
        "Simplest walker: θ*/γ^(1/3) against γ^(2/3) (Garcia 1998 App. A.2)",
        "γ^(2/3)",
        "θ* / γ^(1/3)",
        &series,
        false,
        false,
    )?;
    let mut series = Vec::new();
    for (g, _, _, _, fpd, _) in fits {
        let name = match g {
            GarciaGait::LongPeriod => "long",
            GarciaGait::ShortPeriod => "short",
        };
        let a = g.asymptotics();
        let pts: Vec<(f64, f64)> = scaling
            .iter()
            .filter(|r| r.0 == *g && r.1 <= 0.012)
            .map(|r| (r.1.powf(2.0 / 3.0), r.4))
            .collect();
        let xs: Vec<f64> = pts.iter().map(|p| p.0).collect();
        series.push((format!("{name}: computed period τ"), pts));
        series.push((
            format!("{name}: Garcia τ₀ + τ₁γ^(2/3) + τ₂γ^(4/3)"),
            xs.iter()
                .map(|&x| (x, a.tau0 + a.tau1 * x + a.tau2 * x * x))
                .collect(),
        ));
        let _ = fpd;
    }
    pdw_store::plot_lines(
        dir.join("scaling_period.png"),
        "Simplest walker: step period against γ^(2/3)",
        "γ^(2/3)",
        "period τ (units √(l/g))",
        &series,
        false,
        false,
    )?;
    Ok(())
}

/// Tables: `table.md`, section by section.
fn report(
    gaits: &[FixedPoint],
    branches: &[(String, Branch)],
    t_cont: f64,
    cascade: &Cascade,
    orbit: &Orbit,
    fits: &[Fit],
    fits_small: &[Fit],
) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# Garcia et al. 1998 reproduced (simplest walker)\n");
    let _ = writeln!(md, "Reproduce: `{}`.\n", command("garcia"));
    report_gaits(&mut md, gaits);
    report_branches(&mut md, branches, t_cont);
    report_cascade(&mut md, cascade, orbit);
    report_scaling(&mut md, fits, fits_small);
    md
}

/// Both gaits at γ = 0.009 against Garcia's printed values.
fn report_gaits(md: &mut String, gaits: &[FixedPoint]) {
    let _ = writeln!(
        md,
        "## Both gaits at γ = 0.009 (DOP853 1e-14, Newton to 1e-13)\n"
    );
    let mut t = Table::new(&[
        "gait",
        "θ*",
        "θ̇*",
        "period",
        "multipliers",
        "Garcia θ*",
        "Garcia θ̇*",
        "|Δ|∞",
    ]);
    let refs = [
        (0.20031090049483, -0.19983247291764),
        (0.19393736960624, -0.20386692731962),
    ];
    for ((fp, (rt, rd)), name) in gaits
        .iter()
        .zip(refs)
        .zip(["long (stable)", "short (unstable)"])
    {
        t.row(vec![
            name.into(),
            format!("{:.14}", fp.section[0]),
            format!("{:.14}", fp.section[1]),
            format!("{:.10}", fp.metrics.period),
            fmt_multipliers(&fp.multipliers, 9),
            format!("{rt:.14}"),
            format!("{rd:.14}"),
            sci((fp.section[0] - rt).abs().max((fp.section[1] - rd).abs())),
        ]);
    }
    let _ = writeln!(md, "{}", t.markdown());
    let _ = writeln!(
        md,
        "Garcia's printed multipliers of the stable gait, −0.191 ± 0.556i, came from finite \
         differences; the exact (variational) ones above differ by {}.\n",
        sci((gaits[0].multipliers[0].re + 0.191).hypot(gaits[0].multipliers[0].im.abs() - 0.556))
    );
}

/// The continued branches: their ranges, ends and bifurcations.
fn report_branches(md: &mut String, branches: &[(String, Branch)], t_cont: f64) {
    let _ = writeln!(
        md,
        "## Branches (pseudo-arclength, DOP853 1e-13) — {t_cont:.2} s for both\n"
    );
    let _ = writeln!(md, "![bifurcation](bifurcation_full.png)\n");
    for (name, b) in branches {
        let ps: Vec<f64> = b.points.iter().map(|p| p.param).collect();
        let _ = writeln!(
            md,
            "- {name}: {} points, γ from {:.6} to {:.6}, end: {:?}",
            b.points.len(),
            ps.iter().cloned().fold(f64::INFINITY, f64::min),
            ps.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
            b.end
        );
        for bf in &b.bifurcations {
            let _ = writeln!(
                md,
                "  - {} at γ = {:.12} (bracket {}), multipliers {}",
                kind_name(bf.kind),
                bf.param,
                sci(bf.param_bracket),
                fmt_multipliers(&bf.multipliers, 6)
            );
        }
    }
}

/// The period doublings with their Feigenbaum-type ratios against Garcia's, and the orbit
/// diagram's counts.
fn report_cascade(md: &mut String, cascade: &Cascade, orbit: &Orbit) {
    let (pds, t_casc) = (&cascade.pds, cascade.seconds);
    let _ = writeln!(md, "\n## Period-doubling cascade — {t_casc:.1} s\n");
    let _ = writeln!(md, "![cascade](cascade.png)\n");
    let mut t = Table::new(&[
        "k",
        "period doubling",
        "γ_k",
        "bracket",
        "δ_k = (γ_k − γ_{k−1})/(γ_{k+1} − γ_k)",
        "Garcia",
    ]);
    let garcia = ["—", "5.9", "5.2", "4.6", "—", "—"];
    for (k, p) in pds.iter().enumerate() {
        let delta = if k >= 1 && k + 1 < pds.len() {
            format!(
                "{:.3}",
                (pds[k].param - pds[k - 1].param) / (pds[k + 1].param - pds[k].param)
            )
        } else {
            "—".into()
        };
        t.row(vec![
            (k + 1).to_string(),
            format!("{} → {}", p.period_strides, 2 * p.period_strides),
            format!("{:.12}", p.param),
            sci(p.param_bracket),
            delta,
            garcia.get(k).unwrap_or(&"—").to_string(),
        ]);
    }
    let _ = writeln!(md, "{}", t.markdown());
    let (lo, hi) = WINDOW;
    let (n_orbit, t_orbit, chaotic, fell) = (orbit.n, orbit.seconds, orbit.chaotic, orbit.fell);
    let _ = writeln!(
        md,
        "Orbit diagram: {n_orbit} slopes in [{lo}, {hi}], {} transient + {} recorded strides each \
         (DOP853 1e-10, 2 threads): {t_orbit:.1} s. No period ≤ 64 detected (chaotic or \
         not converged) at {chaotic} slopes; the walker fell at {fell}.\n",
        orbit.opts.transient, orbit.opts.record
    );
}

/// The scaling coefficients: Garcia's against both fits.
fn report_scaling(md: &mut String, fits: &[Fit], fits_small: &[Fit]) {
    let _ = writeln!(md, "## Small-slope scaling (Garcia App. A.2)\n");
    let _ = writeln!(
        md,
        "![theta](scaling_theta.png) ![period](scaling_period.png)\n"
    );
    let mut t = Table::new(&[
        "gait",
        "coefficient",
        "Garcia 1998",
        "fitted, γ ≤ 1e-4",
        "fitted, γ ≤ 1e-6",
    ]);
    for ((g, ft, alpha, c1, fpd, _), (_, ft2, alpha2, c12, fpd2, _)) in fits.iter().zip(fits_small)
    {
        let a = g.asymptotics();
        let name = format!("{g:?}");
        for (c, pub_v, fit_v, fit2) in [
            ("Θ₀", a.theta0, ft[0], ft2[0]),
            ("Θ₁", a.theta1, ft[1], ft2[1]),
            ("α", a.alpha, *alpha, *alpha2),
            ("c₁", a.c1, *c1, *c12),
            ("τ₀", a.tau0, fpd[0], fpd2[0]),
            ("τ₁", a.tau1, fpd[1], fpd2[1]),
            ("τ₂", a.tau2, fpd[2], fpd2[2]),
        ] {
            t.row(vec![
                name.clone(),
                c.into(),
                format!("{pub_v:.6}"),
                format!("{fit_v:.6}"),
                format!("{fit2:.6}"),
            ]);
        }
    }
    let _ = writeln!(md, "{}", t.markdown());
}

/// `scaling.csv`: every direct solve, full precision.
fn scaling_csv(scaling: &[ScalingRow]) -> String {
    let mut csv = String::from("gait,slope,theta,thetadot,period,multipliers\n");
    for r in scaling {
        let _ = writeln!(
            csv,
            "{:?},{:e},{:.16e},{:.16e},{:.16e},{}",
            r.0,
            r.1,
            r.2,
            r.3,
            r.4,
            fmt_multipliers(&r.5, 12).replace(", ", ";")
        );
    }
    csv
}
