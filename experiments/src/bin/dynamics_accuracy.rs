//! Accuracy of the three planar forward-dynamics routes of `pdw-soa` against the number of
//! joints n: the O(n) articulated-body recursion (`aba`), CRBA + Cholesky
//! (`forward_dynamics_crba`) and the literal dense operator form `𝓜 = HᵀΦᵀMΦH` with LU
//! (`naive_forward_dynamics`), on seeded random planar revolute chains.
//!
//! Each method returns `q̈_m` for an applied torque `τ`. Its **backward error** is measured
//! independently with inverse dynamics (RNEA, seed eq. 2.62): `τ_check = 𝓜 q̈_m + C =
//! rnea(q, q̇, q̈_m)`, residual `r = τ_check − τ`, reported as `‖r‖/‖τ‖` and, scale-free, as
//! `‖r‖ / (ε (‖τ‖ + ‖C‖))` (C = Coriolis, centrifugal and gravity forces; ε = 2⁻⁵²). Its
//! **forward error** is bounded by `κ(𝓜)` times the backward error (Higham, *Accuracy and
//! Stability of Numerical Algorithms*, §7.1), so the 2-norm condition number
//! `κ(𝓜) = λ_max/λ_min` (faer's symmetric eigenvalues of the CRBA mass matrix) is listed, and
//! the methods' disagreement `‖q̈_m − q̈_aba‖/‖q̈_aba‖` shows the forward error actually seen.
//!
//! Time per call is not re-measured here: it is read from the criterion table in
//! `experiments/results/soa_scaling/soa_scaling.md`.

use faer::Side;
use pdw_experiments::{command, results_dir, sci, write_text, Table};
use pdw_soa::{
    aba, bias_forces, crba, forward_dynamics_crba, naive_forward_dynamics, rnea, Chain,
    ChainBuilder, Link, NaiveWorkspace, Workspace,
};
use std::fmt::Write as _;

const NAME: &str = "dynamics_accuracy";
const SIZES: [usize; 8] = [2, 3, 5, 8, 16, 32, 64, 128];
const CHAINS: usize = 24;
const SEED: u64 = 20_261_121;
const METHODS: [&str; 3] = ["aba", "crba + Cholesky", "naive + LU"];

/// SplitMix64 (Steele, Lea & Flood 2014): a small seeded generator, uniform in `[a, b)`.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self, a: f64, b: f64) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        a + (b - a) * ((z >> 11) as f64 / (1u64 << 53) as f64)
    }
    fn vec(&mut self, n: usize, a: f64) -> Vec<f64> {
        (0..n).map(|_| self.uniform(-a, a)).collect()
    }
}

/// Random planar revolute chain with the distribution of the criterion benchmark
/// (`benches/benches/soa.rs`): links 0.3–1.2 m, masses 0.5–3 kg, COM at 20–80 % of the link,
/// inertias 0.01–0.3 kg m², gravity 9.81 on slope 0.05.
fn random_chain(r: &mut Rng, n: usize) -> anyhow::Result<Chain> {
    let mut b = ChainBuilder::new().gravity(9.81).slope(0.05);
    for _ in 0..n {
        let len = r.uniform(0.3, 1.2);
        let ang = r.uniform(-0.5, 0.5);
        let to_next = [len * ang.sin(), -len * ang.cos()];
        let f = r.uniform(0.2, 0.8);
        b = b.revolute(Link {
            to_next,
            com: [f * to_next[0], f * to_next[1]],
            mass: r.uniform(0.5, 3.0),
            inertia: r.uniform(0.01, 0.3),
        });
    }
    Ok(b.build()?)
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn diff_norm(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len().is_multiple_of(2) {
        0.5 * (v[m - 1] + v[m])
    } else {
        v[m]
    }
}

fn max(v: &[f64]) -> f64 {
    v.iter().copied().fold(0.0, f64::max)
}

/// Least-squares slope of `log y` against `log x`.
fn loglog_slope(pts: &[(f64, f64)]) -> f64 {
    let l: Vec<(f64, f64)> = pts.iter().map(|(x, y)| (x.ln(), y.ln())).collect();
    pdw_experiments::fit_line(&l).1
}

/// Per-n statistics over the random chains.
struct Stats {
    n: usize,
    /// `[method][chain]` relative residual ‖r‖/‖τ‖.
    rel: [Vec<f64>; 3],
    /// `[method][chain]` residual in units of ε (‖τ‖ + ‖C‖).
    eps_units: [Vec<f64>; 3],
    /// `[method − 1][chain]` disagreement with aba, ‖q̈_m − q̈_aba‖/‖q̈_aba‖.
    fwd: [Vec<f64>; 2],
    cond: Vec<f64>,
    c_over_tau: Vec<f64>,
}

fn measure(n: usize) -> anyhow::Result<Stats> {
    let mut r = Rng(SEED ^ (n as u64).wrapping_mul(0x2545_F491_4F6C_DD1D));
    let mut s = Stats {
        n,
        rel: Default::default(),
        eps_units: Default::default(),
        fwd: Default::default(),
        cond: Vec::new(),
        c_over_tau: Vec::new(),
    };
    for _ in 0..CHAINS {
        let chain = random_chain(&mut r, n)?;
        let q = r.vec(n, 1.0);
        let qd = r.vec(n, 1.0);
        let tau = r.vec(n, 2.0);
        let mut ws = Workspace::new(&chain);
        let mut nws = NaiveWorkspace::new(&chain);
        let mut qdd = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        aba(&chain, &mut ws, &q, &qd, &tau, None, &mut qdd[0])?;
        forward_dynamics_crba(&chain, &mut ws, &q, &qd, &tau, None, &mut qdd[1])?;
        naive_forward_dynamics(&chain, &mut ws, &mut nws, &q, &qd, &tau, None, &mut qdd[2])?;
        let mut c = vec![0.0; n];
        bias_forces(&chain, &mut ws, &q, &qd, &mut c)?;
        let scale = norm(&tau) + norm(&c);
        let mut back = vec![0.0; n];
        for (m, qdd_m) in qdd.iter().enumerate() {
            rnea(&chain, &mut ws, &q, &qd, qdd_m, None, &mut back)?;
            let res = diff_norm(&back, &tau);
            s.rel[m].push(res / norm(&tau));
            s.eps_units[m].push(res / (f64::EPSILON * scale));
        }
        let a0 = norm(&qdd[0]);
        s.fwd[0].push(diff_norm(&qdd[1], &qdd[0]) / a0);
        s.fwd[1].push(diff_norm(&qdd[2], &qdd[0]) / a0);
        let mass = crba(&chain, &mut ws, &q)?;
        let ev = mass
            .self_adjoint_eigenvalues(Side::Lower)
            .map_err(|e| anyhow::anyhow!("eigenvalues of 𝓜 (n = {n}): {e:?}"))?;
        s.cond.push(ev[ev.len() - 1] / ev[0]);
        s.c_over_tau.push(norm(&c) / norm(&tau));
    }
    Ok(s)
}

/// Rows `n → [aba ns, crba ns, naive ns]` of the criterion table in `soa_scaling.md`.
fn read_timings() -> Vec<(usize, [f64; 3])> {
    let p =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("results/soa_scaling/soa_scaling.md");
    let Ok(text) = std::fs::read_to_string(p) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for line in text.lines() {
        let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
        if cells.len() != 9 {
            continue;
        }
        let Ok(n) = cells[0].parse::<usize>() else {
            continue;
        };
        let v: Vec<f64> = [1, 3, 5]
            .iter()
            .filter_map(|&i| cells[i].parse().ok())
            .collect();
        if v.len() == 3 && !out.iter().any(|(m, _)| *m == n) {
            out.push((n, [v[0], v[1], v[2]]));
        }
    }
    out
}

fn main() -> anyhow::Result<()> {
    faer::set_global_parallelism(faer::Par::Seq);
    let dir = results_dir(NAME)?;
    let stats: Vec<Stats> = SIZES
        .iter()
        .map(|&n| measure(n))
        .collect::<Result<_, _>>()?;

    let mut t = Table::new(&[
        "n",
        "κ(𝓜) median",
        "κ(𝓜) max",
        "‖C‖/‖τ‖ median",
        "aba ‖r‖/‖τ‖ med / max",
        "crba ‖r‖/‖τ‖ med / max",
        "naive ‖r‖/‖τ‖ med / max",
        "aba ‖r‖/ε(‖τ‖+‖C‖) med",
        "crba ‖r‖/ε(‖τ‖+‖C‖) med",
        "naive ‖r‖/ε(‖τ‖+‖C‖) med",
        "crba vs aba ‖Δq̈‖/‖q̈‖ max",
        "naive vs aba ‖Δq̈‖/‖q̈‖ max",
    ]);
    let mut s_rel: Vec<(String, Vec<(f64, f64)>)> = METHODS
        .iter()
        .map(|m| (format!("{m}: ‖r‖/‖τ‖ (median)"), Vec::new()))
        .collect();
    let mut s_eps: Vec<(String, Vec<(f64, f64)>)> = METHODS
        .iter()
        .map(|m| (format!("{m}: ‖r‖/ε(‖τ‖+‖C‖) (median)"), Vec::new()))
        .collect();
    let mut s_cond = vec![
        ("κ(M) median".to_string(), Vec::new()),
        ("crba vs aba ‖Δq̈‖/‖q̈‖ / ε (max)".to_string(), Vec::new()),
        ("naive vs aba ‖Δq̈‖/‖q̈‖ / ε (max)".to_string(), Vec::new()),
    ];
    for s in &stats {
        let n = s.n as f64;
        let mut med_rel = [0.0; 3];
        let mut med_eps = [0.0; 3];
        for m in 0..3 {
            med_rel[m] = median(&mut s.rel[m].clone());
            med_eps[m] = median(&mut s.eps_units[m].clone());
            s_rel[m].1.push((n, med_rel[m]));
            s_eps[m].1.push((n, med_eps[m]));
        }
        let cmed = median(&mut s.cond.clone());
        s_cond[0].1.push((n, cmed));
        s_cond[1].1.push((n, max(&s.fwd[0]) / f64::EPSILON));
        s_cond[2].1.push((n, max(&s.fwd[1]) / f64::EPSILON));
        t.row(vec![
            s.n.to_string(),
            sci(cmed),
            sci(max(&s.cond)),
            format!("{:.1}", median(&mut s.c_over_tau.clone())),
            format!("{} / {}", sci(med_rel[0]), sci(max(&s.rel[0]))),
            format!("{} / {}", sci(med_rel[1]), sci(max(&s.rel[1]))),
            format!("{} / {}", sci(med_rel[2]), sci(max(&s.rel[2]))),
            format!("{:.1}", med_eps[0]),
            format!("{:.1}", med_eps[1]),
            format!("{:.1}", med_eps[2]),
            sci(max(&s.fwd[0])),
            sci(max(&s.fwd[1])),
        ]);
        eprintln!(
            "n = {:3}: κ {cmed:.2e}; rel {:.2e} {:.2e} {:.2e}",
            s.n, med_rel[0], med_rel[1], med_rel[2]
        );
    }
    write_text(&dir, "accuracy.csv", &t.csv().replace(" / ", ";"))?;

    // Growth exponents ‖r‖ ∝ n^p for n ≥ 8.
    let growth = |pts: &[(f64, f64)]| {
        let tail: Vec<(f64, f64)> = pts
            .iter()
            .copied()
            .filter(|p| p.0 >= 8.0 && p.1 > 0.0)
            .collect();
        loglog_slope(&tail)
    };
    let p_rel: Vec<f64> = s_rel.iter().map(|s| growth(&s.1)).collect();
    let p_eps: Vec<f64> = s_eps.iter().map(|s| growth(&s.1)).collect();
    let p_cond = growth(&s_cond[0].1);
    let p_c = growth(
        &stats
            .iter()
            .map(|s| (s.n as f64, median(&mut s.c_over_tau.clone())))
            .collect::<Vec<_>>(),
    );

    let mut series = s_rel.clone();
    series.extend(s_eps.iter().cloned());
    pdw_store::plot_lines(
        dir.join("accuracy_vs_n.png"),
        "Forward dynamics backward error vs n (residual by RNEA, median of 24 chains)",
        "joints n",
        "relative residual",
        &series,
        true,
        true,
    )?;
    pdw_store::plot_lines(
        dir.join("conditioning_vs_n.png"),
        "Mass-matrix condition number and forward disagreement vs n",
        "joints n",
        "κ(M)  |  ‖Δq̈‖/(ε‖q̈‖)",
        &s_cond,
        true,
        true,
    )?;
    let timings = read_timings();
    if !timings.is_empty() {
        let names = ["aba (ns)", "crba + Cholesky (ns)", "naive + LU (ns)"];
        let ts: Vec<(String, Vec<(f64, f64)>)> = (0..3)
            .map(|m| {
                (
                    names[m].to_string(),
                    timings.iter().map(|(n, v)| (*n as f64, v[m])).collect(),
                )
            })
            .collect();
        pdw_store::plot_lines(
            dir.join("time_vs_n.png"),
            "Forward dynamics time per call vs n (criterion, soa_scaling)",
            "joints n",
            "ns per call",
            &ts,
            true,
            true,
        )?;
    }

    // Speed next to accuracy.
    let mut side = Table::new(&[
        "n",
        "aba ns",
        "aba ‖r‖/‖τ‖",
        "crba ns",
        "crba ‖r‖/‖τ‖",
        "naive ns",
        "naive ‖r‖/‖τ‖",
        "κ(𝓜)",
    ]);
    for (i, s) in stats.iter().enumerate() {
        let tm = timings.iter().find(|(n, _)| *n == s.n).map(|x| x.1);
        let f = |m: usize| tm.map_or("—".to_string(), |v| format!("{:.0}", v[m]));
        side.row(vec![
            s.n.to_string(),
            f(0),
            sci(s_rel[0].1[i].1),
            f(1),
            sci(s_rel[1].1[i].1),
            f(2),
            sci(s_rel[2].1[i].1),
            sci(s_cond[0].1[i].1),
        ]);
    }

    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Forward dynamics: accuracy against n, next to time against n\n\n\
         Reproduce: `{}` (about a second; the times are read from \
         `experiments/results/soa_scaling/soa_scaling.md`, measured by \
         `cargo bench -p pdw-benches --bench soa`).\n",
        command(NAME)
    );
    let _ = writeln!(
        md,
        "{CHAINS} seeded random planar revolute chains per n (the benchmark's distribution: \
         links 0.3–1.2 m, masses 0.5–3 kg, q, q̇ ∈ [−1, 1], τ ∈ [−2, 2], gravity on slope 0.05). \
         Each method's q̈ is checked by inverse dynamics (RNEA): r = rnea(q, q̇, q̈_m) − τ. \
         Growth exponents p (‖r‖ ∝ n^p, least squares over n = 8…128): \
         ‖r‖/‖τ‖ — aba {:.2}, crba {:.2}, naive {:.2}; ‖r‖/ε(‖τ‖+‖C‖) — aba {:.2}, crba {:.2}, \
         naive {:.2}; κ(𝓜) {:.2}; ‖C‖/‖τ‖ {:.2}.\n",
        p_rel[0], p_rel[1], p_rel[2], p_eps[0], p_eps[1], p_eps[2], p_cond, p_c
    );
    let _ = writeln!(
        md,
        "## Speed and accuracy side by side\n\n{}",
        side.markdown()
    );
    let _ = writeln!(md, "## Accuracy in detail\n\n{}", t.markdown());
    write_text(&dir, "table.md", &md)?;
    Ok(())
}
