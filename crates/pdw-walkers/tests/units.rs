//! Units in spec files mean what they say: a value with a unit is converted into the spec's
//! base unit (`deg` → rad, `cm` → m), an unknown unit is refused naming the parameter, the unit
//! and the units accepted, and the shipped models' numbers do not change by a bit.

use pdw_hybrid::{HybridSystem, Scratch};
use pdw_walkers::{ChainWalker, Walker, WalkerSpec};

/// Every walker built from `a` and `b` has the same parameters and flow, bit for bit.
fn assert_same_walker(a: &ChainWalker, b: &ChainWalker, what: &str) {
    let bits = |w: &ChainWalker| -> Vec<(String, u64)> {
        w.param_values()
            .into_iter()
            .map(|(n, v)| (n, v.to_bits()))
            .collect()
    };
    assert_eq!(bits(a), bits(b), "{what}: parameters");
    let mut ws = Scratch::new();
    let x = [0.25, -0.5, -1.0, 0.6];
    let (mut fa, mut fb) = ([0.0; 4], [0.0; 4]);
    a.flow(&mut ws, 0, &x, &mut fa);
    b.flow(&mut ws, 0, &x, &mut fb);
    assert_eq!(fa.map(f64::to_bits), fb.map(f64::to_bits), "{what}: flow");
}

fn compass_with(old: &str, new: &str) -> Result<ChainWalker, String> {
    let text = pdw_walkers::preset_text("compass").unwrap();
    assert!(text.contains(old), "{old}");
    let text = text.replace(old, new);
    WalkerSpec::from_toml(&text, "my.toml")
        .and_then(ChainWalker::from_spec)
        .map_err(|e| e.to_string())
}

#[test]
fn a_slope_in_degrees_gives_the_walker_of_its_value_in_radians() {
    let preset = pdw_walkers::presets::compass(&[]).unwrap();
    let deg = compass_with(
        "value = 0.05235987755982988, unit = \"rad\"",
        "value = 3, unit = \"deg\"",
    )
    .unwrap();
    assert_same_walker(&deg, &preset, "3 deg");
    let sign = compass_with(
        "value = 0.05235987755982988, unit = \"rad\"",
        "value = 3.0, unit = \"°\"",
    )
    .unwrap();
    assert_same_walker(&sign, &preset, "3 °");
    // the table lists the converted value in its base unit
    let t = WalkerSpec::from_toml(
        &pdw_walkers::preset_text("compass").unwrap().replace(
            "value = 0.05235987755982988, unit = \"rad\"",
            "value = 3, unit = \"deg\"",
        ),
        "my.toml",
    )
    .unwrap()
    .param_table();
    let i = t.names.iter().position(|n| n == "slope").unwrap();
    assert_eq!(
        (t.values[i], t.units[i].as_str()),
        (0.05235987755982988, "rad")
    );
}

#[test]
fn lengths_and_masses_with_a_prefix_convert_in_an_si_spec() {
    let preset = pdw_walkers::presets::compass(&[]).unwrap();
    let cm = compass_with(
        "a = { value = 0.5, unit = \"m\"",
        "a = { value = 50, unit = \"cm\"",
    )
    .unwrap();
    assert_same_walker(&cm, &preset, "a = 50 cm");
    let g = compass_with(
        "leg_mass = { value = 5.0, unit = \"kg\"",
        "leg_mass = { value = 5000, unit = \"g\"",
    )
    .unwrap();
    assert_same_walker(&g, &preset, "leg_mass = 5000 g");
    let gravity = compass_with(
        "gravity = { value = 9.81, unit = \"m/s^2\"",
        "gravity = { value = 981, unit = \"cm/s^2\"",
    )
    .unwrap();
    assert_same_walker(&gravity, &preset, "gravity = 981 cm/s^2");
    // not by accident: 50 m is another walker
    let m = compass_with(
        "a = { value = 0.5, unit = \"m\"",
        "a = { value = 50, unit = \"m\"",
    );
    assert!(m.is_err() || m.unwrap().param_values() != preset.param_values());
}

#[test]
fn an_unknown_unit_is_refused_naming_the_parameter_the_unit_and_the_units_accepted() {
    let e = compass_with(
        "a = { value = 0.5, unit = \"m\"",
        "a = { value = 0.5, unit = \"furlong\"",
    )
    .unwrap_err();
    for part in [
        "my.toml",
        "parameters.a.unit",
        "\"furlong\"",
        "`furlong` is not a unit",
        "units accepted: rad, deg, °",
        "cm",
        "L, M, T",
    ] {
        assert!(e.contains(part), "{part:?} missing in: {e}");
    }
    // a prefix cannot be converted into a model's own units (the kneed preset's L, M, T)
    let text = pdw_walkers::preset_text("kneed").unwrap().replace(
        "a1 = { value = 0.375, unit = \"L\"",
        "a1 = { value = 37.5, unit = \"cm\"",
    );
    let e = WalkerSpec::from_toml(&text, "k.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("parameters.a1.unit") && e.contains("`cm` cannot"),
        "{e}"
    );
    // a spec built in code is checked when it is resolved
    let mut spec =
        WalkerSpec::from_toml(pdw_walkers::preset_text("compass").unwrap(), "c").unwrap();
    spec.parameters.get_mut("b").unwrap().unit = "parsec".into();
    let e = ChainWalker::from_spec(spec).unwrap_err().to_string();
    assert!(
        e.contains("parameters.b.unit") && e.contains("parsec"),
        "{e}"
    );
}

/// The shipped model files (`models/*.toml`) and the docs' example keep their units and their
/// numbers bit for bit: every unit they use is a base unit of the table.
#[test]
fn every_shipped_model_keeps_its_numbers_and_units() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        n += 1;
        let text = std::fs::read_to_string(&path).unwrap();
        let raw: toml::Table = text.parse().unwrap();
        let spec = WalkerSpec::from_file(&path).unwrap();
        let t = spec.param_table();
        for (name, p) in raw["parameters"].as_table().unwrap() {
            let i = t.names.iter().position(|n| n == name).unwrap();
            let value = p["value"].as_float().unwrap();
            assert_eq!(t.values[i].to_bits(), value.to_bits(), "{path:?} {name}");
            assert_eq!(t.units[i], p["unit"].as_str().unwrap(), "{path:?} {name}");
        }
        ChainWalker::from_spec(spec).unwrap();
    }
    assert_eq!(
        n, 6,
        "models/ holds compass, kneed, kneed_latched, seed5, seed5_latched, seed5_walking"
    );
    // the example of docs/models.md
    let doc = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/models.md"),
    )
    .unwrap();
    let start = doc.find("# my_kneed.toml").unwrap();
    let example = &doc[start..start + doc[start..].find("```").unwrap()];
    let spec = WalkerSpec::from_toml(example, "my_kneed.toml").unwrap();
    let t = spec.param_table();
    assert_eq!(t.get("slope"), Some(0.0504));
    assert_eq!(t.get("hip_mass"), Some(0.5));
    ChainWalker::from_spec(spec).unwrap();
}

/// The seed5 preset with `old` replaced by `new`, built.
fn seed5_with(old: &str, new: &str) -> Result<ChainWalker, String> {
    let text = pdw_walkers::preset_text("seed5").unwrap();
    assert!(text.contains(old), "{old}");
    WalkerSpec::from_toml(&text.replace(old, new), "my.toml")
        .and_then(ChainWalker::from_spec)
        .map_err(|e| e.to_string())
}

fn assert_refused(e: Result<ChainWalker, String>, parts: &[&str]) {
    let Err(e) = e else {
        panic!("accepted, expected a refusal naming {parts:?}")
    };
    for part in parts {
        assert!(e.contains(part), "{part:?} missing in: {e}");
    }
}

#[test]
fn a_unit_of_another_quantity_than_its_parameters_role_is_refused_naming_both() {
    // 572.96 deg is 10 rad: it was taken as the hip's 10 kg
    assert_refused(
        compass_with(
            "hip_mass = { value = 10.0, unit = \"kg\"",
            "hip_mass = { value = 572.96, unit = \"deg\"",
        ),
        &[
            "parameters.hip_mass.unit",
            "unit `deg` is an angle, hip_mass is a mass (kg, g, …)",
        ],
    );
    // a force is not a mass
    assert_refused(
        compass_with(
            "leg_mass = { value = 5.0, unit = \"kg\"",
            "leg_mass = { value = 49.05, unit = \"N\"",
        ),
        &[
            "parameters.leg_mass.unit",
            "unit `N` is a force, leg_mass is a mass (kg, g, …)",
            "segments[0].mass",
        ],
    );
    // a slope in metres, a stride time budget in metres
    assert_refused(
        compass_with(
            "value = 0.05235987755982988, unit = \"rad\"",
            "value = 0.05, unit = \"m\"",
        ),
        &["unit `m` is a length, slope is an angle (rad, deg, °, …)"],
    );
    assert_refused(
        compass_with(
            "max_stride_time = { value = 5.0, unit = \"s\"",
            "max_stride_time = { value = 5.0, unit = \"m\"",
        ),
        &["unit `m` is a length, max_stride_time is a time (s, ms, …)"],
    );
    // a length in radians: alone, and in a sum with a length
    assert_refused(
        seed5_with(
            "shank_length = { value = 2.0, unit = \"m\"",
            "shank_length = { value = 2.0, unit = \"rad\"",
        ),
        &[
            "parameters.shank_length.unit",
            "unit `rad` is an angle, shank_length is a length (m, cm, mm, …)",
        ],
    );
    assert_refused(
        compass_with(
            "a = { value = 0.5, unit = \"m\"",
            "a = { value = 0.5, unit = \"rad\"",
        ),
        &[
            "segments[0].length",
            "\"a + b\"",
            "`+` between an angle and a length (a in `rad`, b in `m`)",
        ],
    );
    // the kneed preset's own units: a mass in L
    let text = pdw_walkers::preset_text("kneed").unwrap().replace(
        "hip_mass = { value = 0.5, unit = \"M\"",
        "hip_mass = { value = 0.5, unit = \"L\"",
    );
    let e = WalkerSpec::from_toml(&text, "k.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("unit `L` is a length, hip_mass is a mass (M, …)"),
        "{e}"
    );
    // a dimensionless parameter where a mass is expected, and a knee mode in kg
    assert_refused(
        compass_with(
            "hip_mass = { value = 10.0, unit = \"kg\"",
            "hip_mass = { value = 10.0, unit = \"1\"",
        ),
        &["unit `1` is dimensionless, hip_mass is a mass (kg, g, …)"],
    );
    assert_refused(
        seed5_with(
            "free_swing_knee = { value = 0.0, unit = \"1\"",
            "free_swing_knee = { value = 0.0, unit = \"kg\"",
        ),
        &["unit `kg` is a mass, free_swing_knee is dimensionless (1)"],
    );
}

#[test]
fn right_units_of_each_quantity_convert_in_the_roles_they_fill() {
    let preset = pdw_walkers::presets::compass(&[]).unwrap();
    for (old, new) in [
        (
            "hip_mass = { value = 10.0, unit = \"kg\"",
            "hip_mass = { value = 10000, unit = \"g\"",
        ),
        (
            "b = { value = 0.5, unit = \"m\"",
            "b = { value = 500, unit = \"mm\"",
        ),
        (
            "max_stride_time = { value = 5.0, unit = \"s\"",
            "max_stride_time = { value = 5000, unit = \"ms\"",
        ),
        (
            "value = 0.05235987755982988, unit = \"rad\"",
            "value = 3, unit = \"deg\"",
        ),
    ] {
        assert_same_walker(&compass_with(old, new).unwrap(), &preset, new);
    }
    // an inertia in g cm^2, a plain number as an angle (radians), a COM as a fraction of a length
    let text = pdw_walkers::preset_text("compass")
        .unwrap()
        .replace("inertia = 0.0 ", "inertia = \"i\" ")
        .replace(
            "[parameters]\n",
            "[parameters]\ni = { value = 5e6, unit = \"g cm^2\" }\nf = { value = 0.5 }\n",
        )
        .replace("com = \"a\" ", "com = \"f * (a + b)\" ")
        .replace("unit = \"rad\"", "unit = \"1\"");
    for part in [
        "inertia = \"i\"",
        "com = \"f * (a + b)\"",
        "slope = { value = 0.05235987755982988, unit = \"1\"",
    ] {
        assert!(text.contains(part), "{part}");
    }
    let spec = WalkerSpec::from_toml(&text, "my.toml").unwrap();
    let t = spec.param_table();
    assert_eq!(t.get("i"), Some(0.5));
    ChainWalker::from_spec(spec).unwrap();
}

#[test]
fn torques_and_impulses_have_their_own_quantities() {
    use pdw_walkers::units::{convert, dimension_of, Dimension, UnitSystem};
    for u in ["N m", "N*m", "N·m", "kg m^2/s^2"] {
        assert_eq!(dimension_of(u), Ok(Dimension::TORQUE), "{u}");
    }
    for u in ["N m s", "N*m*s", "kg m^2/s"] {
        assert_eq!(dimension_of(u), Ok(Dimension::IMPULSE), "{u}");
    }
    let si = UnitSystem::Si;
    assert_eq!(
        convert(2.0, "N m", "latch_torque", Dimension::TORQUE, si),
        Ok(2.0)
    );
    let e = convert(2.0, "N m s", "latch_torque", Dimension::TORQUE, si).unwrap_err();
    assert_eq!(
        e,
        "unit `N m s` is an angular impulse, latch_torque is a torque (N m, N*m, …)"
    );
    assert!(convert(2.0, "N", "latch_impulse", Dimension::IMPULSE, si)
        .unwrap_err()
        .contains("is a force, latch_impulse is an angular impulse (N m s"));
}
