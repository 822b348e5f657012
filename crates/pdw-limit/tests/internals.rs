//! Tests of pdw-limit's internal helpers (attractor naming and relabelling, orbit
//! rotation, row-major products, cgroup memory limits, Brent's
//! minimiser and the Illinois root finder), run here rather than as unit tests so that the
//! library is not compiled a second time with `cfg(test)`. The helpers they reach are public but
//! hidden from the documentation.

mod attractors {
    use pdw_limit::attractors::*;
    use pdw_limit::basin::{CellResult, Outcome};
    fn att(kind: AttractorKind, k: usize, name: &str) -> Attractor {
        Attractor {
            name: name.into(),
            code: 0,
            kind,
            period_k: k,
            points: vec![vec![0.0, 0.0]],
            multipliers: Vec::new(),
            period_time: 1.0,
            radius: 0.1,
            validity: pdw_limit::OrbitValidity::Unchecked,
        }
    }

    #[test]
    fn names_and_codes_follow_discovery_order() {
        let mut v = vec![
            att(AttractorKind::Periodic, 1, "gait"),
            att(AttractorKind::Periodic, 2, ""),
            att(AttractorKind::Chaotic, 0, ""),
            att(AttractorKind::Periodic, 2, ""),
            att(AttractorKind::Periodic, 1, ""),
            att(AttractorKind::Chaotic, 0, ""),
        ];
        name_and_code(&mut v);
        let got: Vec<(&str, u8)> = v.iter().map(|a| (a.name.as_str(), a.code)).collect();
        assert_eq!(
            got,
            vec![
                ("gait", 0),
                ("period-2", 16),
                ("chaotic", 17),
                ("period-2b", 18),
                ("period-1b", 19),
                ("chaotic-b", 20)
            ]
        );
        let set = AttractorSet { attractors: v };
        let legend = set.legend();
        // the 13 fixed outcomes (0-12), then the attractors from 16
        assert_eq!(legend.len(), 13 + 5);
        assert_eq!(legend[0], (0, "gait".to_string()));
        assert_eq!(legend[12], (12, "fall_rolls_back".to_string()));
        assert_eq!(legend[13], (16, "period-2".to_string()));
    }

    #[test]
    fn relabel_maps_known_orbits_and_walking_cells_near_a_chaotic_sample() {
        let mut v = vec![
            att(AttractorKind::Periodic, 2, ""),
            att(AttractorKind::Chaotic, 0, ""),
        ];
        v[1].points = vec![vec![1.0, 1.0]];
        name_and_code(&mut v);
        let set = AttractorSet { attractors: v };
        let cell = |o: Outcome, a: u8, f: [f64; 2]| CellResult {
            outcome: o.code(),
            strides: 1,
            period: 2,
            attractor: a,
            final_state: f.to_vec(),
        };
        let mut cells = vec![
            cell(Outcome::Other, 0, [0.0, 0.0]),
            cell(Outcome::Other, u8::MAX, [0.0, 0.0]),
            cell(Outcome::Timeout, u8::MAX, [1.05, 1.0]),
            cell(Outcome::Timeout, u8::MAX, [1.5, 1.0]),
            cell(Outcome::FallForward, u8::MAX, [1.0, 1.0]),
        ];
        set.relabel(&mut cells);
        let codes: Vec<u8> = cells.iter().map(|c| c.outcome).collect();
        assert_eq!(codes, vec![16, 1, 17, 7, 2]);
        assert_eq!(cells[2].outcome(), Outcome::Other);
    }
}

mod outcomes {
    use pdw_hybrid::FallKind;
    use pdw_limit::basin::{legend, Outcome, ATTRACTOR_CODE_BASE};
    use pdw_limit::end::{table, End};
    use pdw_limit::StrideOutcome;

    /// Every fall kind a model's terminal guard can carry has its own basin class (the catch-all
    /// `fall` only for kinds without a name), every code maps back to its outcome, and every
    /// fixed code lies below the attractors' first.
    #[test]
    fn each_fall_kind_is_its_own_class_and_codes_round_trip() {
        let kinds = [
            (FallKind::Forward, "fall_forward"),
            (FallKind::Backward, "fall_backward"),
            (FallKind::KneeBent, "fall_knee_bent"),
            (FallKind::KneeBuckled, "fall_knee_buckled"),
            (FallKind::RollsBack, "fall_rolls_back"),
            (FallKind::Other, "fall"),
        ];
        let mut seen = Vec::new();
        for (k, name) in kinds {
            let o = Outcome::of_fall(k);
            assert_eq!(o.name(), name, "{k:?}");
            assert!(o.is_fall(), "{k:?}");
            assert!(!seen.contains(&o.code()), "{k:?} shares a code");
            seen.push(o.code());
        }
        for o in Outcome::ALL {
            assert_eq!(Outcome::from_code(o.code()), Some(o));
            assert!(o.code() < ATTRACTOR_CODE_BASE);
        }
        for c in [14, 15, ATTRACTOR_CODE_BASE, 255] {
            assert_eq!(Outcome::from_code(c), None, "{c}");
        }
        assert_eq!(Outcome::from_code(13), Some(Outcome::HeelStrike));
        let l = legend();
        assert_eq!(l.len(), Outcome::CELL_ENDS.len());
        assert_eq!(l.len(), 13);
        assert_eq!(l[11], (11, "fall_knee_buckled"));
        assert!(!l.iter().any(|&(c, _)| c == Outcome::HeelStrike.code()));
    }

    /// Every stride outcome, each fall kind once.
    fn every_stride_outcome() -> Vec<StrideOutcome> {
        let kinds = [
            FallKind::Forward,
            FallKind::Backward,
            FallKind::KneeBent,
            FallKind::KneeBuckled,
            FallKind::RollsBack,
            FallKind::Other,
        ];
        let mut v = vec![
            StrideOutcome::Ok,
            StrideOutcome::NoHeelStrike,
            StrideOutcome::NonFinite,
            StrideOutcome::StepTooSmall,
            StrideOutcome::MaxSteps,
            StrideOutcome::TooManyEvents,
        ];
        v.extend(
            kinds
                .iter()
                .map(|&kind| StrideOutcome::Fall { kind, guard: 1 }),
        );
        v
    }

    /// The one table: codes 0..=13 in order, each with one name and back; every stride's end
    /// is one entry of it, found again by its code and by its name; a complete stride is the
    /// only `heel_strike` and no stride ends as a cell-only end (gait, other, timeout).
    #[test]
    fn every_stride_end_maps_to_exactly_one_code_and_name() {
        for (i, e) in End::ALL.iter().enumerate() {
            assert_eq!(usize::from(e.code()), i, "{e:?}");
            assert_eq!(End::from_name(e.name()), Some(*e), "{e:?}");
        }
        let mut names: Vec<&str> = End::ALL.iter().map(|e| e.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), End::ALL.len(), "two ends share a name");
        assert_eq!(table().len(), End::ALL.len());
        assert_eq!(table()[13], (13, "heel_strike"));
        assert!(End::ALL.iter().all(|e| e.code() < ATTRACTOR_CODE_BASE));
        for o in every_stride_outcome() {
            let e = o.end();
            assert_eq!(End::from_code(e.code()), Some(e), "{o:?}");
            assert_eq!(End::from_name(e.name()), Some(e), "{o:?}");
            assert_eq!(e == End::HeelStrike, o.is_ok(), "{o:?}");
            assert!(
                !matches!(e, End::Gait | End::Other | End::Timeout),
                "{o:?} ends as a cell-only {e:?}"
            );
            if let StrideOutcome::Fall { kind, .. } = o {
                assert_eq!(e, Outcome::of_fall(kind));
                assert!(e.is_fall());
            }
        }
        assert_eq!(StrideOutcome::NoHeelStrike.end().code(), 5);
        assert_eq!(
            StrideOutcome::NoHeelStrike.end().name(),
            "fall_no_heel_strike"
        );
        for o in [
            StrideOutcome::StepTooSmall,
            StrideOutcome::MaxSteps,
            StrideOutcome::TooManyEvents,
        ] {
            assert_eq!(o.end(), End::IntegratorFailure, "{o:?}");
        }
        assert!(End::CELL_ENDS.iter().all(|e| e.is_cell_end()));
        assert!(!End::HeelStrike.is_cell_end());
    }

    /// The integrator's stops mean one thing to every driver: the end time is no heel strike
    /// (never a cell's `timeout`), a terminal guard the fall of its kind, a reset guard a reset.
    #[test]
    fn integrator_stops_name_one_stride_end() {
        use pdw_hybrid::{Crossing, GuardKind, GuardSpec, StopReason};
        use pdw_limit::stride::StrideStop;
        let guards = [
            GuardSpec {
                name: "heel_strike",
                crossing: Crossing::Falling,
                kind: GuardKind::Reset,
            },
            GuardSpec {
                name: "hip_below_ground",
                crossing: Crossing::Falling,
                kind: GuardKind::Terminal(FallKind::Forward),
            },
        ];
        let end = |stop| match StrideStop::of(stop, &guards) {
            StrideStop::End(o) => Some(o.end()),
            StrideStop::Reset { .. } => None,
        };
        assert_eq!(end(StopReason::Guard { guard: 0 }), None);
        assert_eq!(end(StopReason::Guard { guard: 1 }), Some(End::FallForward));
        assert_eq!(end(StopReason::EndTime), Some(End::FallNoHeelStrike));
        assert_eq!(end(StopReason::NonFinite), Some(End::NonFinite));
        assert_eq!(end(StopReason::StepTooSmall), Some(End::IntegratorFailure));
        assert_eq!(end(StopReason::MaxSteps), Some(End::IntegratorFailure));
    }
}

mod periodic {
    use pdw_limit::periodic::{canonical_start, matmul, same_orbit};
    #[test]
    fn canonical_start_rotates_to_the_smallest_point() {
        let o = vec![vec![0.3, 1.0], vec![0.1, 2.0], vec![0.2, 0.0]];
        let c = canonical_start(&o);
        assert_eq!(c, vec![vec![0.1, 2.0], vec![0.2, 0.0], vec![0.3, 1.0]]);
        assert!(same_orbit(&o, &c));
        assert!(!same_orbit(
            &o,
            &[vec![0.1, 2.1], vec![0.2, 0.0], vec![0.3, 1.0]]
        ));
    }

    #[test]
    fn matmul_is_row_major_product() {
        let a = [1.0, 2.0, 3.0, 4.0];
        let b = [0.0, 1.0, 1.0, 0.0];
        assert_eq!(matmul(&a, &b, 2), vec![2.0, 1.0, 4.0, 3.0]);
    }
}

mod resources {
    use pdw_limit::resources::{cgroup_room, memory_available};
    use std::path::Path;
    fn write(p: &Path, text: &str) {
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }

    #[test]
    fn cgroup_limits_v1_and_v2_are_read_and_no_limit_is_none() {
        let dir = std::env::temp_dir().join(format!("pdw-cgroup-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        // v1: a 400 MiB limit with 100 MiB used in the process's group
        write(
            &dir.join("memory/job/memory.limit_in_bytes"),
            &format!("{}\n", 400u64 << 20),
        );
        write(
            &dir.join("memory/job/memory.usage_in_bytes"),
            &format!("{}\n", 100u64 << 20),
        );
        assert_eq!(
            cgroup_room("4:memory:/job\n1:cpu:/\n", &dir),
            Some(300 << 20)
        );
        // v2 under the unified mount; "max" is no limit
        write(&dir.join("unified/u/memory.max"), "max\n");
        write(&dir.join("unified/u/memory.current"), "5\n");
        assert_eq!(cgroup_room("0::/u\n", &dir), None);
        write(&dir.join("unified/u/memory.max"), "1000\n");
        assert_eq!(cgroup_room("0::/u\n", &dir), Some(995));
        // the smaller of the two, and a v1 root without a limit
        assert_eq!(cgroup_room("4:memory:/job\n0::/u\n", &dir), Some(995));
        write(
            &dir.join("memory/memory.limit_in_bytes"),
            "9223372036854771712\n",
        );
        assert_eq!(cgroup_room("4:memory:/elsewhere\n", &dir), None);
        let _ = std::fs::remove_dir_all(&dir);
        assert!(memory_available() > 0);
    }
}

mod validity {
    use pdw_limit::validity::{brent_min, illinois};
    #[test]
    fn brent_finds_a_parabola_minimum() {
        let mut f = |t: f64| (t - 0.3).powi(2) - 1.0;
        let f5 = f(0.5);
        let (t, v) = brent_min(&mut f, 0.0, 0.5, 1.0, f5);
        assert!((t - 0.3).abs() < 1e-7, "{t}");
        assert!((v + 1.0).abs() < 1e-14);
        // minimum at the end of the bracket
        let mut g = |t: f64| t;
        let (t, v) = brent_min(&mut g, 0.0, 0.0, 1.0, 0.0);
        assert_eq!((t, v), (0.0, 0.0));
    }

    #[test]
    fn illinois_finds_a_root() {
        let mut f = |t: f64| t.cos() - t;
        let r = illinois(&mut f, 0.0, 1.0, 1.0, 1f64.cos() - 1.0);
        assert!((r - 0.739_085_133_215_160_6).abs() < 1e-12, "{r}");
    }
}
