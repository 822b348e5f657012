//! One deterministic disturbance: the walk after one step of another height or slope, and the
//! bisection for the largest one survived, against independent walks and the rimless wheel's
//! closed-form step map.

use pdw::disturb;
use pdw_limit::terrain::TerrainKind;

const GAMMA: f64 = 0.08;
const G: f64 = 9.81;

fn wheel() -> pdw::BuiltModel {
    pdw::build("rimless", &[("slope".to_string(), GAMMA)]).unwrap()
}

/// Steps an 8-spoke wheel (l = 1) completes from its rolling gait when step 1's foothold is `d`
/// lower and every later one level, by the closed-form map (module docs of the rimless wheel):
/// the hub must pass its apex `θ = −γ` when the step contains it.
fn closed_form_steps(d: f64, steps: usize) -> usize {
    let a = std::f64::consts::PI / 8.0;
    let reach = 2.0 * a.sin();
    let mut omega = (4.0 * G * a.sin() * GAMMA.sin()).sqrt() / (2.0 * a).tan();
    let mut th_plus = -a;
    for k in 0..steps {
        let h = if k == 0 { d } else { 0.0 };
        let th_minus = a + (h / reach).asin();
        let lowest = if th_plus < -GAMMA && -GAMMA < th_minus {
            1.0
        } else {
            (th_minus + GAMMA).cos().max((th_plus + GAMMA).cos())
        };
        if omega * omega <= 2.0 * G * (lowest - (th_plus + GAMMA).cos()) {
            return k;
        }
        let w2 = omega * omega + 2.0 * G * ((th_plus + GAMMA).cos() - (th_minus + GAMMA).cos());
        omega = (2.0 * a).cos() * w2.sqrt();
        th_plus = th_minus - 2.0 * a;
    }
    steps
}

#[test]
fn a_small_step_decays_back_to_the_gait_at_the_rimless_multiplier() {
    let m = wheel();
    let r = disturb::respond(
        &m,
        TerrainKind::StepDown,
        0.01,
        40,
        pdw::mfpt::default_integrator(),
    )
    .unwrap();
    assert!(r.survived());
    // the rimless wheel's return map ω' = cos 2α √(ω² + c) has the multiplier
    // cos² 2α ω*/ω'(…) = cos² 2α at its fixed point: the deviation shrinks by it per step
    let lam = (std::f64::consts::PI / 4.0).cos().powi(2);
    for k in 2..8 {
        let ratio = r.deviation[k + 1] / r.deviation[k];
        assert!(
            (ratio - lam).abs() < 0.02,
            "step {k}: ratio {ratio} vs {lam}"
        );
    }
    assert!(r.returned_after.unwrap() > 5);
    assert!(r.deviation[r.returned_after.unwrap() - 1] < disturb::RETURN_TOL);
}

#[test]
fn the_largest_step_up_brackets_the_edge_and_matches_the_closed_form_map() {
    let m = wheel();
    let integ = pdw::mfpt::default_integrator();
    let tol = 1e-5;
    let (ok, fell) =
        disturb::largest(&m, TerrainKind::StepDown, -1.0, tol, 1.0, 50, integ).unwrap();
    assert!(ok < 0.0 && fell < ok && ok - fell <= tol, "{ok} {fell}");
    // independent walks at both ends of the bracket
    let at = |d| disturb::respond(&m, TerrainKind::StepDown, d, 50, integ).unwrap();
    assert!(at(ok).survived());
    assert!(!at(fell).survived());
    assert!(!at(ok - tol).survived() || ok - tol > fell);
    // the closed-form map's own edge, bisected to 1e-12
    let (mut lo, mut hi) = (0.0, -0.5);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if closed_form_steps(mid, 50) == 50 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    assert!(
        (ok - lo).abs() <= tol + 1e-8,
        "bisected {ok}, closed form {lo}"
    );
}
