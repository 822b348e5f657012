//! The integrator check (`pdw::integrator::gait_drift`): every command's default integrator
//! carries every preset's gait back to itself within the check's tolerance, so a default run
//! never warns; a loose one does not.

use pdw::integrator::{gait_drift, integrator_warning, CHECK_GAIT_TOL};
use pdw_hybrid::Options;

/// Each command's default integrator.
fn defaults() -> Vec<(&'static str, Options)> {
    vec![
        (
            "fixedpoint",
            pdw_limit::gaits::default_integrator(pdw::mfpt::GAIT_TOL),
        ),
        ("follow", Options::dop853(1e-13)),
        ("basin", pdw_limit::BasinOptions::default_integrator()),
        ("mfpt", pdw::mfpt::default_integrator()),
        ("simulate", pdw::simulate::default_integrator()),
        ("gsn", pdw::gsn::default_integrator()),
    ]
}

#[test]
fn the_default_integrators_resolve_every_presets_gait() {
    let mut checked = 0;
    for info in pdw_walkers::models() {
        let name = info.name.as_str();
        let m = pdw::build(name, &[]).unwrap();
        let guesses = pdw::gaits::model_guesses(m.walker.as_ref());
        let (found, _) = pdw::gaits::search(&m, &guesses, pdw::mfpt::GAIT_TOL).unwrap();
        let Some(gait) = pdw::gaits::selected(&found) else {
            continue;
        };
        for (command, o) in defaults() {
            let d = gait_drift(&m, o, &gait.fp.section, CHECK_GAIT_TOL).unwrap();
            assert_eq!(d, None, "{name}, {command}'s default integrator");
        }
        checked += 1;
    }
    assert!(checked >= 4, "{checked} presets with a gait");
}

#[test]
fn a_loose_integrator_is_named_in_the_warning() {
    let m = pdw::build("compass", &[]).unwrap();
    for o in [
        Options {
            rtol: 1.0,
            atol: 1.0,
            ..Options::dop853(1.0)
        },
        Options::rk4(1.5),
    ] {
        let w = integrator_warning(&m, &o).unwrap().expect("a warning");
        assert!(
            w.contains(&pdw::integrator_text(&o)) && w.contains("cannot resolve a stride"),
            "{w}"
        );
    }
    assert_eq!(
        integrator_warning(&m, &pdw::mfpt::default_integrator()).unwrap(),
        None
    );
}
