//! Failure modes, each triggered on purpose and diagnosed by the engine (not a crash, not a
//! silently wrong number): a fixed-step RK4 whose step straddles a heel strike; Newton from a
//! bad guess; chaos where no period-one gait attracts; a rimless wheel on a slope too shallow to
//! keep rolling; non-finite states and absurd parameters.

use pdw_experiments::{command, results_dir, sci, write_text, Table};
use pdw_hybrid::Options;
use pdw_limit::{
    find_fixed_point, orbit_diagram, NewtonOptions, OrbitOptions, OrbitStart, StrideMap,
};
use pdw_walkers::{Walker, WalkerError};
use std::fmt::Write as _;

fn simplest(g: f64) -> Result<Box<dyn Walker>, WalkerError> {
    pdw_walkers::build("simplest", &[("slope", g)])
}

fn one_line(s: impl std::fmt::Display) -> String {
    let t = s.to_string().replace('\n', " ").replace('|', "/");
    if t.chars().count() > 260 {
        format!("{}…", t.chars().take(260).collect::<String>())
    } else {
        t
    }
}

fn main() -> anyhow::Result<()> {
    faer::set_global_parallelism(faer::Par::Seq);
    let dir = results_dir("failure_modes")?;
    let mut md = String::new();
    let _ = writeln!(md, "# Failure modes, triggered and diagnosed\n");
    let _ = writeln!(md, "Reproduce: `{}`.\n", command("failure_modes"));
    let w = simplest(0.009)?;
    rk4_straddles_heel_strike(w.as_ref(), &mut md)?;
    let map = StrideMap::new(w.as_ref(), Options::dop853(1e-12))?;
    newton_from_bad_guesses(&map, &mut md);
    chaos(&mut md)?;
    rimless_on_shallow_slopes(&mut md)?;
    absurd_inputs(w.as_ref(), &map, &mut md);
    write_text(&dir, "table.md", &md)?;
    Ok(())
}

/// Step 1: Fixed-step RK4 with steps as long as a large part of the stride: one stride of the
/// simplest walker `w` (γ = 0.009) from its fixed point, and Newton from Garcia's guess, at
/// each step against DOP853 1e-14.
fn rk4_straddles_heel_strike(w: &dyn Walker, md: &mut String) -> anyhow::Result<()> {
    let reference = StrideMap::new(w, Options::dop853(1e-14))?;
    let s_star = [0.20031090054425046, -0.19983247300495477];
    let p_ref = reference.stride(&s_star)?;
    let mut t = Table::new(&[
        "RK4 step h",
        "steps per stride",
        "stride outcome",
        "period",
        "|P(s*) − P_ref(s*)|∞",
        "fixed point from Garcia's guess",
    ]);
    for h in [0.01, 0.1, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0] {
        let map = StrideMap::new(w, Options::rk4(h))?;
        let st = map.stride(&s_star)?;
        let err = if st.outcome.is_ok() {
            st.next
                .iter()
                .zip(&p_ref.next)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        } else {
            f64::NAN
        };
        let fp = match find_fixed_point(
            &map,
            &w.gait_guesses()[0].section,
            &NewtonOptions::default(),
        ) {
            Ok(fp) => format!(
                "found, |s − s*|∞ = {}",
                sci(fp
                    .section
                    .iter()
                    .zip(&s_star)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max))
            ),
            Err(e) => format!("error: {}", one_line(e)),
        };
        t.row(vec![
            format!("{h}"),
            format!("{:.1}", p_ref.period / h),
            st.outcome.to_string(),
            format!("{:.6}", st.period),
            sci(err),
            fp,
        ]);
    }
    let _ = writeln!(
        md,
        "## 1. Fixed-step RK4 whose step straddles the heel strike\n\nSimplest walker, γ = \
         0.009, one stride from the fixed point s* (reference DOP853 1e-14: period {:.10}). \
         With h ≥ 1.5 (fewer than 3 steps per stride) one step can span both the mid-stance \
         scuffing crossing of φ − 2θ and the heel strike; the engine samples each step's \
         Hermite interpolant at 4 interior points, so the admissible crossing is still located, \
         but the map is then so inaccurate that Newton stops with a line-search failure, the \
         residual history and the last iterate instead of returning a wrong gait. At h = 4 the \
         RK4 solution itself is wrong enough that the stance leg reverses: reported as a fall.\n\n{}",
        p_ref.period,
        t.markdown()
    );
    Ok(())
}

/// Step 2: Newton from bad guesses on the simplest walker's stride `map` (γ = 0.009, DOP853
/// 1e-12).
fn newton_from_bad_guesses(map: &StrideMap, md: &mut String) {
    let mut t = Table::new(&["guess (θ, θ̇)", "what it is", "engine's answer"]);
    for (g, what) in [
        (
            vec![0.5, -0.1],
            "legs far apart, slow: the walker falls backward in the first stride",
        ),
        (vec![0.2, -0.5], "much too fast: falls forward"),
        (vec![0.15, -0.15], "inside the basin but 0.05 off"),
        (vec![0.1937, -0.2039], "near the unstable short-period gait"),
        (vec![f64::NAN, -0.2], "non-finite guess"),
        (vec![0.2], "wrong dimension"),
    ] {
        let r = find_fixed_point(map, &g, &NewtonOptions::default());
        let ans = match r {
            Ok(fp) => format!(
                "converged in {} iterations to ({:.10}, {:.10}), residual {}, {}",
                fp.iterations,
                fp.section[0],
                fp.section[1],
                sci(fp.residual),
                if fp.stable { "stable" } else { "unstable" }
            ),
            Err(e) => format!("error: {}", one_line(e)),
        };
        t.row(vec![format!("{g:?}"), what.into(), ans]);
    }
    let _ = writeln!(md, "\n## 2. Newton from bad guesses\n\n{}", t.markdown());
}

/// Step 3: Chaos: no attracting period-one gait. Brute-force orbits (2000 transient strides, 256
/// recorded, 2 threads) beside Newton's period-one fixed point at five slopes of the cascade.
fn chaos(md: &mut String) -> anyhow::Result<()> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    let gammas = [0.0150, 0.0160, 0.0180, 0.0185, 0.0189];
    let starts: Vec<Vec<f64>> = gammas
        .iter()
        .map(|&g| {
            pdw_walkers::simplest::GarciaGait::LongPeriod
                .section_guess(g)
                .to_vec()
        })
        .collect();
    let oo = OrbitOptions {
        transient: 2000,
        record: 256,
        chunk: 1,
        max_period: 64,
        ..OrbitOptions::default()
    };
    let cols = orbit_diagram(
        &simplest,
        &gammas,
        &OrbitStart::PerParam(starts),
        &oo,
        &pool,
    )?;
    let mut t = Table::new(&[
        "γ",
        "period-one fixed point (Newton)",
        "orbit after 2000 strides",
        "spread of θ over 256 strides",
    ]);
    for (c, &g) in cols.iter().zip(&gammas) {
        let wg = simplest(g)?;
        let m = StrideMap::new(wg.as_ref(), Options::dop853(1e-13))?;
        let fp = match find_fixed_point(
            &m,
            &pdw_walkers::simplest::GarciaGait::LongPeriod.section_guess(g),
            &NewtonOptions::default(),
        ) {
            Ok(fp) => format!(
                "exists, {}: |λ|max = {:.4}",
                if fp.stable { "stable" } else { "unstable" },
                fp.multipliers[0].modulus()
            ),
            Err(e) => format!("error: {}", one_line(e)),
        };
        let th: Vec<f64> = c.points.iter().map(|p| p[0]).collect();
        let spread = th.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
            - th.iter().cloned().fold(f64::INFINITY, f64::min);
        let orbit = match (&c.fall, c.period) {
            (Some((k, o)), _) => format!("fell at stride {k}: {o}"),
            (None, Some(p)) => format!("period {p}"),
            (None, None) => "no period ≤ 64 (chaotic or quasi-periodic)".into(),
        };
        t.row(vec![format!("{g}"), fp, orbit, sci(spread)]);
    }
    let _ = writeln!(md, "\n## 3. Chaos (simplest walker)\n\n{}", t.markdown());
    Ok(())
}

/// Step 4: Rimless wheel on a slope too shallow to keep rolling: up to 200 strides from each
/// start ω₀, and whether a rolling fixed point exists.
fn rimless_on_shallow_slopes(md: &mut String) -> anyhow::Result<()> {
    let mut t = Table::new(&[
        "slope",
        "ω₀",
        "strides completed",
        "how the run ended",
        "ω sequence (first strides)",
    ]);
    for (slope, w0) in [(0.08, 1.0), (0.01, 3.0), (0.01, 1.0), (0.0, 3.0)] {
        let wh = pdw_walkers::build("rimless", &[("slope", slope)])?;
        let m = StrideMap::new(wh.as_ref(), Options::dop853(1e-12))?;
        let mut s = vec![w0];
        let mut seq = vec![w0];
        let mut end = String::from("still rolling after 200 strides");
        let mut k = 0;
        for i in 0..200 {
            let st = m.stride(&s)?;
            if !st.outcome.is_ok() {
                end = format!("stride {i}: {} — stopped (rolls back)", st.outcome);
                break;
            }
            s = st.next;
            k += 1;
            if seq.len() < 6 {
                seq.push(s[0]);
            }
        }
        let guesses = wh.gait_guesses();
        let fp_note = if guesses.is_empty() {
            "; no rolling fixed point exists (ω* ≤ ω₁)".to_string()
        } else {
            format!("; rolling fixed point ω* = {:.6}", guesses[0].section[0])
        };
        t.row(vec![
            format!("{slope}"),
            format!("{w0}"),
            k.to_string(),
            format!("{end}{fp_note}"),
            seq.iter()
                .map(|v| format!("{v:.4}"))
                .collect::<Vec<_>>()
                .join(", "),
        ]);
    }
    let _ = writeln!(
        md,
        "\n## 4. Rimless wheel on a shallow slope (8 spokes)\n\n{}",
        t.markdown()
    );
    Ok(())
}

/// Step 5: Non-finite states and absurd parameters: models, integrators (with the simplest
/// walker `w`) and strides (of `map`) that must be refused or reported, each answer in words.
fn absurd_inputs(w: &dyn Walker, map: &StrideMap, md: &mut String) {
    let mut t = Table::new(&["input", "engine's answer"]);
    let cases: Vec<(&str, String)> = vec![
        (
            "simplest, slope = NaN",
            match simplest(f64::NAN) {
                Ok(_) => "accepted".into(),
                Err(e) => format!("rejected: {}", one_line(e)),
            },
        ),
        (
            "simplest, slope = 2 rad",
            match simplest(2.0) {
                Ok(_) => "accepted".into(),
                Err(e) => format!("rejected: {}", one_line(e)),
            },
        ),
        (
            "compass, leg_mass = −1",
            match pdw_walkers::build("compass", &[("leg_mass", -1.0)]) {
                Ok(_) => "accepted".into(),
                Err(e) => format!("rejected: {}", one_line(e)),
            },
        ),
        (
            "compass, gravity = ∞",
            match pdw_walkers::build("compass", &[("gravity", f64::INFINITY)]) {
                Ok(_) => "accepted".into(),
                Err(e) => format!("rejected: {}", one_line(e)),
            },
        ),
        (
            "compass, knee = 3 (unknown parameter)",
            match pdw_walkers::build("compass", &[("knee", 3.0)]) {
                Ok(_) => "accepted".into(),
                Err(e) => format!("rejected: {}", one_line(e)),
            },
        ),
        (
            "model \"biped\"",
            match pdw_walkers::build("biped", &[]) {
                Ok(_) => "accepted".into(),
                Err(e) => format!("rejected: {}", one_line(e)),
            },
        ),
        (
            "DOPRI5 with rtol = 1e-20",
            match StrideMap::new(w, Options::dopri5(1e-20)) {
                Ok(_) => "accepted".into(),
                Err(e) => format!("rejected: {}", one_line(e)),
            },
        ),
        (
            "RK4 with h = 0",
            match StrideMap::new(w, Options::rk4(0.0)) {
                Ok(_) => "accepted".into(),
                Err(e) => format!("rejected: {}", one_line(e)),
            },
        ),
        (
            "stride from (NaN, −0.2)",
            match map.stride(&[f64::NAN, -0.2]) {
                Ok(st) => format!("stride outcome: {}", st.outcome),
                Err(e) => format!("error: {}", one_line(e)),
            },
        ),
        (
            "stride from (0.2, −1e300)",
            match map.stride(&[0.2, -1e300]) {
                Ok(st) => format!("stride outcome: {}", st.outcome),
                Err(e) => format!("error: {}", one_line(e)),
            },
        ),
        (
            "stride from (0.2, ∞)",
            match map.stride(&[0.2, f64::INFINITY]) {
                Ok(st) => format!("stride outcome: {}", st.outcome),
                Err(e) => format!("error: {}", one_line(e)),
            },
        ),
    ];
    for (i, a) in cases {
        t.row(vec![i.into(), a]);
    }
    let _ = writeln!(
        md,
        "\n## 5. Non-finite states and absurd parameters\n\n{}",
        t.markdown()
    );
}
