//! The spec parser's and the unit table's internals (expression limits and precedence, message
//! lengths, file checks; conversions and unit systems), run here rather than as unit tests so
//! that the library is not compiled a second time with `cfg(test)`.

mod expressions {
    use pdw_walkers::spec::*;

    #[test]
    fn deep_or_long_expressions_are_refused_not_a_stack_overflow() {
        let env = [("a", 2.0)];
        // within the limits
        let ok = format!("{}a{}", "(".repeat(200), ")".repeat(200));
        assert_eq!(eval_expr(&ok, &env), Ok(2.0));
        assert_eq!(eval_expr(&format!("{}a", "-".repeat(200)), &env), Ok(2.0));
        // 30 000 parentheses and 100 000 unary minuses overflowed the stack before the limit
        let deep = format!("{}a{}", "(".repeat(30_000), ")".repeat(30_000));
        let e = eval_expr(&deep, &env).unwrap_err();
        assert!(e.contains("characters"), "{e}");
        let deep = format!("{}a{}", "(".repeat(4_000), ")".repeat(4_000));
        let e = eval_expr(&deep, &env).unwrap_err();
        assert!(e.contains("256 levels"), "{e}");
        let e = eval_expr(&format!("{}a", "-".repeat(9_000)), &env).unwrap_err();
        assert!(e.contains("256 levels"), "{e}");
        let e = eval_expr(&format!("{}a", "-".repeat(100_000)), &env).unwrap_err();
        assert!(e.contains("more than the 10000"), "{e}");
    }

    #[test]
    fn powers_bind_tighter_than_unary_minus_and_associate_to_the_right() {
        let env = [("a", 2.0), ("l", 0.5)];
        let ev = |e: &str| eval_expr(e, &env);
        assert_eq!(ev("2^3"), Ok(8.0));
        assert_eq!(ev("2**3"), Ok(8.0));
        assert_eq!(ev("-2^2"), Ok(-4.0));
        assert_eq!(ev("-2**2"), Ok(-4.0));
        assert_eq!(ev("(-2)^2"), Ok(4.0));
        assert_eq!(ev("2^3^2"), Ok(512.0));
        assert_eq!(ev("2**3**2"), Ok(512.0));
        assert_eq!(ev("(2^3)^2"), Ok(64.0));
        assert_eq!(ev("2^-1"), Ok(0.5));
        assert_eq!(ev("2 * 3^2"), Ok(18.0));
        assert_eq!(ev("12 / 2^2"), Ok(3.0));
        assert_eq!(ev("1 + a^2"), Ok(5.0));
        assert_eq!(ev("a * l^2 / 12"), Ok(2.0 * 0.25 / 12.0));
        assert_eq!(ev("l ** 0.5"), Ok(0.5f64.sqrt()));
        assert_eq!(ev("1e-3^2"), Ok(1e-6));
        assert!(ev("2^").is_err());
        assert!(ev("^2").is_err());
        assert!(ev("2***3").is_err());
        // a long chain of powers is a nesting like any other
        let e = ev(&format!("1{}", "^1".repeat(300))).unwrap_err();
        assert!(e.contains("256 levels"), "{e}");
    }

    #[test]
    fn messages_echo_at_most_80_characters_of_an_expression() {
        let long = format!("a{}", " + b".repeat(5_000));
        let q = quoted(&long);
        assert!(
            q.chars().count() < 120 && q.contains("20001 characters"),
            "{q}"
        );
        assert_eq!(quoted("a + 1"), "\"a + 1\"");
        let text = format!(
            "name = \"x\"\n[parameters]\nslope = {{ value = 0.01, unit = \"rad\" }}\n\
             [[segments]]\nname = \"leg\"\nlength = \"{long}\"\nmass = 1.0\ncom = 0.5\n"
        );
        if let Ok(spec) = WalkerSpec::from_toml(&text, "t") {
            let values = spec.param_table().values;
            let e = spec.resolve(&values).unwrap_err().to_string();
            assert!(e.len() < 600, "{} bytes: {e}", e.len());
        }
    }

    #[test]
    fn spec_files_are_regular_and_small() {
        let e = WalkerSpec::from_file(std::path::Path::new("/dev/zero"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a regular file"), "{e}");
        let dir = std::env::temp_dir().join(format!("pdw-spec-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let big = dir.join("big.toml");
        std::fs::write(&big, vec![b'#'; (MAX_SPEC_BYTES + 1) as usize]).unwrap();
        let e = WalkerSpec::from_file(&big).unwrap_err().to_string();
        assert!(e.contains("larger than 1024 KiB"), "{e}");
        let link = dir.join("zero.toml");
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
        let e = WalkerSpec::from_file(&link).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

mod unit_table {
    use pdw_walkers::units::*;

    #[test]
    fn base_units_leave_the_value_bit_for_bit() {
        for u in [
            "rad", "1", "m", "kg", "s", "m/s^2", "kg m^2", "L", "M", "T", "L/T^2", "N",
        ] {
            let x = 0.05235987755982988;
            for sys in [UnitSystem::Si, UnitSystem::Abstract] {
                assert_eq!(to_base(x, u, sys), Ok((x, u.to_string())), "{u}");
            }
        }
    }

    #[test]
    fn prefixes_and_degrees_convert() {
        let si = UnitSystem::Si;
        assert_eq!(
            to_base(3.0, "deg", si),
            Ok((0.05235987755982988, "rad".into()))
        );
        assert_eq!(
            to_base(3.0, "°", si),
            Ok((0.05235987755982988, "rad".into()))
        );
        assert_eq!(
            to_base(180.0, "deg", si),
            Ok((std::f64::consts::PI, "rad".into()))
        );
        assert_eq!(
            to_base(1.0, "1/deg", si).map(|p| p.0),
            Ok(180.0 / std::f64::consts::PI)
        );
        assert_eq!(to_base(50.0, "cm", si), Ok((0.5, "m".into())));
        assert_eq!(to_base(7.0, "mm", si), Ok((0.007, "m".into())));
        assert_eq!(to_base(250.0, "g", si), Ok((0.25, "kg".into())));
        assert_eq!(to_base(981.0, "cm/s^2", si), Ok((9.81, "m/s^2".into())));
        assert_eq!(to_base(2.0, "1/ms", si), Ok((2000.0, "1/s".into())));
        assert_eq!(to_base(5e6, "g cm^2", si), Ok((0.5, "kg m^2".into())));
    }

    #[test]
    fn unknown_mixed_or_unconvertible_units_are_refused() {
        let e = to_base(1.0, "furlong", UnitSystem::Si).unwrap_err();
        assert!(e.contains("`furlong`"), "{e}");
        assert!(to_base(1.0, "m/L", UnitSystem::Si)
            .unwrap_err()
            .contains("mixes"));
        let e = to_base(1.0, "cm", UnitSystem::Abstract).unwrap_err();
        assert!(e.contains("`cm`"), "{e}");
        assert!(to_base(1.0, "", UnitSystem::Si).is_err());
        assert!(to_base(1.0, "m/", UnitSystem::Si).is_err());
        assert!(to_base(1.0, "m^x", UnitSystem::Si).is_err());
        assert!(to_base(1.0, "(m)", UnitSystem::Si).is_err());
    }

    #[test]
    fn a_spec_is_abstract_when_a_parameter_uses_l_m_or_t() {
        assert_eq!(system_of(["rad", "L", "M"]), UnitSystem::Abstract);
        assert_eq!(system_of(["rad", "m", "kg", "1"]), UnitSystem::Si);
        assert_eq!(system_of(["L/T^2"]), UnitSystem::Abstract);
    }
}
