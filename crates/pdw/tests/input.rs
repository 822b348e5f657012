//! The value syntaxes of the front ends: accepted forms and refused ones, with messages that
//! name the value.

use pdw::input::*;

#[test]
fn slope_accepts_radians_and_degrees() {
    assert_eq!(parse_slope("0.009").unwrap(), 0.009);
    let d = parse_slope("3deg").unwrap();
    assert!((d - 3.0f64.to_radians()).abs() < 1e-15);
    assert!(parse_slope("2").is_err());
    assert!(parse_slope("nan").is_err());
    assert!(parse_slope("abc").unwrap_err().0.contains("abc"));
}

/// `3°`, `3deg`, ` 3 deg` are one slope, 3π/180 rounded once: the compass preset's
/// 0.05235987755982988 (Goswami et al. 1998's 3°), as a spec's `{ value = 3, unit = "deg" }`.
#[test]
fn slope_in_degrees_is_the_same_number_in_every_form() {
    const THREE_DEG: f64 = 0.05235987755982988;
    for form in ["3deg", "3°", " 3 deg", "3 °", "3.0deg", " 3deg "] {
        assert_eq!(parse_slope(form), Ok(THREE_DEG), "{form:?}");
    }
    assert_eq!(parse_slope("0.05rad"), Ok(0.05));
    assert_eq!(parse_slope("0.05 rad"), Ok(0.05));
    assert_eq!(parse_slope("-3°"), Ok(-THREE_DEG));
    assert_eq!(parse_slope_for("3°", "--set slope"), Ok(THREE_DEG));
    assert_eq!(
        parse_assignment("slope=3°"),
        Ok(("slope".into(), THREE_DEG))
    );
    assert_eq!(parse_sweep("slope=1deg:3°:3").map(|s| s.hi), Ok(THREE_DEG));
    let units = pdw_walkers::units::to_base(3.0, "deg", pdw_walkers::units::UnitSystem::Si);
    assert_eq!(units.map(|u| u.0), Ok(THREE_DEG));
    // refused, naming the value and the forms accepted
    for (bad, part) in [
        ("3 furlong", "`furlong`, not an angle"),
        ("3cm", "`cm`, not an angle"),
        ("3degx", "3degx"),
        ("deg", "'deg' is not a number"),
        ("90deg", "outside (-pi/2, pi/2)"),
    ] {
        let e = parse_slope(bad).unwrap_err().0;
        assert!(e.contains(part), "{bad:?}: {e}");
        assert!(e.contains("3deg, 3°"), "{bad:?}: {e}");
    }
}

/// A slope of 1 (meant as 1°) is 57°: the warning names the degrees and the likely meaning.
#[test]
fn a_slope_far_steeper_than_walking_is_named_in_degrees() {
    assert_eq!(
        pdw::model::steep_slope_warning(1.0).as_deref(),
        Some(
            "slope 1 rad = 57.3° is far steeper than passive walking (≲ 0.3 rad); did you mean \
             1deg?"
        )
    );
    assert!(pdw::model::steep_slope_warning(-0.5)
        .unwrap()
        .contains("-28.6°"));
    assert_eq!(pdw::model::steep_slope_warning(0.3), None);
    assert_eq!(pdw::model::steep_slope_warning(0.0504), None);
    assert_eq!(pdw::model::steep_slope_warning(f64::NAN), None);
}

#[test]
fn grid_axis_sweep_shard_reject_bad_input() {
    assert_eq!(parse_grid("401x201").unwrap(), (401, 201));
    assert!(parse_grid("0x5").is_err());
    assert!(parse_grid("12").is_err());
    let e = parse_grid_for("--map-grid", "0x0").unwrap_err().0;
    assert!(e.starts_with("--map-grid: '0'"), "{e}");
    assert_eq!(
        parse_axis("theta=0.15:0.25", "--x").unwrap(),
        AxisRange {
            name: "theta".into(),
            lo: 0.15,
            hi: 0.25
        }
    );
    assert!(parse_axis("theta=0.25:0.15", "--x")
        .unwrap_err()
        .0
        .contains("inverted"));
    assert!(parse_axis("theta", "--x").is_err());
    let sw = parse_sweep("slope=0.001:0.019:400").unwrap();
    assert_eq!((sw.lo, sw.hi, sw.n), (0.001, 0.019, 400));
    assert!(parse_sweep("slope=0.001:0.019:1").is_err());
    assert_eq!(parse_shard("2/4").unwrap(), (2, 4));
    assert!(parse_shard("4/4").is_err());
    assert_eq!(parse_assignment("mass=2.5").unwrap(), ("mass".into(), 2.5));
    assert!(parse_assignment("=2").is_err());
    assert_eq!(parse_guess("0.2,-0.2").unwrap(), vec![0.2, -0.2]);
}
