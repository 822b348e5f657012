//! The walk's setup shared by `pdw-sweep simulate` and Python's `simulate`: the starts against
//! Garcia et al. 1998's two period-one gaits of the simplest walker at γ = 0.009 (values from
//! REFERENCES §1, held here), and the refusals, each naming the front end's option.

use pdw::simulate::{self, GaitKind, SimulateFlags, Start, StartError, Walk};
use pdw_hybrid::Options;

const FLAGS: SimulateFlags = SimulateFlags {
    steps: "--steps",
    dt_out: "--dt-out",
    state: "--state",
    gait: "--gait",
    rk4_step: "--rk4-step",
};

/// Garcia's stable ("long period") gait at γ = 0.009: θ*, θ̇*, τ.
const STABLE: (f64, f64, f64) = (0.20031090049483, -0.19983247291764, 3.88);
/// Garcia's unstable ("short period") gait at γ = 0.009.
const UNSTABLE: (f64, f64, f64) = (0.19393736960624, -0.20386692731962, 3.10);

fn simplest() -> pdw::BuiltModel {
    pdw::build("simplest", &[("slope".to_string(), 0.009)]).unwrap()
}

fn start_ok(m: &pdw::BuiltModel, s: Start) -> Walk {
    match simulate::start(m, &s, &FLAGS) {
        Ok(w) => w,
        Err(e) => panic!("{e:?}"),
    }
}

#[test]
fn a_walk_from_either_gait_starts_on_garcias_fixed_point_and_stays_on_it() {
    let m = simplest();
    for (kind, (theta, rate, tau)) in [(GaitKind::Stable, STABLE), (GaitKind::Unstable, UNSTABLE)] {
        let walk = start_ok(&m, Start::Gait(kind));
        assert!((walk.x0[0] - theta).abs() < 1e-9, "{kind:?} {:?}", walk.x0);
        assert!((walk.x0[1] - rate).abs() < 1e-9, "{kind:?} {:?}", walk.x0);
        let period = walk.period.expect("a gait has a period");
        assert!((period - tau).abs() < 0.01, "{kind:?}: period {period}");
        assert!(walk.label.starts_with(kind.name()), "{}", walk.label);
        // Three steps from the fixed point land on it again (the unstable one too: its largest
        // multiplier ≈ 4 grows the 1e-12 residual to ~1e-10 in three steps).
        let opts = simulate::options(&m, 3, None, simulate::default_integrator());
        let tr = simulate::run(&m, &walk, &opts).unwrap();
        assert!(tr.outcome.is_ok(), "{kind:?}: {}", tr.outcome);
        assert_eq!(tr.steps_done, 3);
        let ds = m.walker.section_dim();
        for p in tr.section.chunks(ds) {
            assert!(
                (p[0] - theta).abs() < 1e-8 && (p[1] - rate).abs() < 1e-8,
                "{p:?}"
            );
        }
    }
}

#[test]
fn a_state_of_the_wrong_length_is_refused_naming_the_option() {
    let m = simplest();
    match simulate::start(&m, &Start::State(vec![0.2, -0.2, 0.4]), &FLAGS) {
        Err(StartError::Input(e)) => assert!(e.0.starts_with("--state: "), "{}", e.0),
        other => panic!("{other:?}"),
    }
    // section coordinates are lifted to the full state
    let walk = start_ok(&m, Start::State(vec![STABLE.0, STABLE.1]));
    assert_eq!(walk.x0.len(), m.walker.dim());
    assert_eq!(walk.period, None);
}

#[test]
fn bad_requests_are_refused_naming_the_option() {
    let e = simulate::check_request(0, None, &FLAGS).unwrap_err().0;
    assert!(e.starts_with("--steps: 0"), "{e}");
    for h in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = simulate::check_request(3, Some(h), &FLAGS).unwrap_err().0;
        assert!(e.starts_with("--dt-out: "), "{e}");
    }
    assert!(simulate::check_request(3, Some(0.01), &FLAGS).is_ok());
    let e = GaitKind::parse("stabel", "gait").unwrap_err().0;
    assert_eq!(e, "gait: 'stabel' is not one of stable, unstable");
    assert_eq!(
        GaitKind::parse("unstable", "gait").unwrap(),
        GaitKind::Unstable
    );
}

/// A walk from a gait whose period and output spacing (or rk4 step) would record more samples
/// than the budget is refused before it runs, naming the option that sets the spacing; a walk
/// from a state (no period known) or with adaptive output is left to the integrator's bound.
#[test]
fn a_walk_that_cannot_fit_its_samples_is_refused_before_it_runs() {
    let m = simplest();
    let walk = Walk {
        x0: vec![STABLE.0, STABLE.1, 2.0 * STABLE.0, 0.0],
        label: "test".into(),
        period: Some(4.0),
    };
    // spacings and period exact in binary: 10 steps × 16 samples per stride = 160
    let mut opts = simulate::options(&m, 10, Some(0.25), simulate::default_integrator());
    opts.max_samples = 160;
    assert!(simulate::check_samples(&walk, &opts, &FLAGS).is_ok());
    opts.max_samples = 159;
    let e = simulate::check_samples(&walk, &opts, &FLAGS).unwrap_err().0;
    assert!(e.starts_with("--dt-out: 10 steps"), "{e}");
    let mut rk4 = simulate::options(&m, 10, None, Options::rk4(0.125));
    rk4.max_samples = 319;
    let e = simulate::check_samples(&walk, &rk4, &FLAGS).unwrap_err().0;
    assert!(e.starts_with("--rk4-step: "), "{e}");
    let adaptive = simulate::options(&m, 10, None, simulate::default_integrator());
    assert!(simulate::check_samples(&walk, &adaptive, &FLAGS).is_ok());
    let from_state = Walk {
        period: None,
        ..walk
    };
    assert!(simulate::check_samples(&from_state, &opts, &FLAGS).is_ok());
}
