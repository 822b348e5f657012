//! The seed's walker (Table 3.1: shanks 2 kg, thighs 3 kg, every segment 2 m) redesigned under
//! the full validity criteria: stable, valid along the whole stride (loads, clearance over the
//! whole swing) and at every impact (stops and contacts push only), every criterion with a
//! relative margin of at least [`MIN_MARGIN`] of its natural scale, and robust to ±5 % in every
//! free parameter — or, where no design does, which criterion fails where.
//!
//! The model is `seed5_stage2.toml` (the earlier search's design space) with its knees held by
//! hyper-extension **stops**: a stance knee whose stop would pull at an impact buckles (a fall),
//! a trailing knee whose stop would pull at heel strike is released and the new swing knee
//! starts flexing (the chain walker's mode change, section `swing_knee_rate`).
//!
//! 1. **Search** (argmin's Nelder–Mead through [`pdw_limit::design::search`], seeded random
//!    starts first) over the seven free parameters of the earlier search, with its bounds
//!    (the thigh's COM allowed down to the knee). Each design is judged by [`judge`]: the
//!    latched model's gait (both knees held both ways) first; one stride of the stop model from
//!    it — where that stride's stance knee buckles, so does the design (verdict "stance knee
//!    buckles"); otherwise the stop model's gait by Newton (from the stop model's state after
//!    [`WALK`] strides, the latched gait, the nearest designs' gaits, the model's guesses), its
//!    multipliers, one stride on the dense solution ([`pdw_limit::Validity::along`]). Graded
//!    cost: max |λ| when feasible; `1 + Σ shortfalls below MIN_MARGIN` (capped at 3) when
//!    stable but not valid with margin; `4 + 0.9·min(1, Σ shortfalls of the latched gait)`
//!    when the stop model has no gait but the latched one does (so that the search can climb
//!    out); `5 + (|λ| − 1)` unstable; 10 without a gait.
//! 2. **Maps** of the same judgement on grids of two parameters through the best design: the
//!    region of each verdict and, for the invalid ones, the binding criterion's group.
//! 3. **Robustness** of every feasible design found: 2·7 one-at-a-time ±5 % designs and 16
//!    seeded random corners of the ±5 % box, each judged again.
//!
//! Writes `experiments/results/seed5_design/redesign.md`, `redesign.csv` (every design),
//! `map_*.csv` / `map_*.png`.

use std::fmt::Write as _;

use anyhow::Context;
use ndarray::Array2;
use pdw_experiments::{command, results_dir, write_text};
use pdw_limit::design::{search, status, DesignEval, DesignOptions, DesignSpace, Objective};
use pdw_limit::{simulate, BasinOptions, TrajectoryOptions, Validity};
use pdw_walkers::registry::ModelInfo;
use pdw_walkers::{Walker, WalkerSpec};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Every criterion's margin over its natural scale must be at least this.
const MIN_MARGIN: f64 = 1e-2;
/// Largest friction coefficient of the ground.
const MU: f64 = 0.6;
/// Free parameters and bounds (the earlier search's, `experiments/results/seed5_design/README.md`).
const FREE: [(&str, f64, f64); 7] = [
    ("thigh_cn", -0.1, 0.4),
    ("shank_cn", -0.3, 0.25),
    ("foot_radius", 0.0, 1.2),
    ("hip_mass", 0.0, 20.0),
    ("slope", 0.01, 0.12),
    ("thigh_com", 0.0, 0.95),
    ("shank_com", 0.1, 0.95),
];
/// Designs evaluated by the search (`--budget`), seeded random ones among them (`--init`).
const BUDGET: usize = 300;
const INIT: usize = 100;
/// Map grids, cells per side (`--map`).
const MAP_N: usize = 11;

/// `--budget N`, `--init N`, `--map N` from the command line (defaults above).
fn sizes() -> anyhow::Result<(usize, usize, usize)> {
    let (mut budget, mut init, mut map) = (BUDGET, INIT, MAP_N);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let slot = match a.as_str() {
            "--budget" => &mut budget,
            "--init" => &mut init,
            "--map" => &mut map,
            _ => anyhow::bail!("unknown argument {a:?} (expected --budget N, --init N, --map N)"),
        };
        let v = args
            .next()
            .ok_or_else(|| anyhow::anyhow!("{a} needs a value"))?;
        *slot = v
            .parse()
            .map_err(|_| anyhow::anyhow!("{a} {v:?} is not a whole number"))?;
    }
    anyhow::ensure!(
        init >= 1 && budget >= init && map >= 2,
        "need 1 <= --init <= --budget and --map >= 2"
    );
    Ok((budget, init, map))
}
/// Strides walked by the stop model from the latched gait.
const WALK: usize = 8;

/// One map: verdict codes, its CSV, the x and y grids.
type MapResult = (Array2<u8>, String, Vec<f64>, Vec<f64>);

/// Verdict codes (map legend).
const NAMES: [&str; 10] = [
    "valid, margins >= 1e-2",
    "valid, a margin < 1e-2",
    "swing foot below the slope",
    "knee stop pulls (continuous)",
    "impact: a stop or contact pulls",
    "normal force / friction",
    "stance knee buckles at an impact",
    "unstable",
    "no gait",
    "stop model falls (other)",
];

/// One judged design.
#[derive(Clone, Debug)]
struct Judged {
    code: u8,
    cost: f64,
    rho: f64,
    /// The stop model's gait (section), if any.
    section: Option<Vec<f64>>,
    /// The latched model's gait, if computed.
    latched: Option<Vec<f64>>,
    /// Binding criterion and its relative margin (or the reason).
    binding: String,
    relative: f64,
    /// The trailing knee leaves the heel strike flexing at this rate (rad/s; 0: held).
    knee_rate: f64,
}

fn latched_spec(spec: &WalkerSpec) -> WalkerSpec {
    let mut s = spec.clone();
    for k in &mut s.knees {
        k.hold = Some("latch".into());
    }
    s
}

/// Shortfalls of the relative margins below [`MIN_MARGIN`] and the binding one of a stride.
fn shortfall(v: &Validity) -> (f64, String, f64) {
    let s: f64 = v
        .margins
        .iter()
        .filter(|m| m.relative.is_finite())
        .map(|m| (MIN_MARGIN - m.relative).max(0.0))
        .sum();
    let friction = v
        .max_friction_required
        .max(v.impact_friction_required.max(0.0))
        - MU;
    let s = s + friction.max(0.0);
    match v.binding() {
        Some(b) => (s, b.name.clone(), b.relative),
        None => (s, "none".into(), f64::NAN),
    }
}

/// A period-one gait from the first of `guesses` that converges, with its largest multiplier
/// modulus.
fn gait(w: &dyn Walker, guesses: &[(String, Vec<f64>)]) -> Option<(pdw_limit::FixedPoint, f64)> {
    let ds = w.section_dim();
    let g: Vec<(String, Vec<f64>)> = guesses
        .iter()
        .map(|(n, s)| {
            let mut s = s.clone();
            s.resize(ds, 0.0);
            (n.clone(), s)
        })
        .collect();
    // the first guess that converges (neighbours' gaits come first); Newton at 1e-9 with at
    // most 12 iterations (a design whose gait needs more is graded as without one)
    let map = pdw_limit::StrideMap::new(w, pdw_hybrid::Options::dop853(1e-11)).ok()?;
    let opts = pdw_limit::NewtonOptions {
        tol: 1e-9,
        max_iters: 12,
        ..pdw_limit::NewtonOptions::default()
    };
    g.iter().find_map(|(_, guess)| {
        let fp = pdw_limit::find_fixed_point(&map, guess, &opts).ok()?;
        let rho = fp
            .multipliers
            .iter()
            .map(|l| l.re.hypot(l.im))
            .fold(0.0, f64::max);
        Some((fp, rho))
    })
}

/// Judges one design (module docs, item 1).
fn judge(
    stop: &ModelInfo,
    latched: &ModelInfo,
    values: &[f64],
    guesses: &[(String, Vec<f64>)],
) -> Judged {
    let mut j = Judged {
        code: 8,
        cost: 10.0,
        rho: f64::NAN,
        section: None,
        latched: None,
        binding: String::new(),
        relative: f64::NAN,
        knee_rate: f64::NAN,
    };
    let (Ok(ws), Ok(wl)) = (stop.build_from(values), latched.build_from(values)) else {
        j.binding = "not a model".into();
        j.cost = 11.0;
        return j;
    };
    // the latched gait first: a start for the stop model and the grade where it buckles
    let lat = gait(wl.as_ref(), guesses);
    let mut g: Vec<(String, Vec<f64>)> = Vec::new();
    if let Some((fp, _)) = &lat {
        g.push(("latched gait".into(), fp.section.clone()));
        j.latched = Some(fp.section.clone());
    }
    g.extend(guesses.iter().cloned());
    // the stop model from the latched gait: its strides (a stable stop gait attracts them);
    // one stride first, the common case being a buckle at its first knee strike
    let walk = lat.as_ref().map(|(lfp, _)| {
        let mut x = vec![0.0; ws.dim()];
        let mut s = lfp.section.clone();
        s.resize(ws.section_dim(), 0.0);
        ws.lift(&s, &mut x);
        let one = simulate(ws.as_ref(), &x, &TrajectoryOptions::new(1));
        match &one {
            Ok(t) if !t.events.iter().any(|e| e.fall) => {
                simulate(ws.as_ref(), &x, &TrajectoryOptions::new(WALK))
            }
            _ => one,
        }
    });
    let walked = match &walk {
        Some(Ok(t)) => t.events.iter().find(|e| e.fall).map(|e| e.kind.clone()),
        Some(Err(e)) => Some(format!("{e}")),
        None => None,
    };
    if let (Some(Ok(t)), None) = (&walk, &walked) {
        g.insert(0, (format!("{WALK} stop-model strides"), t.section.clone()));
    }
    let stop_gait = match &walked {
        // the stride from the latched gait buckles: no Newton on the stop model (its gaits
        // near the latched one buckle too; the verdict is the buckle)
        Some(k) if k.contains("buckle") => None,
        _ => gait(ws.as_ref(), &g),
    };
    let Some((fp, rho)) = stop_gait else {
        let Some((_, lrho)) = lat else {
            j.binding = "no gait (neither stops nor latches)".into();
            return j;
        };
        match walked {
            Some(k) if k.contains("buckle") => {
                j.code = 6;
                j.binding = format!("{k} (from the latched gait)");
            }
            Some(k) => {
                j.code = 9;
                j.binding = format!("from the latched gait the stride falls: {k}");
            }
            None => {
                j.binding = format!("walks {WALK} strides from the latched gait; no gait found");
            }
        }
        // graded by the latched gait's shortfalls, so that the search can climb out
        let lv = lat
            .as_ref()
            .and_then(|(lfp, _)| simulate(wl.as_ref(), &lfp.state, &TrajectoryOptions::new(1)).ok())
            .and_then(|t| Validity::along(wl.as_ref(), &t, 0));
        let (sf, name, rel) = lv
            .as_ref()
            .map_or((1.0, String::new(), f64::NAN), shortfall);
        j.binding = format!("{}; latched binding {name}", j.binding);
        j.relative = rel;
        j.rho = lrho;
        j.cost = 4.0 + 0.9 * sf.min(1.0);
        return j;
    };
    j.rho = rho;
    j.section = Some(fp.section.clone());
    j.knee_rate = fp.section.get(3).copied().unwrap_or(0.0);
    if rho >= 1.0 {
        j.code = 7;
        j.binding = format!("max |λ| = {rho:.4}");
        j.cost = 5.0 + (rho - 1.0).min(4.0);
        return j;
    }
    let Some(v) = simulate(ws.as_ref(), &fp.state, &TrajectoryOptions::new(1))
        .ok()
        .and_then(|t| Validity::along(ws.as_ref(), &t, 0))
    else {
        j.code = 9;
        j.binding = "stride not re-walked".into();
        j.cost = 4.0;
        return j;
    };
    let (sf, name, rel) = shortfall(&v);
    j.binding = name.clone();
    j.relative = rel;
    let friction_ok = v.max_friction_required <= MU
        && (v.impact_friction_required.is_nan() || v.impact_friction_required <= MU);
    if let Some(f) = &v.fell {
        j.code = 9;
        j.binding = f.clone();
        j.cost = 1.0 + (sf + 0.5).min(3.0);
        return j;
    }
    let valid = v.valid() && friction_ok;
    j.code = if valid && rel >= MIN_MARGIN {
        0
    } else if valid {
        1
    } else if !friction_ok || name == "normal_force" {
        5
    } else if name == "swing_clearance" {
        2
    } else if name.ends_with("knee_torque") {
        3
    } else if name.contains(':') {
        4
    } else {
        5
    };
    j.cost = if j.code == 0 { rho } else { 1.0 + sf.min(3.0) };
    j
}

/// The two models judged and the layout of the free parameters, shared by every step.
struct Setup {
    /// `seed5_stage2.toml` with stop knees.
    stop: ModelInfo,
    /// The same with latched knees.
    latched: ModelInfo,
    /// The free parameters' names ([`FREE`]).
    names: Vec<&'static str>,
    /// Every parameter of the model at its default.
    base: Vec<f64>,
    /// The stop model's own gait guesses at `base`.
    model_guesses: Vec<(String, Vec<f64>)>,
}

impl Setup {
    /// Reads `seed5_stage2.toml` from `dir`.
    fn new(dir: &std::path::Path) -> anyhow::Result<Self> {
        let path = dir.join("seed5_stage2.toml");
        let spec = WalkerSpec::from_file(&path).context("seed5_stage2.toml")?;
        let stop = ModelInfo::from_spec(spec.clone());
        let latched = ModelInfo::from_spec(latched_spec(&spec));
        let names: Vec<&str> = FREE.iter().map(|f| f.0).collect();
        let base: Vec<f64> = stop.params.iter().map(|p| p.default).collect();
        let model_guesses = pdw_limit::gaits::model_guesses(stop.build_from(&base)?.as_ref());
        Ok(Self {
            stop,
            latched,
            names,
            base,
            model_guesses,
        })
    }

    /// Index of parameter `n` in the model's parameters.
    fn index(&self, n: &str) -> usize {
        self.stop.params.iter().position(|p| p.name == n).unwrap()
    }

    /// Every parameter's value: `base` with the free ones set to `p`.
    fn values_of(&self, p: &[f64]) -> Vec<f64> {
        let mut v = self.base.clone();
        for (k, n) in self.names.iter().enumerate() {
            v[self.index(n)] = p[k];
        }
        v
    }

    /// [`judge`] of all the parameters' values `values`.
    fn judge(&self, values: &[f64], guesses: &[(String, Vec<f64>)]) -> Judged {
        judge(&self.stop, &self.latched, values, guesses)
    }
}

/// A judged design: its free parameters and the verdict.
type Design = (Vec<f64>, Judged);

fn main() -> anyhow::Result<()> {
    let (budget, init, map_n) = sizes()?;
    let dir = results_dir("seed5_design")?;
    let setup = Setup::new(&dir)?;
    let (judged, search_s) = run_search(&setup, budget, init)?;
    let counts = write_csv(&dir, &setup, &judged)?;
    let best = judged
        .iter()
        .min_by(|a, b| a.1.cost.total_cmp(&b.1.cost))
        .cloned()
        .context("no design evaluated")?;
    let mut md = report_search(&setup, budget, init, search_s, &counts, &best);
    robustness(&setup, &judged, &mut md);
    maps(&dir, &setup, &best, map_n, &mut md)?;
    write_text(&dir, "redesign.md", &md)?;
    print!("{md}");
    Ok(())
}

/// Step 1: the search (seeded random designs, then Nelder–Mead, on the margin objective); every
/// design judged, in order, and the search's wall time (s).
fn run_search(setup: &Setup, budget: usize, init: usize) -> anyhow::Result<(Vec<Design>, f64)> {
    let space = DesignSpace {
        names: setup.names.iter().map(|s| s.to_string()).collect(),
        lo: FREE.iter().map(|f| f.1).collect(),
        hi: FREE.iter().map(|f| f.2).collect(),
    };
    let opts = DesignOptions {
        objective: Objective::Margin,
        mu: MU,
        knee_margin: 0.0,
        min_margin: MIN_MARGIN,
        budget,
        seed: 7,
        start: Some(
            setup
                .names
                .iter()
                .map(|n| setup.base[setup.index(n)])
                .collect(),
        ),
        init,
        basin_grid: 3,
        basin_box: Some([0.02, 0.08]),
        basin: BasinOptions::default(),
        newton_tol: 1e-10,
    };
    let mut judged: Vec<(Vec<f64>, Judged)> = Vec::new();
    let t0 = std::time::Instant::now();
    let mut eval = |p: &[f64], guesses: &[(String, Vec<f64>)]| -> DesignEval {
        let j = setup.judge(&setup.values_of(p), guesses);
        eprintln!(
            "design {:>3}: {} cost {:.4} ({}, {:.3e})",
            judged.len(),
            NAMES[j.code as usize],
            j.cost,
            j.binding,
            j.relative
        );
        let mut ev = DesignEval {
            params: p.to_vec(),
            status: match j.code {
                0 => status::FEASIBLE,
                7 => status::UNSTABLE,
                8 | 6 => status::NO_GAIT,
                _ => status::INVALID,
            },
            reason: j.binding.clone(),
            cost: j.cost,
            basin_fraction: f64::NAN,
            rho: j.rho,
            section: [f64::NAN; 3],
            min_normal_force: f64::NAN,
            max_friction: f64::NAN,
            min_knee_torque: f64::NAN,
            period: f64::NAN,
            step_length: f64::NAN,
            min_relative_margin: j.relative,
            basin_box: [f64::NAN; 2],
            binding: j.binding.clone(),
            shortfall: f64::NAN,
            strides_survived: f64::NAN,
            probe_residual: f64::NAN,
            fates: String::new(),
            run: 0,
        };
        // the stop model's gait, else the latched one, as the neighbours' start
        if let Some(s) = j.section.as_ref().or(j.latched.as_ref()) {
            ev.section = [s[0], s[1], s[2]];
        }
        judged.push((p.to_vec(), j));
        ev
    };
    let history = search(&space, &opts, &setup.model_guesses, Vec::new(), &mut eval)?;
    let search_s = t0.elapsed().as_secs_f64();
    let _ = history;
    Ok((judged, search_s))
}

/// `redesign.csv`: every design judged; returns how many got each verdict.
fn write_csv(
    dir: &std::path::Path,
    setup: &Setup,
    judged: &[Design],
) -> anyhow::Result<[usize; NAMES.len()]> {
    let mut csv = format!(
        "{},verdict,cost,max_abs_lambda,binding,relative_margin,swing_knee_rate\n",
        setup.names.join(",")
    );
    let mut counts = [0usize; NAMES.len()];
    for (p, j) in judged {
        counts[j.code as usize] += 1;
        let _ = writeln!(
            csv,
            "{},{},{},{},\"{}\",{},{}",
            p.iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(","),
            NAMES[j.code as usize],
            j.cost,
            j.rho,
            j.binding.replace('"', "'"),
            j.relative,
            j.knee_rate
        );
    }
    write_text(dir, "redesign.csv", &csv)?;
    Ok(counts)
}

/// The file's head and the search's section: verdict counts and the best design.
fn report_search(
    setup: &Setup,
    budget: usize,
    init: usize,
    search_s: f64,
    counts: &[usize; NAMES.len()],
    best: &Design,
) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# The seed's walker redesigned under the full criteria\n\nReproduce: `{}` (writes this \
         file, `redesign.csv` and the maps). Model: `seed5_stage2.toml` with stop knees (a \
         stance knee whose stop would pull at an impact buckles; a trailing knee whose stop \
         would pull is released at heel strike). Feasible: stable, valid along the stride and \
         at every impact, friction ≤ {MU}, every relative margin ≥ {MIN_MARGIN}.\n",
        command("seed5_redesign")
    );
    let _ = writeln!(
        md,
        "## Search\n\n{budget} designs ({init} seeded random, then Nelder–Mead), {:.0} s. \
         Free: {}.\n\n| verdict | designs |\n|---|---|",
        search_s,
        FREE.iter()
            .map(|f| format!("{} ∈ [{}, {}]", f.0, f.1, f.2))
            .collect::<Vec<_>>()
            .join(", ")
    );
    for (c, n) in NAMES.iter().enumerate() {
        let _ = writeln!(md, "| {n} | {} |", counts[c]);
    }
    let _ = writeln!(
        md,
        "\nBest design (cost {:.4}): {} — verdict **{}**, binding `{}` at relative margin \
         {:.3e}, max |λ| {:.4}, swing knee leaves heel strike at {:.4} rad/s.\n",
        best.1.cost,
        setup
            .names
            .iter()
            .zip(&best.0)
            .map(|(n, v)| format!("{n} = {v:.5}"))
            .collect::<Vec<_>>()
            .join(", "),
        NAMES[best.1.code as usize],
        best.1.binding,
        best.1.relative,
        best.1.rho,
        best.1.knee_rate
    );
    md
}

/// Step 3: robustness of the feasible designs (the first 5): each free parameter ±5 %, and 16
/// random sign patterns of ±5 % in all of them (seeded), judged from the design's gait.
fn robustness(setup: &Setup, judged: &[Design], md: &mut String) {
    let feasible: Vec<&(Vec<f64>, Judged)> = judged.iter().filter(|d| d.1.code == 0).collect();
    let _ = writeln!(md, "## Robustness (±5 % in every free parameter)\n");
    if feasible.is_empty() {
        let _ = writeln!(md, "No feasible design to check.\n");
    }
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for (p, j) in feasible.iter().take(5) {
        let mut perturbed: Vec<Vec<f64>> = Vec::new();
        for k in 0..p.len() {
            for s in [-0.05, 0.05] {
                let mut q = p.clone();
                q[k] *= 1.0 + s;
                perturbed.push(q);
            }
        }
        for _ in 0..16 {
            perturbed.push(
                p.iter()
                    .map(|v| v * (1.0 + if rng.random::<bool>() { 0.05 } else { -0.05 }))
                    .collect(),
            );
        }
        let guesses: Vec<(String, Vec<f64>)> = j
            .section
            .iter()
            .map(|s| ("design gait".to_string(), s.clone()))
            .chain(setup.model_guesses.iter().cloned())
            .collect();
        let ok = perturbed
            .iter()
            .filter(|q| setup.judge(&setup.values_of(q), &guesses).code <= 1)
            .count();
        let _ = writeln!(
            md,
            "- design {:?}: {ok} of {} perturbed designs stable and valid",
            p,
            perturbed.len()
        );
    }
}

/// The maps: pairs of free parameters through the best design.
const MAPS: [(&str, &str); 4] = [
    ("foot_radius", "slope"),
    ("thigh_cn", "shank_cn"),
    ("thigh_com", "shank_com"),
    ("hip_mass", "slope"),
];

/// Step 2: maps through the best design, computed in parallel (2 threads), written with their
/// sections of `md`.
fn maps(
    dir: &std::path::Path,
    setup: &Setup,
    best: &Design,
    map_n: usize,
    md: &mut String,
) -> anyhow::Result<()> {
    let _ = writeln!(md, "\n## Maps through the best design\n");
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    let results: Vec<MapResult> = pool.install(|| {
        use rayon::prelude::*;
        MAPS.par_iter()
            .map(|&(xn, yn)| map(setup, best, xn, yn, map_n))
            .collect()
    });
    for (&(xn, yn), (code, mcsv, xs, ys)) in MAPS.iter().zip(results) {
        let (kx, ky) = (
            setup.names.iter().position(|n| *n == xn).unwrap(),
            setup.names.iter().position(|n| *n == yn).unwrap(),
        );
        let file = format!("map_{xn}_{yn}");
        write_text(dir, &format!("{file}.csv"), &mcsv)?;
        let header = pdw_store::BasinHeader {
            command: command("seed5_redesign"),
            model: "seed5_stage2 (stop knees)".into(),
            slope: setup.values_of(&best.0)[setup.index("slope")],
            params: String::new(),
            model_resolved: String::new(),
            integrator: String::new(),
            tolerances: String::new(),
            max_strides: 1,
            x_name: xn.into(),
            x: xs.clone(),
            y_name: yn.into(),
            y: ys.clone(),
            z: None,
            state_names: vec![xn.into(), yn.into()],
            legend: NAMES
                .iter()
                .enumerate()
                .map(|(c, s)| (c as u8, s.to_string()))
                .collect(),
            shard: None,
        };
        pdw_store::plot_basin(
            dir.join(format!("{file}.png")),
            &header,
            code.view(),
            Some((best.0[kx], best.0[ky])),
            &format!("seed5 (Table 3.1), stop knees: verdicts in ({xn}, {yn})"),
        )?;
        let c: Vec<String> = (0..NAMES.len())
            .filter_map(|c| {
                let k = code.iter().filter(|&&v| v as usize == c).count();
                (k > 0).then(|| format!("{}: {k}", NAMES[c]))
            })
            .collect();
        let _ = writeln!(
            md,
            "### {xn} × {yn}\n\n![{file}]({file}.png)\n\n{map_n}×{map_n} cells, the other \
             parameters at the best design's (⊗): {}. Per cell: [{file}.csv]({file}.csv).\n",
            c.join(", ")
        );
    }
    Ok(())
}

/// One map: `map_n` × `map_n` designs over free parameters `xn` × `yn`, the others at the best
/// design's; each cell judged from its left and lower neighbours' gaits, the best design's and
/// the model's.
fn map(setup: &Setup, best: &Design, xn: &str, yn: &str, map_n: usize) -> MapResult {
    let (kx, ky) = (
        setup.names.iter().position(|n| *n == xn).unwrap(),
        setup.names.iter().position(|n| *n == yn).unwrap(),
    );
    let xs = pdw_limit::linspace(FREE[kx].1, FREE[kx].2, map_n);
    let ys = pdw_limit::linspace(FREE[ky].1, FREE[ky].2, map_n);
    let mut code = Array2::<u8>::zeros((map_n, map_n));
    let mut sections: Vec<Vec<Option<Vec<f64>>>> = vec![vec![None; map_n]; map_n];
    let mut mcsv = format!("{xn},{yn},verdict,max_abs_lambda,binding,relative_margin\n");
    for iy in 0..map_n {
        for ix in 0..map_n {
            let mut p = best.0.clone();
            p[kx] = xs[ix];
            p[ky] = ys[iy];
            let mut guesses: Vec<(String, Vec<f64>)> = Vec::new();
            for (jx, jy) in [(ix.wrapping_sub(1), iy), (ix, iy.wrapping_sub(1))] {
                if let Some(Some(s)) = sections.get(jy).and_then(|r| r.get(jx)) {
                    guesses.push(("neighbour".into(), s.clone()));
                }
            }
            if let Some(s) = &best.1.section {
                guesses.push(("best design".into(), s.clone()));
            }
            guesses.extend(setup.model_guesses.iter().cloned());
            let j = setup.judge(&setup.values_of(&p), &guesses);
            code[[iy, ix]] = j.code;
            sections[iy][ix] = j.section.clone().or(j.latched.clone());
            let _ = writeln!(
                mcsv,
                "{},{},{},{},\"{}\",{}",
                xs[ix],
                ys[iy],
                NAMES[j.code as usize],
                j.rho,
                j.binding.replace('"', "'"),
                j.relative
            );
        }
        eprintln!("map {xn} x {yn}: row {iy} done");
    }
    (code, mcsv, xs, ys)
}
