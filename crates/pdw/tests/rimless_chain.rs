//! The rimless wheel on random slopes against its closed form: the wheel's stride on a line of
//! any slope is a pendulum's energy balance and a plastic impact, so the terrain stride, the
//! Markov chain and the Monte Carlo walkers can all be checked against a chain this file
//! builds from that closed form alone (its own map, grid, interpolation and solve).
//!
//! The closed-form stride (Coleman; Tedrake, *Underactuated Robotics* ch. 4; Byl & Tedrake,
//! IJRR 28(8), 2009, §3): with `ψ` the stance spoke's angle from the vertical (downhill
//! positive), a wheel that landed on a line inclined `s'` starts at `ψ₀ = s' − α`; it lands on
//! the next line, inclined `s`, at `ψ₁ = s + α`. Energy per unit mass gives
//! `ω(ψ)² = ω₀² + 2 (g/l)(cos ψ₀ − cos ψ)`; the wheel rolls back (falls) when `ω²` reaches 0 on
//! `[ψ₀, ψ₁]`, i.e. at the point of that interval nearest the top `ψ = 0`. The spoke impact
//! keeps `cos 2α` of the rate: `ω' = cos 2α · ω(ψ₁)`.

use pdw::mfpt::{self, MfptPlan};
use pdw_limit::markov::gauss_hermite;
use pdw_limit::terrain::{SlopeTerrain, SlopeWalk};

/// The preset wheel (8 spokes, l = 1 m, g = 9.81) on its preset mean slope, σ = 0.5°.
const MEAN: f64 = 0.08;
const SD_DEG: f64 = 0.5;

struct Wheel {
    alpha: f64,
    g_over_l: f64,
}

impl Wheel {
    fn of(m: &pdw::BuiltModel) -> Self {
        let p = |n: &str| m.params.iter().find(|q| q.0 == n).unwrap().1;
        Wheel {
            alpha: std::f64::consts::PI / p("n_spokes"),
            g_over_l: p("g") / p("l"),
        }
    }

    /// The rate after landing on a line inclined `s`, from rate `w0` just after landing on a
    /// line inclined `s_prev`; `None` when the wheel rolls back.
    fn stride(&self, s_prev: f64, w0: f64, s: f64) -> Option<f64> {
        let (psi0, psi1) = (s_prev - self.alpha, s + self.alpha);
        if w0 <= 0.0 || psi1 <= psi0 {
            return None;
        }
        let w2 = |psi: f64| w0 * w0 + 2.0 * self.g_over_l * (psi0.cos() - psi.cos());
        let top = 0.0f64.clamp(psi0, psi1);
        if w2(top) <= 0.0 {
            return None;
        }
        Some((2.0 * self.alpha).cos() * w2(psi1).sqrt())
    }
}

#[test]
fn the_terrain_stride_of_the_rimless_wheel_is_its_closed_form_map() {
    let m = pdw::build("rimless", &[("slope".to_string(), MEAN)]).unwrap();
    let wheel = Wheel::of(&m);
    let at = mfpt::model_at(&m);
    let walk = SlopeWalk::new(&at, MEAN, mfpt::default_integrator()).unwrap();
    let mut integ = walk.integrator(2).unwrap();
    let (mut checked, mut falls) = (0, 0);
    for k in 0..400u64 {
        // Slopes within ±3° of the mean, rates across the fall threshold and beyond.
        let u = |j| pdw_limit::terrain::uniform(7, k, j, 0);
        let s_prev = MEAN + (u(0) - 0.5) * 6f64.to_radians();
        let s = MEAN + (u(1) - 0.5) * 6f64.to_radians();
        let w0 = 0.6 + 1.2 * u(2);
        // Mean-frame state just after landing on `s_prev`: θ = −α in that line's frame.
        let x = [-wheel.alpha + s_prev - MEAN, w0];
        let got = walk.stride(&mut integ, &x, s).unwrap();
        match wheel.stride(s_prev, w0, s) {
            Some(w1) => {
                assert!(
                    got.outcome.is_ok(),
                    "{k}: {:?} but closed form {w1}",
                    got.outcome
                );
                assert!(
                    (got.post[1] - w1).abs() < 1e-8,
                    "{k}: {} vs {w1}",
                    got.post[1]
                );
                let theta = -wheel.alpha + s - MEAN;
                assert!((got.post[0] - theta).abs() < 1e-9, "{k}: {:?}", got.post);
                checked += 1;
            }
            None => {
                assert!(
                    !got.outcome.is_ok(),
                    "{k}: walked on but closed form rolls back"
                );
                falls += 1;
            }
        }
    }
    assert!(
        checked > 100 && falls > 50,
        "{checked} strides, {falls} falls"
    );
}

/// The closed-form chain: layer `j` = the quadrature node of the last landing slope, a
/// uniform grid of `n_rate` rates on `[lo, hi]` per layer, the landing rate spread over its two
/// neighbouring grid rates by linear weights.
struct ClosedChain {
    slopes: Vec<(f64, f64)>,
    lo: f64,
    h: f64,
    n_rate: usize,
}

impl ClosedChain {
    fn new(nodes: usize, n_rate: usize, lo: f64, hi: f64) -> Self {
        let (z, w) = gauss_hermite(nodes);
        let sd = SD_DEG.to_radians();
        let slopes = z.iter().zip(&w).map(|(z, w)| (MEAN + sd * z, *w)).collect();
        let h = (hi - lo) / (n_rate - 1) as f64;
        ClosedChain {
            slopes,
            lo,
            h,
            n_rate,
        }
    }

    /// The transition row from slope `s_prev` and rate `w0`: (state, probability) pairs.
    fn row(&self, wheel: &Wheel, s_prev: f64, w0: f64) -> Vec<(usize, f64)> {
        let mut r = Vec::new();
        for (l, (s, p)) in self.slopes.iter().enumerate() {
            let Some(w1) = wheel.stride(s_prev, w0, *s) else {
                continue;
            };
            let t = (w1 - self.lo) / self.h;
            assert!(
                t >= 0.0 && t < (self.n_rate - 1) as f64,
                "rate {w1} off the grid"
            );
            let k = t.floor() as usize;
            let f = t - k as f64;
            r.push((l * self.n_rate + k, p * (1.0 - f)));
            r.push((l * self.n_rate + k + 1, p * f));
        }
        r
    }

    /// The quasi-stationary MFPT `1/(π·fall) − 1` (heel strikes): `π` the dominant left
    /// eigenvector of `Q` by power iteration (its convergence is set by the gap to the second
    /// eigenvalue, not by `1 − λ`, so it reaches MFPTs no iteration on `m = 1 + Q m` can).
    fn quasi_stationary_mfpt(&self, wheel: &Wheel) -> f64 {
        let n = self.slopes.len() * self.n_rate;
        let rows: Vec<Vec<(usize, f64)>> = (0..n)
            .map(|i| {
                let (j, k) = (i / self.n_rate, i % self.n_rate);
                self.row(wheel, self.slopes[j].0, self.lo + k as f64 * self.h)
            })
            .collect();
        let fall: Vec<f64> = rows
            .iter()
            .map(|r| (1.0 - r.iter().map(|e| e.1).sum::<f64>()).max(0.0))
            .collect();
        let mut pi = vec![1.0 / n as f64; n];
        let mut last = 0.0;
        for _ in 0..100_000 {
            let mut next = vec![0.0; n];
            for (i, r) in rows.iter().enumerate() {
                for (j, q) in r {
                    next[*j] += pi[i] * q;
                }
            }
            let total: f64 = next.iter().sum();
            next.iter_mut().for_each(|v| *v /= total);
            pi = next;
            let rate: f64 = pi.iter().zip(&fall).map(|(p, f)| p * f).sum();
            if (rate - last).abs() < 1e-9 * rate {
                break;
            }
            last = rate;
        }
        1.0 / last - 1.0
    }

    /// MFPT (heel strikes) from the gait `w_star` of the mean slope, on a line of the mean
    /// slope: `m = 1 + Q m` by Gauss–Seidel sweeps until the largest change is 1e-10 of `m`.
    fn mfpt(&self, wheel: &Wheel, w_star: f64) -> f64 {
        let n = self.slopes.len() * self.n_rate;
        let rows: Vec<Vec<(usize, f64)>> = (0..n)
            .map(|i| {
                let (j, k) = (i / self.n_rate, i % self.n_rate);
                self.row(wheel, self.slopes[j].0, self.lo + k as f64 * self.h)
            })
            .collect();
        let mut m = vec![1.0; n];
        for _ in 0..1_000_000 {
            let mut change: f64 = 0.0;
            for (i, r) in rows.iter().enumerate() {
                let v = 1.0 + r.iter().map(|(j, q)| q * m[*j]).sum::<f64>();
                change = change.max((v - m[i]).abs());
                m[i] = v;
            }
            let top = m.iter().cloned().fold(0.0, f64::max);
            if change < 1e-10 * top {
                break;
            }
        }
        self.row(wheel, MEAN, w_star)
            .iter()
            .map(|(j, q)| q * m[*j])
            .sum()
    }
}

/// The engine's chain against the closed-form chain on the same 11-node quadrature: they
/// differ only in how the section is meshed, so they agree within both meshes' refinement
/// differences.
#[test]
fn the_engines_markov_chain_of_the_rimless_wheel_matches_the_closed_form_chain() {
    let m = pdw::build("rimless", &[("slope".to_string(), MEAN)]).unwrap();
    let wheel = Wheel::of(&m);
    let (x0, s0) = mfpt::start(&m).unwrap();
    let (lo, hi) = (0.5, 1.8);
    let fine = ClosedChain::new(11, 2601, lo, hi).mfpt(&wheel, s0[0]);
    let half = ClosedChain::new(11, 1301, lo, hi).mfpt(&wheel, s0[0]);
    let plan = plan();
    let pool = pool();
    let bounds = mfpt::visited_box(&m, &plan, &x0, &pool).unwrap();
    let engine = |mesh| {
        let c = mfpt::ChainPlan {
            nodes: 11,
            mesh,
            bounds: None,
            section: Default::default(),
            layout: Default::default(),
        };
        mfpt::chain(&m, &plan, &c, &bounds, &x0, &pool)
            .unwrap()
            .mfpt
    };
    let (coarse, finer) = (engine(400), engine(800));
    eprintln!("closed form {fine} (h×2: {half}); engine {finer} (mesh/2: {coarse})");
    let tol = (finer - coarse).abs() + (fine - half).abs();
    assert!(
        (finer - fine).abs() < tol,
        "engine {finer} vs closed form {fine} (tol {tol})"
    );
}

/// The chain on the mid-stance section (no layers; [`pdw_limit::mid_stance`]) against the
/// closed-form chain on the same 11-node quadrature, which is meshed just after heel strike:
/// the same discrete-terrain walk seen at another instant of the stride, so both converge to
/// one MFPT. Both converge slowly (linear interpolation across where the wheel starts to roll
/// back): the closed form gives 114.54, 115.25, 115.43 on 2601, 5201, 10401 rates, the
/// mid-stance chain 116.06, 115.82, 115.55 on meshes of 200, 800, 3200; so the finest of each
/// are compared, within both meshes' refinement differences.
#[test]
fn the_mid_stance_chain_of_the_rimless_wheel_matches_the_closed_form_chain() {
    let m = pdw::build("rimless", &[("slope".to_string(), MEAN)]).unwrap();
    let wheel = Wheel::of(&m);
    let (x0, s0) = mfpt::start(&m).unwrap();
    let (lo, hi) = (0.5, 1.8);
    let fine = ClosedChain::new(11, 10401, lo, hi).mfpt(&wheel, s0[0]);
    let half = ClosedChain::new(11, 5201, lo, hi).mfpt(&wheel, s0[0]);
    let c = mfpt::ChainPlan {
        nodes: 11,
        mesh: 1600,
        bounds: None,
        section: mfpt::ChainSection::MidStance,
        layout: Default::default(),
    };
    let pair = mfpt::chain_pair(&m, &plan(), &c, &x0, &pool(), &|_| {}).unwrap();
    let (coarse, finer) = (pair.results[0].mfpt, pair.results[1].mfpt);
    eprintln!("closed form {fine} (h×2: {half}); mid-stance {finer} (mesh/2: {coarse})");
    let tol = (finer - coarse).abs() + (fine - half).abs();
    assert!(
        (finer - fine).abs() < tol,
        "mid-stance {finer} vs closed form {fine} (tol {tol})"
    );
}

/// Where the mid-stance chain fails, visibly: Byl & Tedrake's 8° slope at σ = 1° (40 nodes,
/// the extreme ones near 0° and 16°). At mid-stance the hub's rate has no floor but zero, and
/// the wheels that barely pass the top on the flattest nodes land ever closer to it: the
/// widening passes end with landings still below the box, so box exits are a visible share of
/// the absorption (the front ends' box warning) and the quasi-stationary MFPT falls short of
/// the closed-form chain's ≈ 8·10¹¹ — the section just after heel strike, whose rates are
/// bounded below by the impact, holds every landing (the test above it).
#[test]
fn the_mid_stance_chain_reports_the_landings_its_box_cannot_hold() {
    let mean = 8f64.to_radians();
    let m = pdw::build("rimless", &[("slope".to_string(), mean)]).unwrap();
    let wheel = Wheel::of(&m);
    let (x0, _) = mfpt::start(&m).unwrap();
    let mut plan = plan();
    plan.terrain.mean = mean;
    plan.terrain.sd = 1f64.to_radians();
    let c = mfpt::ChainPlan {
        nodes: 40,
        mesh: 200,
        bounds: None,
        section: mfpt::ChainSection::MidStance,
        layout: Default::default(),
    };
    let pair = mfpt::chain_pair(&m, &plan, &c, &x0, &pool(), &|_| {}).unwrap();
    assert_eq!(
        pair.chain_box.passes,
        mfpt::HULL_PASSES,
        "{:?}",
        pair.chain_box
    );
    let mut cc = ClosedChain::new(40, 2201, 0.4, 2.6);
    cc.slopes = mfpt::terrain_nodes(&plan, 40);
    let closed = cc.quasi_stationary_mfpt(&wheel);
    for r in &pair.results {
        let absorbed = r.out_of_mesh + r.fall_per_step;
        assert!(r.out_of_mesh > 0.01 * absorbed, "{r:?}");
        assert!(r.mfpt_lambda < closed, "{r:?} vs closed form {closed}");
        assert!(r.mfpt_lambda > 1e10, "{r:?}");
    }
}

/// Gauss–Hermite quadrature converges slowly here (the next stride's value jumps where the
/// wheel starts to roll back, so the integrand over the landing slope is discontinuous): 11
/// nodes are several per cent off. With 41 nodes the closed-form chain agrees with 2000 Monte
/// Carlo walkers within 3 standard errors plus its own grid and quadrature changes.
#[test]
fn the_converged_closed_form_chain_agrees_with_the_monte_carlo_walkers() {
    let m = pdw::build("rimless", &[("slope".to_string(), MEAN)]).unwrap();
    let wheel = Wheel::of(&m);
    let (x0, s0) = mfpt::start(&m).unwrap();
    let (lo, hi) = (0.5, 1.8);
    let n41 = ClosedChain::new(41, 651, lo, hi).mfpt(&wheel, s0[0]);
    let n41_fine = ClosedChain::new(41, 1301, lo, hi).mfpt(&wheel, s0[0]);
    let n21 = ClosedChain::new(21, 1301, lo, hi).mfpt(&wheel, s0[0]);
    let own = (n41_fine - n41).abs() + (n41_fine - n21).abs();
    let (_, mc) = mfpt::run(&m, &plan(), &x0, &pool(), &|_| {}).unwrap();
    eprintln!(
        "closed form 41 nodes {n41_fine} (grid/2 {n41}, 21 nodes {n21}); Monte Carlo {} ± {}",
        mc.restricted_mean, mc.restricted_stderr
    );
    assert_eq!(mc.censored, 0);
    assert!(own < 0.05 * n41_fine, "{n41_fine} {n41} {n21}");
    let tol = 3.0 * mc.restricted_stderr + own;
    assert!(
        (mc.restricted_mean - n41_fine).abs() < tol,
        "Monte Carlo {} vs closed form {n41_fine} (tol {tol})",
        mc.restricted_mean
    );
}

/// At σ = 1° on Byl & Tedrake's 8° slope the walkers of a short run stay in a narrow band, and
/// a chain meshed over that band measures the time to leave it (its absorption is almost all
/// landings outside the mesh). The widened box holds every landing: its absorption is falls,
/// and its quasi-stationary MFPT — near 10¹², far beyond any Monte Carlo — agrees with the
/// closed-form chain's (power iteration on its own grid) within both meshes' refinement.
#[test]
fn the_chains_widened_box_makes_falls_not_box_exits_absorb() {
    let mean = 8f64.to_radians();
    let m = pdw::build("rimless", &[("slope".to_string(), mean)]).unwrap();
    let wheel = Wheel::of(&m);
    let (x0, _) = mfpt::start(&m).unwrap();
    let mut plan = plan();
    plan.terrain.mean = mean;
    plan.terrain.sd = 1f64.to_radians();
    let pool = pool();
    let c = |mesh| mfpt::ChainPlan {
        nodes: 40,
        mesh,
        bounds: None,
        section: Default::default(),
        layout: Default::default(),
    };
    let visited = mfpt::visited_box(&m, &plan, &x0, &pool).unwrap();
    let narrow = mfpt::chain(&m, &plan, &c(200), &visited, &x0, &pool).unwrap();
    assert!(
        narrow.out_of_mesh > 10.0 * narrow.fall_per_step,
        "{narrow:?}"
    );
    let cb = mfpt::chain_box(&m, &plan, &c(200), &x0, &pool, &|_| {}).unwrap();
    assert!(cb.passes > 0 && cb.out_share > 0.9, "{cb:?}");
    let wide = cb.bounds;
    let run = |n| mfpt::chain(&m, &plan, &c(n), &wide, &x0, &pool).unwrap();
    let (coarse, fine) = (run(200), run(400));
    for r in [&coarse, &fine] {
        assert!(r.out_of_mesh < 1e-6 * r.fall_per_step, "{r:?}");
    }
    let closed = |n_rate| {
        let mut cc = ClosedChain::new(40, n_rate, 0.4, 2.6);
        cc.slopes = mfpt::terrain_nodes(&plan, 40);
        cc.quasi_stationary_mfpt(&wheel)
    };
    let (c1, c2) = (closed(1101), closed(2201));
    eprintln!("narrow box {narrow:?}\nwide {coarse:?} {fine:?}\nclosed form {c1} (grid/2) {c2}");
    assert!(fine.mfpt_lambda > 1e10, "{fine:?}");
    let tol = (fine.mfpt_lambda - coarse.mfpt_lambda).abs() + (c2 - c1).abs();
    assert!(
        (fine.mfpt_lambda - c2).abs() < tol,
        "engine {} vs closed form {c2} (tol {tol})",
        fine.mfpt_lambda
    );
}

fn plan() -> MfptPlan {
    MfptPlan {
        terrain: SlopeTerrain {
            mean: MEAN,
            sd: SD_DEG.to_radians(),
            seed: 1,
            kind: pdw_limit::terrain::TerrainKind::Slope,
            dist: Default::default(),
        },
        walkers: 2000,
        max_strides: 20_000,
        integrator: mfpt::default_integrator(),
        // the walkers integrate their strides: the closed-form chain here checks the engine's
        // integrated walk (its own closed form is checked in `mfpt_closed_form`)
        stride_map: mfpt::StrideMap::Integrated,
    }
}

fn pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
}

/// The plan of [`plan`] with the standardised draws of `dist` and standard deviation `sd`.
fn plan_with(dist: pdw_limit::terrain::TerrainDist, sd: f64, walkers: usize) -> MfptPlan {
    let mut p = plan();
    p.terrain.dist = dist;
    p.terrain.sd = sd;
    p.walkers = walkers;
    p
}

/// The engine's chain at `mesh` and `2 mesh` over the walkers' box (11 quadrature nodes).
fn engine_pair(m: &pdw::BuiltModel, plan: &MfptPlan, x0: &[f64], mesh: usize) -> (f64, f64) {
    let c = mfpt::ChainPlan {
        nodes: 11,
        mesh,
        bounds: None,
        section: Default::default(),
        layout: Default::default(),
    };
    let pair = mfpt::chain_pair(m, plan, &c, x0, &pool(), &|_| {}).unwrap();
    (pair.results[0].mfpt, pair.results[1].mfpt)
}

/// On uniform slopes (σ = 0.5°, half-width √3 σ) the engine's chain on its Gauss–Legendre
/// nodes and the closed-form chain on 41 of them agree with 2000 Monte Carlo walkers within 3
/// standard errors plus each chain's own mesh change.
#[test]
fn the_chain_on_uniform_slopes_agrees_with_the_monte_carlo_walkers() {
    let m = pdw::build("rimless", &[("slope".to_string(), MEAN)]).unwrap();
    let wheel = Wheel::of(&m);
    let (x0, s0) = mfpt::start(&m).unwrap();
    let plan = plan_with(
        pdw_limit::terrain::TerrainDist::Uniform,
        SD_DEG.to_radians(),
        2000,
    );
    let (_, mc) = mfpt::run(&m, &plan, &x0, &pool(), &|_| {}).unwrap();
    assert_eq!(mc.censored, 0);
    let (coarse, fine) = engine_pair(&m, &plan, &x0, 200);
    let closed = |n_rate| {
        let mut cc = ClosedChain::new(41, n_rate, 0.5, 1.8);
        cc.slopes = mfpt::terrain_nodes(&plan, 41);
        cc.mfpt(&wheel, s0[0])
    };
    let (c1, c2) = (closed(651), closed(1301));
    eprintln!(
        "uniform: Monte Carlo {} ± {}; engine {coarse} / {fine}; closed form {c1} / {c2}",
        mc.restricted_mean, mc.restricted_stderr
    );
    for (chain, own) in [(fine, (fine - coarse).abs()), (c2, (c2 - c1).abs())] {
        let tol = 3.0 * mc.restricted_stderr + own;
        assert!(
            (mc.restricted_mean - chain).abs() < tol,
            "Monte Carlo {} vs chain {chain} (tol {tol})",
            mc.restricted_mean
        );
    }
}

/// A file of the values −1 and +1 is the two-point distribution: its quadrature is those two
/// slopes with weight ½ each, the engine's chain on it matches a closed-form chain built on
/// the two slopes directly, and both agree with 4000 Monte Carlo walkers that draw from the
/// file within 3 standard errors plus the meshes' changes.
#[test]
fn a_file_of_minus_one_and_one_is_the_two_point_distribution() {
    let path = std::env::temp_dir().join(format!("pdw-two-point-{}.txt", std::process::id()));
    std::fs::write(&path, "# two values\n-1\n1 # up\n\n").unwrap();
    let flags = mfpt::MfptFlags {
        terrain: "--terrain",
        sd: "--sd",
        mean: "--mean",
        walkers: "--walkers",
        max_steps: "--max-strides",
        dist: "--dist",
    };
    let dist = mfpt::parse_dist(&format!("file:{}", path.display()), &flags).unwrap();
    std::fs::remove_file(&path).unwrap();
    let sd = 1f64.to_radians();
    let plan = plan_with(dist, sd, 4000);
    assert_eq!(
        mfpt::terrain_nodes(&plan, 11),
        vec![(MEAN - sd, 0.5), (MEAN + sd, 0.5)]
    );
    let m = pdw::build("rimless", &[("slope".to_string(), MEAN)]).unwrap();
    let wheel = Wheel::of(&m);
    let (x0, s0) = mfpt::start(&m).unwrap();
    let (_, mc) = mfpt::run(&m, &plan, &x0, &pool(), &|_| {}).unwrap();
    assert_eq!(mc.censored, 0);
    let (coarse, fine) = engine_pair(&m, &plan, &x0, 200);
    let closed = |n_rate| {
        let mut cc = ClosedChain::new(1, n_rate, 0.3, 2.2);
        cc.slopes = vec![(MEAN - sd, 0.5), (MEAN + sd, 0.5)];
        cc.mfpt(&wheel, s0[0])
    };
    let (c1, c2) = (closed(1901), closed(3801));
    eprintln!(
        "two points: Monte Carlo {} ± {}; engine {coarse} / {fine}; closed form {c1} / {c2}",
        mc.restricted_mean, mc.restricted_stderr
    );
    let own = (fine - coarse).abs() + (c2 - c1).abs();
    assert!(
        (fine - c2).abs() < own.max(1e-3 * c2),
        "engine {fine} vs {c2}"
    );
    let tol = 3.0 * mc.restricted_stderr + own;
    assert!(
        (mc.restricted_mean - c2).abs() < tol,
        "Monte Carlo {} vs closed form {c2} (tol {tol})",
        mc.restricted_mean
    );
}

/// The chain whose strides are taken in closed form (`--stride-map auto` on the rimless wheel,
/// [`pdw_limit::terrain::SlopeWalk::with_closed_form`]) against the same chain with every stride
/// integrated: the same quadrature, mesh and box, so they differ only by the integrator's
/// tolerance (1e-10 here) in each landing, far below the chain's own discretisation.
#[test]
fn the_chain_in_closed_form_strides_equals_the_integrated_chain() {
    let m = pdw::build("rimless", &[("slope".to_string(), MEAN)]).unwrap();
    let (x0, _) = mfpt::start(&m).unwrap();
    let pool = pool();
    let integrated = plan();
    let closed = MfptPlan {
        stride_map: mfpt::StrideMap::ClosedForm,
        ..plan()
    };
    let bounds = mfpt::visited_box(&m, &integrated, &x0, &pool).unwrap();
    let c = mfpt::ChainPlan {
        nodes: 11,
        mesh: 400,
        bounds: None,
        section: Default::default(),
        layout: Default::default(),
    };
    let a = mfpt::chain(&m, &integrated, &c, &bounds, &x0, &pool).unwrap();
    let b = mfpt::chain(&m, &closed, &c, &bounds, &x0, &pool).unwrap();
    eprintln!("integrated {a:?}\nclosed form {b:?}");
    assert_eq!(a.states, b.states);
    assert!(
        (a.mfpt - b.mfpt).abs() < 1e-6 * a.mfpt,
        "{} vs {}",
        a.mfpt,
        b.mfpt
    );
    assert!(
        (a.lambda - b.lambda).abs() < 1e-9,
        "{} vs {}",
        a.lambda,
        b.lambda
    );
    assert!(
        (a.fall_per_step - b.fall_per_step).abs() < 1e-6 * a.fall_per_step,
        "{} vs {}",
        a.fall_per_step,
        b.fall_per_step
    );
    // the closed-form chain is not a copy of the integrated one: some landing moved
    assert_ne!(a.mfpt.to_bits(), b.mfpt.to_bits());
}

/// The quadrature check's verdict ([`mfpt::quadrature_check`]: the coarse mesh with twice the
/// terrain's nodes) against the converged MFPT of the closed-form chain written here (its own
/// map, grid and solve; 41 nodes on 1301 rates, 118.395, which 2601 rates move by 0.02 % and 44
/// nodes by 0.08 %): the engine warns at the default 11 nodes, whose MFPT is more than
/// [`mfpt::QUADRATURE_MAX`] from the converged one (1.4 %), and not at 22, whose MFPT is within
/// it; with 11 the doubled quadrature's MFPT is the closer of the two. (The closed-form chain's
/// own change under doubling is no verdict for the engine's: its grid spans rates down to the
/// wheel's roll-back, where linear interpolation across the jump makes its quadrature converge
/// more slowly — 2.5 % from 11 to 22 nodes and 1.5 % from 22 to 44, against the engine's 1.5 %
/// and 0.3 % on the walkers' box.)
#[test]
fn the_quadrature_check_warns_where_the_chain_is_not_converged_in_its_nodes() {
    let m = pdw::build("rimless", &[("slope".to_string(), MEAN)]).unwrap();
    let wheel = Wheel::of(&m);
    let (x0, s0) = mfpt::start(&m).unwrap();
    let converged = ClosedChain::new(41, 1301, 0.5, 1.8).mfpt(&wheel, s0[0]);
    let plan = MfptPlan {
        stride_map: mfpt::StrideMap::ClosedForm,
        ..plan()
    };
    let pool = pool();
    let mut warned = Vec::new();
    for nodes in [11, 22] {
        let c = mfpt::ChainPlan {
            nodes,
            mesh: 400,
            bounds: None,
            section: Default::default(),
            layout: Default::default(),
        };
        let pair = mfpt::chain_pair(&m, &plan, &c, &x0, &pool, &|_| {}).unwrap();
        let q = pair
            .quadrature
            .expect("a grid's chain checks its quadrature");
        let base = pair.results[0].mfpt;
        let off = (base - converged).abs() / converged;
        eprintln!(
            "{nodes} nodes: engine {base} -> {} ({:.4}); converged {converged} ({off:.4} off) {:?}",
            q.mfpt, q.change, q.warning
        );
        assert_eq!((q.nodes, q.mesh), (2 * nodes, 400));
        assert_eq!(
            q.warning.is_some(),
            off > mfpt::QUADRATURE_MAX,
            "{nodes} nodes: {off} from the converged chain, check change {}",
            q.change
        );
        if let Some(w) = &q.warning {
            assert!(
                w.contains(&format!("give nodes {} or more", 2 * nodes)),
                "{w}"
            );
            assert!((q.mfpt - converged).abs() < (base - converged).abs());
        }
        warned.push(q.warning.is_some());
    }
    assert_eq!(
        warned,
        [true, false],
        "11 nodes not converged, 22 converged"
    );
}
