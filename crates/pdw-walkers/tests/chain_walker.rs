//! The chain walker built from specs: round trip of spec files, clear errors for bad specs,
//! batched guards equal to the scalar guards bit for bit, exact Jacobians against Richardson
//! differences (allocation: `chain_walker_alloc.rs`; the batched flow in every lane against
//! independent models: the tests crate's `compass_closed_form.rs` and
//! `round_foot_kneed_reference.rs`).

use crate::chain_common;
use faer::Mat;
use pdw_hybrid::{HybridSystem, Scratch, Section};

use chain_common::{all_presets, random_state};
use pdw_walkers::{presets, ChainWalker, Walker, WalkerError, WalkerSpec};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn spec_round_trip_gives_identical_dynamics() {
    let mut r = ChaCha8Rng::seed_from_u64(1);
    for (name, text) in pdw_walkers::PRESETS {
        let spec = WalkerSpec::from_toml(text, name).unwrap();
        let printed = spec.to_toml();
        let back = WalkerSpec::from_toml(&printed, "printed").unwrap();
        assert_eq!(spec, back, "{name}: spec changed in the round trip");
        let (a, b) = (
            ChainWalker::from_spec(spec).unwrap(),
            ChainWalker::from_spec(back).unwrap(),
        );
        let mut ws = Scratch::new();
        for mode in 0..a.n_modes() {
            for _ in 0..20 {
                let x = random_state(&a, &mut r, mode);
                let (mut fa, mut fb) = (vec![0.0; a.dim()], vec![0.0; b.dim()]);
                a.flow(&mut ws, mode, &x, &mut fa);
                b.flow(&mut ws, mode, &x, &mut fb);
                for (u, v) in fa.iter().zip(&fb) {
                    assert_eq!(u.to_bits(), v.to_bits(), "{name} mode {mode}");
                }
            }
        }
        assert_eq!(a.gait_guesses(), b.gait_guesses());
    }
}

/// A spec file with one changed parameter default equals `--set` of that parameter on the preset.
#[test]
fn file_model_with_a_changed_parameter_equals_set_on_the_preset() {
    let text = pdw_walkers::preset_text("compass")
        .unwrap()
        .replace("hip_mass = { value = 10.0,", "hip_mass = { value = 7.5,");
    let dir = std::env::temp_dir().join(format!("pdw-spec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("my_compass.toml");
    std::fs::write(&path, text).unwrap();
    let file = pdw_walkers::build(path.to_str().unwrap(), &[]).unwrap();
    let set = pdw_walkers::build("compass", &[("hip_mass", 7.5)]).unwrap();
    let base = pdw_walkers::build("compass", &[]).unwrap();
    let mut ws = Scratch::new();
    let x = [0.25, -0.5, -1.0, 0.6];
    let (mut f1, mut f2, mut f3) = ([0.0; 4], [0.0; 4], [0.0; 4]);
    file.flow(&mut ws, 0, &x, &mut f1);
    set.flow(&mut ws, 0, &x, &mut f2);
    base.flow(&mut ws, 0, &x, &mut f3);
    assert_eq!(f1.map(f64::to_bits), f2.map(f64::to_bits));
    assert_ne!(
        f1[2], f3[2],
        "the changed hip mass must change the dynamics"
    );
    assert_eq!(file.param_values(), set.param_values());
    std::fs::remove_dir_all(&dir).ok();
}

fn spec_error(text: &str) -> String {
    let spec = match WalkerSpec::from_toml(text, "bad.toml") {
        Ok(s) => s,
        Err(e) => return e.to_string(),
    };
    match ChainWalker::from_spec(spec) {
        Ok(_) => panic!("spec accepted:\n{text}"),
        Err(e) => {
            assert!(
                matches!(
                    e,
                    WalkerError::InvalidSpec { .. } | WalkerError::SpecSyntax { .. }
                ),
                "{e:?}"
            );
            e.to_string()
        }
    }
}

const OK_SEGMENT: &str = "[[segments]]\nlength = 1.0\nmass = 1.0\ncom = 0.5\n";

#[test]
fn every_bad_spec_is_refused_naming_the_field_the_value_and_the_rule() {
    let head = "name = \"w\"\n[parameters]\nslope = { value = 0.05, unit = \"rad\" }\n";
    let cases: Vec<(String, &[&str])> = vec![
        (
            format!("{head}[[segments]]\nlength = 1.0\nmass = -2.0\ncom = 0.5\n"),
            &["segments[0].mass", "-2", "> 0"],
        ),
        (
            format!("{head}[[segments]]\nlength = 0.0\nmass = 1.0\ncom = 0.5\n"),
            &["segments[0].length", "0", "> 0"],
        ),
        (
            format!("{head}[[segments]]\nlength = nan\nmass = 1.0\ncom = 0.5\n"),
            &["segments[0].length", "NaN", "finite"],
        ),
        (head.to_string(), &["segments", "at least one segment"]),
        (
            format!("{head}{OK_SEGMENT}[[knees]]\nmode = \"locked\"\n"),
            &["knees", "one-segment leg has no knee"],
        ),
        (
            format!("{head}{OK_SEGMENT}colour = \"red\"\n"),
            &["unknown field", "colour"],
        ),
        (
            format!("{head}[[segments]]\nlength = \"a + 1\"\nmass = 1.0\ncom = 0.5\n"),
            &["segments[0].length", "unknown parameter `a`"],
        ),
        (
            format!(
                "{head}{OK_SEGMENT}{OK_SEGMENT}{OK_SEGMENT}[[knees]]\nmode = \"free-swing\"\n\
                 [[knees]]\nmode = \"free-swing\"\n"
            ),
            &["knees", "at most one knee may be free-swing"],
        ),
        (
            format!("{head}{OK_SEGMENT}{OK_SEGMENT}[[knees]]\nmode = \"loose\"\n"),
            &["knees[0].mode", "loose"],
        ),
        (
            format!("{head}[[segments]]\nlength = 1.0\nmass = 1.0\ncom = 0.0\n"),
            &["segments[0].com", "singular"],
        ),
        (
            format!("{head}[[segments]]\nlength = 1.0\nmass = 1.0\ncom = 5.0\n"),
            &[
                "segments[0].com",
                "5",
                "between 0 and the segment's length 1",
            ],
        ),
        (
            format!("{head}[[segments]]\nlength = 1.0\nmass = 1.0\ncom = -0.25\n"),
            &["segments[0].com", "-0.25", "com_normal"],
        ),
        (
            "name = \"w\"\n[[segments]]\nlength = 1.0\nmass = 1.0\ncom = 0.5\n".to_string(),
            &["parameters.slope", "default"],
        ),
        (
            format!("name = \"w\"\nhip_mass = -1.0\n{}{OK_SEGMENT}", &head[11..]),
            &["hip_mass", "-1", ">= 0"],
        ),
    ];
    for (text, needles) in cases {
        let msg = spec_error(&text);
        for n in needles {
            assert!(
                msg.contains(n),
                "message `{msg}` lacks `{n}` for spec:\n{text}"
            );
        }
        assert!(
            !msg.contains("Some(") && !msg.contains("{ "),
            "Debug output in `{msg}`"
        );
    }
    // a preset with a bad override names the parameter's field too
    let e = presets::compass(&[("leg_mass", -1.0)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("segments[0].mass") && e.contains("-1"), "{e}");
    let e = presets::compass(&[("b", -0.5)]).unwrap_err().to_string();
    assert!(e.contains("segments[0].length"), "{e}");
}

/// Central differences of `f` at `x`, extrapolated (Richardson, steps h and h/2).
pub(crate) fn richardson(
    f: &mut dyn FnMut(&[f64], &mut [f64]),
    x: &[f64],
    n_out: usize,
) -> Vec<f64> {
    let n = x.len();
    let mut jac = vec![0.0; n_out * n];
    let (mut fp, mut fm) = (vec![0.0; n_out], vec![0.0; n_out]);
    let mut xp = x.to_vec();
    for j in 0..n {
        let mut d = [vec![0.0; n_out], vec![0.0; n_out]];
        for (k, h) in [1e-4, 5e-5].into_iter().enumerate() {
            xp[j] = x[j] + h;
            f(&xp, &mut fp);
            xp[j] = x[j] - h;
            f(&xp, &mut fm);
            xp[j] = x[j];
            for i in 0..n_out {
                d[k][i] = (fp[i] - fm[i]) / (2.0 * h);
            }
        }
        for i in 0..n_out {
            jac[i * n + j] = (4.0 * d[1][i] - d[0][i]) / 3.0;
        }
    }
    jac
}

pub(crate) fn assert_close(a: &[f64], b: &[f64], tol: f64, what: &str) {
    let scale = b.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    for (i, (u, v)) in a.iter().zip(b).enumerate() {
        assert!(
            (u - v).abs() <= tol * scale,
            "{what}: entry {i}: exact {u} vs differences {v}"
        );
    }
}

#[test]
fn exact_flow_guard_and_reset_jacobians_match_richardson_differences() {
    let mut r = ChaCha8Rng::seed_from_u64(3);
    for (name, w) in all_presets() {
        let d = w.dim();
        let mut ws = Scratch::new();
        for mode in 0..w.n_modes() {
            for _ in 0..5 {
                let x = random_state(&w, &mut r, mode);
                let mut jac = vec![0.0; d * d];
                w.flow_jacobian(&mut ws, mode, &x, &mut jac);
                let mut ws2 = Scratch::new();
                let fd = richardson(&mut |x, f| w.flow(&mut ws2, mode, x, f), &x, d);
                assert_close(
                    &jac,
                    &fd,
                    1e-8,
                    &format!("{name} flow jacobian mode {mode}"),
                );
                for k in 0..w.guards(mode).len() {
                    let mut g = vec![0.0; d];
                    w.guard_gradient(&mut ws, mode, k, &x, &mut g);
                    let fd =
                        richardson(&mut |x, out| out[0] = w.guard(&mut ws2, mode, k, x), &x, 1);
                    assert_close(&g, &fd, 1e-8, &format!("{name} guard {k} mode {mode}"));
                }
                // reset (knee strike in the free mode, heel strike in the locked mode)
                let mut jr = vec![0.0; d * d];
                w.reset_jacobian(&mut ws, mode, 0, &x, &mut jr);
                let fd = richardson(
                    &mut |x, out| {
                        w.reset(&mut ws2, mode, 0, x, out);
                    },
                    &x,
                    d,
                );
                // columns of locked coordinates are not free to vary in the model; compare all
                // columns anyway: the impact maps are smooth in every coordinate
                assert_close(
                    &jr,
                    &fd,
                    1e-8,
                    &format!("{name} reset jacobian mode {mode}"),
                );
            }
        }
    }
}

/// The leg swap is an involution on a symmetric walker's joint angles (swapping twice returns
/// the same chain) and the heel strike keeps the post-impact state on the section.
#[test]
fn heel_strike_lands_on_the_section_and_the_swap_is_an_involution() {
    let mut r = ChaCha8Rng::seed_from_u64(5);
    for (name, w) in all_presets() {
        let n = w.dim() / 2;
        let q: Vec<f64> = (0..n).map(|_| r.random_range(-1.0..1.0)).collect();
        let mut once = vec![0.0; 2 * n];
        let mut twice = vec![0.0; 2 * n];
        w.swap(&q, &q, &mut once);
        let (q1, _) = once.split_at(n);
        w.swap(q1, q1, &mut twice);
        for k in 1..n {
            assert!((twice[k] - q[k]).abs() < 1e-15, "{name}: joint {k}");
        }
        // heel strike from a lifted section state at the symmetric configuration
        let mut x = vec![0.0; 2 * n];
        w.lift(&[0.2, -1.0, 0.4], &mut x);
        // mirror to the pre-impact configuration: stance −0.2, hip +0.4
        x[0] = -0.2;
        x[n / 2] = 0.4;
        let mut post = vec![0.0; 2 * n];
        let mut ws = Scratch::new();
        let mode = w.locked_mode();
        w.reset(&mut ws, mode, 0, &x, &mut post);
        let mut s = [0.0; 3];
        w.project(&post, &mut s);
        let mut lifted = vec![0.0; 2 * n];
        w.lift(&s, &mut lifted);
        for k in 0..2 * n {
            assert!(
                (lifted[k] - post[k]).abs() <= 1e-12,
                "{name}: post-impact state leaves the section at {k}: {post:?}"
            );
        }
    }
}

/// The one-state flow (the scalar workspace's instance of the articulated-body recursion, which
/// event location and dense output call) equals the batched flow's lane bit for bit, for every
/// preset and mode, at lane counts that use the 8-lane chunks, the single lanes after them, and
/// both across blocks.
#[test]
fn one_state_flow_equals_the_batched_flow_bit_for_bit() {
    let mut r = ChaCha8Rng::seed_from_u64(61);
    for (name, w) in all_presets() {
        let d = w.dim();
        for mode in 0..w.n_modes() {
            for lanes in [1usize, 7, 8, 21, 300] {
                let states: Vec<Vec<f64>> =
                    (0..lanes).map(|_| random_state(&w, &mut r, mode)).collect();
                let x = Mat::from_fn(lanes, d, |l, j| states[l][j]);
                let mut dx = Mat::<f64>::zeros(lanes, d);
                let mut ws = Scratch::new();
                w.flow_batch(&mut ws, mode, x.as_ref(), dx.as_mut());
                let mut f = vec![f64::NAN; d];
                for (l, s) in states.iter().enumerate() {
                    w.flow(&mut ws, mode, s, &mut f);
                    for j in 0..d {
                        assert!(f[j].is_finite(), "{name} mode {mode} lane {l} entry {j}");
                        assert_eq!(
                            dx[(l, j)].to_bits(),
                            f[j].to_bits(),
                            "{name} mode {mode} lanes {lanes} lane {l} entry {j}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn batched_guards_equal_scalar_guards_bit_for_bit() {
    let mut r = ChaCha8Rng::seed_from_u64(6);
    for (name, w) in all_presets() {
        let d = w.dim();
        for mode in 0..w.n_modes() {
            let lanes = 37;
            let states: Vec<Vec<f64>> =
                (0..lanes).map(|_| random_state(&w, &mut r, mode)).collect();
            let x = Mat::from_fn(lanes, d, |l, j| states[l][j]);
            let mut ws = Scratch::new();
            for k in 0..w.guards(mode).len() {
                let mut out = vec![0.0; lanes];
                w.guard_batch(&mut ws, mode, k, x.as_ref(), &mut out);
                for (l, s) in states.iter().enumerate() {
                    let g = w.guard(&mut ws, mode, k, s);
                    assert_eq!(
                        out[l].to_bits(),
                        g.to_bits(),
                        "{name} mode {mode} guard {k} lane {l}"
                    );
                }
            }
        }
    }
}

/// The guards' rates are their time derivatives along the flow: `ġ = ∇g·f` against central
/// differences of the guard along the flow direction, `(g(x + εf) − g(x − εf)) / 2ε`; the values
/// are the bits of `guard`; the batched version equals the scalar one bit for bit; and a guard
/// declared affine is affine (its differences along two directions add up).
#[test]
fn guard_rates_are_the_derivatives_along_the_flow() {
    let mut r = ChaCha8Rng::seed_from_u64(16);
    for (name, w) in all_presets() {
        let d = w.dim();
        for mode in 0..w.n_modes() {
            let ng = w.guards(mode).len();
            let lanes = 29;
            let states: Vec<Vec<f64>> =
                (0..lanes).map(|_| random_state(&w, &mut r, mode)).collect();
            let mut ws = Scratch::new();
            let flows: Vec<Vec<f64>> = states
                .iter()
                .map(|x| {
                    let mut f = vec![0.0; d];
                    w.flow(&mut ws, mode, x, &mut f);
                    f
                })
                .collect();
            let xm = Mat::from_fn(lanes, d, |l, j| states[l][j]);
            let fm = Mat::from_fn(lanes, d, |l, j| flows[l][j]);
            let (mut gb, mut rb) = (Mat::<f64>::zeros(lanes, ng), Mat::<f64>::zeros(lanes, ng));
            w.guards_with_rates_batch(
                &mut ws,
                mode,
                xm.as_ref(),
                fm.as_ref(),
                gb.as_mut(),
                rb.as_mut(),
            );
            for (l, (x, f)) in states.iter().zip(&flows).enumerate() {
                let (mut g, mut rate) = (vec![0.0; ng], vec![0.0; ng]);
                w.guards_with_rates(&mut ws, mode, x, f, &mut g, &mut rate);
                let eps = 1e-6;
                let shifted = |s: f64| -> Vec<f64> {
                    x.iter().zip(f).map(|(xi, fi)| xi + s * eps * fi).collect()
                };
                let (xp, xn) = (shifted(1.0), shifted(-1.0));
                for k in 0..ng {
                    let at = format!("{name} mode {mode} guard {k} lane {l}");
                    assert_eq!(
                        g[k].to_bits(),
                        w.guard(&mut ws, mode, k, x).to_bits(),
                        "{at}"
                    );
                    assert_eq!(gb[(l, k)].to_bits(), g[k].to_bits(), "{at}: batch value");
                    assert_eq!(rb[(l, k)].to_bits(), rate[k].to_bits(), "{at}: batch rate");
                    let fd = (w.guard(&mut ws, mode, k, &xp) - w.guard(&mut ws, mode, k, &xn))
                        / (2.0 * eps);
                    let scale = 1.0 + rate[k].abs();
                    assert!(
                        (fd - rate[k]).abs() <= 1e-7 * scale,
                        "{at}: {} vs {fd}",
                        rate[k]
                    );
                    if w.guard_is_linear(mode, k) {
                        // affine: g(x + a) + g(x + b) = g(x) + g(x + a + b)
                        let (a, b): (Vec<f64>, Vec<f64>) = (
                            x.iter().zip(f).map(|(xi, fi)| xi + 0.3 * fi).collect(),
                            x.iter()
                                .enumerate()
                                .map(|(j, xi)| xi - 0.2 * (j as f64 - 1.5))
                                .collect(),
                        );
                        let ab: Vec<f64> = a
                            .iter()
                            .zip(&b)
                            .zip(x)
                            .map(|((ai, bi), xi)| ai + bi - xi)
                            .collect();
                        let lhs = w.guard(&mut ws, mode, k, &a) + w.guard(&mut ws, mode, k, &b);
                        let rhs = w.guard(&mut ws, mode, k, x) + w.guard(&mut ws, mode, k, &ab);
                        assert!((lhs - rhs).abs() <= 1e-12, "{at}: declared affine, is not");
                    }
                }
            }
        }
    }
}

/// Units of every preset as its TOML text declares them, read here with the `toml` crate and not
/// through [`WalkerSpec`]: time in the unit of `max_stride_time` (the kneed preset's `T`, Hsu
/// Chen's time unit), lengths in m when time is in s and in the leg length `l` otherwise, forces
/// and torques in N and N m (M L/T^2 and M L^2/T^2 for a spec in its own units). The kneed preset is named explicitly: its outputs were once
/// labelled rad/s and m while its parameters are in Hsu Chen's units.
#[test]
fn every_preset_reports_the_units_its_file_declares() {
    for (name, text) in pdw_walkers::PRESETS {
        let raw: toml::Table = text.parse().expect("preset TOML");
        let declared = raw["parameters"]["max_stride_time"]["unit"]
            .as_str()
            .expect("max_stride_time has a unit");
        let w = ChainWalker::from_spec(WalkerSpec::from_toml(text, name).unwrap()).unwrap();
        let u = w.units();
        assert_eq!(u.time, declared, "{name}: time unit");
        let length = if declared == "s" { "m" } else { "l" };
        assert_eq!(u.length, length, "{name}: length unit");
        // a spec in its own units L, M, T has no newtons: M L/T^2 and M L^2/T^2
        let own = declared == "T";
        let want = if own {
            ("M L/T^2", "M L^2/T^2", "M L^2/T^2")
        } else {
            ("N", "N m", "J")
        };
        assert_eq!(
            (u.force.as_ref(), u.torque.as_ref(), w.energy_unit()),
            want,
            "{name}"
        );
    }
    let kneed = presets::kneed(&[]).unwrap().units();
    assert_eq!((kneed.time.as_ref(), kneed.length.as_ref()), ("T", "l"));
    assert_eq!(kneed.torque, "M L^2/T^2");
    let compass = presets::compass(&[]).unwrap().units();
    assert_eq!((compass.time.as_ref(), compass.length.as_ref()), ("s", "m"));
}
