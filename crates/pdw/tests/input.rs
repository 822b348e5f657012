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
