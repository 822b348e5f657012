//! The walk's setup shared by `pdw-sweep simulate` and Python's `simulate`: the starts against
//! Garcia et al. 1998's two period-one gaits of the simplest walker at γ = 0.009 (values from
//! REFERENCES §1, held here), and the refusals, each naming the front end's option.

use pdw::simulate::{self, DtOut, GaitKind, SimulateFlags, Start, StartError, Walk};
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

/// The default output spacing: from a gait its period / 100, from a state `T / 50` with
/// `T = √(L/g)` (the simplest walker's unit time, 1; the compass's `√(1 m / 9.81 m/s²)` from
/// its spec), and both sides of every event; `steps` and a given step as asked.
#[test]
fn the_default_spacing_is_a_hundredth_of_the_period_or_a_fiftieth_of_the_time_scale() {
    let m = simplest();
    let gait = start_ok(&m, Start::Gait(GaitKind::Stable));
    let sp = simulate::spacing(&m, &gait, DtOut::Default);
    assert_eq!(sp.dt_out, Some(gait.period.unwrap() / 100.0));
    assert!(sp.event_samples && sp.source.contains("period"), "{sp:?}");
    let state = start_ok(&m, Start::State(vec![STABLE.0, STABLE.1]));
    let sp = simulate::spacing(&m, &state, DtOut::Default);
    assert_eq!(sp.dt_out, Some(1.0 / 50.0));
    assert!(sp.source.contains("sqrt(L/g)"), "{}", sp.source);
    let compass = pdw::build("compass", &[]).unwrap();
    let walk = Walk {
        period: None,
        ..start_ok(&compass, Start::Gait(GaitKind::Stable))
    };
    let h = simulate::spacing(&compass, &walk, DtOut::Default)
        .dt_out
        .unwrap();
    assert!((h - (1.0_f64 / 9.81).sqrt() / 50.0).abs() < 1e-15, "{h}");
    let steps = simulate::spacing(&m, &gait, DtOut::Steps);
    assert_eq!(steps.dt_out, None);
    let given = simulate::spacing(&m, &gait, DtOut::Every(0.25));
    assert_eq!((given.dt_out, given.event_samples), (Some(0.25), false));
}

#[test]
fn dt_out_is_a_positive_step_or_the_word_steps() {
    assert_eq!(DtOut::parse("steps", "--dt-out").unwrap(), DtOut::Steps);
    assert_eq!(DtOut::parse("0.5", "--dt-out").unwrap(), DtOut::Every(0.5));
    for bad in ["0", "-1", "nan", "inf", "step", "fast", ""] {
        let e = DtOut::parse(bad, "--dt-out").unwrap_err().0;
        assert!(
            e.starts_with("--dt-out: ") && e.contains("steps"),
            "{bad}: {e}"
        );
    }
}

/// A default walk of the simplest walker's stable gait: about 100 grid samples per step, and
/// both sides of every heel strike among the samples (the pre-impact state in step k, the
/// post-impact state in step k + 1, at the event's time).
#[test]
fn a_default_walk_has_a_hundred_samples_per_step_and_every_event() {
    for (m, steps) in [(simplest(), 3), (pdw::build("compass", &[]).unwrap(), 3)] {
        let walk = start_ok(&m, Start::Gait(GaitKind::Stable));
        let sp = simulate::spacing(&m, &walk, DtOut::Default);
        let opts = simulate::options_spaced(&m, steps, &sp, simulate::default_integrator());
        let tr = simulate::run(&m, &walk, &opts).unwrap();
        assert_eq!(tr.steps_done, steps);
        let at_event = |t: f64| tr.events.iter().any(|e| e.t == t);
        for (k, e) in tr.events.iter().enumerate() {
            let i =
                tr.t.iter()
                    .position(|&t| t == e.t)
                    .expect("the event is a sample");
            assert_eq!(tr.state(i), &e.pre[..]);
            assert_eq!(tr.state(i + 1), &e.post[..]);
            assert_eq!((tr.step[i], tr.step[i + 1]), (k as u32, k as u32 + 1));
            // the grid's time on the event (a gait's period / 100) is not sampled again
            assert_eq!(tr.t.iter().filter(|&&t| t == e.t).count(), 2, "{}", e.t);
        }
        for k in 0..steps as u32 {
            let grid = (0..tr.len())
                .filter(|&i| tr.step[i] == k && !at_event(tr.t[i]))
                .count();
            assert!(
                (98..=102).contains(&grid),
                "{}: step {k}: {grid}",
                m.info.name
            );
        }
    }
}

/// Positions on the simplest walker's gait, against its geometry by hand (Garcia et al. 1998,
/// module docs of the model: hip `(−sin θ, cos θ)` from the stance foot, swing foot
/// `hip + (sin ψ, −cos ψ)`, `ψ = θ − φ`), each step's stance foot `Σ 2|sin θ⁻|` down the slope;
/// at each heel strike the swing foot is on the slope and where the next stance foot is.
#[test]
fn positions_of_the_simplest_walker_follow_its_geometry_in_one_frame() {
    let m = simplest();
    let walk = start_ok(&m, Start::Gait(GaitKind::Stable));
    let sp = simulate::spacing(&m, &walk, DtOut::Default);
    let opts = simulate::options_spaced(&m, 4, &sp, simulate::default_integrator());
    let tr = simulate::run(&m, &walk, &opts).unwrap();
    let p = simulate::positions(&m, &tr).unwrap();
    assert_eq!(p.names, ["stance_foot", "hip", "swing_foot"]);
    let mut foot = vec![0.0];
    for e in &tr.events {
        foot.push(foot.last().unwrap() + 2.0 * e.pre[0].sin().abs());
    }
    let pt = |i: usize, j: usize| [p.points[6 * i + 2 * j], p.points[6 * i + 2 * j + 1]];
    for i in 0..tr.len() {
        let x = tr.state(i);
        let f = foot[tr.step[i] as usize];
        let hip = [f - x[0].sin(), x[0].cos()];
        let psi = x[0] - x[2];
        let swing = [hip[0] + psi.sin(), hip[1] - psi.cos()];
        for (got, want) in [(pt(i, 0), [f, 0.0]), (pt(i, 1), hip), (pt(i, 2), swing)] {
            assert!((got[0] - want[0]).abs() < 1e-12 && (got[1] - want[1]).abs() < 1e-12);
        }
        // massless legs: the centre of mass is the hip
        assert_eq!([p.com[2 * i], p.com[2 * i + 1]], pt(i, 1));
    }
    for e in &tr.events {
        let i = tr.t.iter().position(|&t| t == e.t).unwrap();
        let (strike, next) = (pt(i, 2), pt(i + 1, 0));
        assert!(
            strike[1].abs() < 1e-9,
            "swing foot {strike:?} off the slope"
        );
        assert!((strike[0] - next[0]).abs() < 1e-9, "{strike:?} vs {next:?}");
    }
}

/// The compass (Goswami et al. 1998: point masses m at a from each foot, m_H at the hip; legs
/// of length l = a + b): hip `l (−sin θ, cos θ)` from the stance foot, swing-leg mass `b` below
/// the hip along the swing leg at absolute angle `θ + q_hip`, and the centre of mass
/// `(m p_stance + m_H p_hip + m p_swing) / (2m + m_H)`, by hand; the swing foot lands on the
/// slope where the next stance foot is.
#[test]
fn the_compass_centre_of_mass_is_the_weighted_mean_of_its_point_masses() {
    let m = pdw::build("compass", &[]).unwrap();
    let (lm, hm, a, b) = (5.0, 10.0, 0.5, 0.5);
    let walk = start_ok(&m, Start::Gait(GaitKind::Stable));
    let sp = simulate::spacing(&m, &walk, DtOut::Default);
    let opts = simulate::options_spaced(&m, 3, &sp, simulate::default_integrator());
    let tr = simulate::run(&m, &walk, &opts).unwrap();
    let p = simulate::positions(&m, &tr).unwrap();
    assert_eq!(p.names, ["stance_foot", "hip", "swing_foot"]);
    let mut foot = vec![0.0];
    for e in &tr.events {
        let th_sw = e.pre[0] + e.pre[1];
        let x_sw = -(a + b) * e.pre[0].sin() + (a + b) * th_sw.sin();
        foot.push(foot.last().unwrap() + x_sw);
    }
    let pt = |i: usize, j: usize| [p.points[6 * i + 2 * j], p.points[6 * i + 2 * j + 1]];
    for i in 0..tr.len() {
        let x = tr.state(i);
        let (th, th_sw) = (x[0], x[0] + x[1]);
        let f = foot[tr.step[i] as usize];
        let along = |d: f64, t: f64| [-d * t.sin(), d * t.cos()];
        let hip = along(a + b, th);
        let stance_mass = along(a, th);
        let swing_mass = [hip[0] + b * th_sw.sin(), hip[1] - b * th_sw.cos()];
        let com = [0, 1]
            .map(|c| (lm * stance_mass[c] + hm * hip[c] + lm * swing_mass[c]) / (2.0 * lm + hm));
        let got_hip = pt(i, 1);
        assert!((got_hip[0] - (f + hip[0])).abs() < 1e-12 && (got_hip[1] - hip[1]).abs() < 1e-12);
        assert!((p.com[2 * i] - (f + com[0])).abs() < 1e-12, "{i}");
        assert!((p.com[2 * i + 1] - com[1]).abs() < 1e-12, "{i}");
    }
    for e in &tr.events {
        let i = tr.t.iter().position(|&t| t == e.t).unwrap();
        let (strike, next) = (pt(i, 2), pt(i + 1, 0));
        assert!(
            strike[1].abs() < 1e-9,
            "swing foot {strike:?} off the slope"
        );
        assert!((strike[0] - next[0]).abs() < 1e-9, "{strike:?} vs {next:?}");
    }
}

/// Round feet: the contact point rolls, so the walk has no positions, and says why.
#[test]
fn round_feet_have_no_positions_and_say_why() {
    let spec = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/seed5_walking.toml"
    );
    let m = pdw::build(spec, &[]).unwrap();
    let guess = m.walker.gait_guesses()[0].section.clone();
    let walk = start_ok(&m, Start::State(guess));
    let opts = simulate::options(&m, 1, None, simulate::default_integrator());
    let tr = simulate::run(&m, &walk, &opts).unwrap();
    let why = simulate::positions(&m, &tr).unwrap_err();
    assert!(why.contains("round feet"), "{why}");
}
