//! Physics claims about the simplest walker, each checked against an independent derivation
//! (Newtonian mechanics in a slope frame) rather than against the model's own formulas.

use faer::Mat;
use pdw_hybrid::{HybridSystem, Scratch, Section};
use pdw_walkers::simplest::{Simplest, SimplestParams, HEEL_STRIKE};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn model(gamma: f64) -> Simplest {
    Simplest::new(SimplestParams {
        slope: gamma,
        ..Default::default()
    })
    .unwrap()
}

type V2 = [f64; 2];
fn dot(a: V2, b: V2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
fn cross(a: V2, b: V2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// Slope frame: x downhill along the slope, y along the normal; gravity (sin γ, −cos γ).
/// Hip = (−sin θ, cos θ) from the stance foot; swing leg absolute angle ψ = θ − φ, swing foot =
/// hip + (sin ψ, −cos ψ). The stance leg is massless with a point-mass hip, so the hip's
/// tangential acceleration is gravity's tangential component; the swing leg is a massless rod
/// with a point foot hanging from the accelerating hip, so the foot's acceleration along the
/// leg's tangent equals gravity's. Returns (θ̈, φ̈).
fn newton_accelerations(gamma: f64, th: f64, thd: f64, ph: f64, phd: f64) -> (f64, f64) {
    let grav = [gamma.sin(), -gamma.cos()];
    let e_th = [-th.cos(), -th.sin()]; // d(hip)/dθ
    let thdd = dot(grav, e_th);
    let a_hip = [
        thdd * e_th[0] + thd * thd * th.sin(),
        thdd * e_th[1] - thd * thd * th.cos(),
    ];
    let psi = th - ph;
    let psid = thd - phd;
    let t = [psi.cos(), psi.sin()]; // d(foot − hip)/dψ
                                    // foot acceleration = a_hip + ψ̈ t + ψ̇² (−sin ψ, cos ψ); the last term is ⟂ t.
    let _ = psid;
    let psidd = dot(grav, t) - dot(a_hip, t);
    (thdd, thdd - psidd)
}

#[test]
fn vector_field_matches_newtonian_derivation_at_random_states() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..1000 {
        let gamma = rng.random_range(-0.5..0.5);
        let m = model(gamma);
        let x = [
            rng.random_range(-1.2..1.2),
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
        ];
        let mut f = [0.0; 4];
        m.flow(&mut Scratch::new(), 0, &x, &mut f);
        let (thdd, phdd) = newton_accelerations(gamma, x[0], x[1], x[2], x[3]);
        assert_eq!(f[0], x[1]);
        assert_eq!(f[2], x[3]);
        assert!((f[1] - thdd).abs() < 1e-14, "θ̈ {} vs {}", f[1], thdd);
        assert!((f[3] - phdd).abs() < 1e-13, "φ̈ {} vs {}", f[3], phdd);
    }
}

#[test]
fn energy_rate_vanishes_along_the_flow() {
    // dE/dt = ∇E · f with E = ½θ̇² + cos(θ − γ), checked at random states.
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let m = model(0.009);
    for _ in 0..200 {
        let x: Vec<f64> = (0..4).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mut f = [0.0; 4];
        m.flow(&mut Scratch::new(), 0, &x, &mut f);
        let de = -(x[0] - 0.009).sin() * f[0] + x[1] * f[1];
        assert!(de.abs() < 1e-15);
    }
}

#[test]
fn heel_strike_conserves_hip_angular_momentum_about_new_contact_and_foot_about_hip() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let m = model(0.009);
    for _ in 0..500 {
        let th: f64 = rng.random_range(-0.7..-0.01);
        let thd: f64 = rng.random_range(-1.5..-0.01);
        let xm = [th, thd, 2.0 * th, rng.random_range(-1.0..1.0)];
        let mut xp = [0.0; 4];
        m.reset(&mut Scratch::new(), 0, HEEL_STRIKE, &xm, &mut xp);

        // Geometry before impact (old stance foot at the origin).
        let hip = [-th.sin(), th.cos()];
        let v_hip = [-th.cos() * thd, -th.sin() * thd];
        let psi = th - xm[2];
        let new_contact = [hip[0] + psi.sin(), hip[1] - psi.cos()];
        assert!(new_contact[1].abs() < 1e-15, "swing foot on the ground");
        // After: the new stance leg is the old swing leg; the hip must keep its position.
        let hip_after = [new_contact[0] - xp[0].sin(), new_contact[1] + xp[0].cos()];
        assert!((hip_after[0] - hip[0]).abs() < 1e-15 && (hip_after[1] - hip[1]).abs() < 1e-15);
        let v_after = [-xp[0].cos() * xp[1], -xp[0].sin() * xp[1]];
        // Hip angular momentum about the new contact point.
        let r = [hip[0] - new_contact[0], hip[1] - new_contact[1]];
        let l_before = cross(r, v_hip);
        let l_after = cross(r, v_after);
        assert!((l_before - l_after).abs() < 1e-12 * (1.0 + l_before.abs()));
        // The impulse is along the new stance leg: v⁺ ⟂ new leg.
        assert!(dot(v_after, r).abs() < 1e-14);
        // Trailing (new swing) foot: the old stance foot at the origin, at rest before impact;
        // its angular momentum about the hip is conserved, i.e. its velocity perpendicular to
        // its leg stays zero: v_hip⁺ + ψ̇⁺ (cos ψ⁺, sin ψ⁺) has no component along (cos ψ⁺, sin ψ⁺).
        let psi_p = xp[0] - xp[2];
        let psid_p = xp[1] - xp[3];
        let foot_p = [hip[0] + psi_p.sin(), hip[1] - psi_p.cos()];
        assert!(
            foot_p[0].abs() < 1e-15 && foot_p[1].abs() < 1e-15,
            "new swing foot = old stance foot"
        );
        let t = [psi_p.cos(), psi_p.sin()];
        let v_foot = [v_after[0] + psid_p * t[0], v_after[1] + psid_p * t[1]];
        assert!(cross([foot_p[0] - hip[0], foot_p[1] - hip[1]], v_foot).abs() < 1e-14);
        // Kinetic energy lost exactly as the impulse predicts: ½(|v⁻|² − |v⁺|²) = ½ (v⁻·e)².
        let e = [r[0] / r[0].hypot(r[1]), r[1] / r[0].hypot(r[1])];
        let lost = 0.5 * (dot(v_hip, v_hip) - dot(v_after, v_after));
        assert!((lost - 0.5 * dot(v_hip, e).powi(2)).abs() < 1e-14);
    }
}

#[test]
fn lift_reproduces_every_post_heel_strike_state() {
    // The section is the image of the jump map: lift(project(R(x⁻))) == R(x⁻).
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    let m = model(0.009);
    for _ in 0..500 {
        let th: f64 = rng.random_range(-0.7..-0.01);
        let xm = [
            th,
            rng.random_range(-1.5..0.0),
            2.0 * th,
            rng.random_range(-1.0..1.0),
        ];
        let mut xp = [0.0; 4];
        m.reset(&mut Scratch::new(), 0, HEEL_STRIKE, &xm, &mut xp);
        let mut s = [0.0; 2];
        m.project(&xp, &mut s);
        let mut xl = [0.0; 4];
        m.lift(&s, &mut xl);
        for j in 0..4 {
            assert!(
                (xl[j] - xp[j]).abs() < 1e-15 * (1.0 + xp[j].abs()),
                "component {j}"
            );
        }
        // and the lifted state is on the heel-strike surface g = 0
        assert!(m.guard(&mut Scratch::new(), 0, HEEL_STRIKE, &xl).abs() < 1e-15);
    }
}

#[test]
fn scuffing_crossing_is_not_admissible_as_heel_strike() {
    let m = model(0.009);
    // Mid-stance: legs about to coincide, swing foot behind or at the stance foot (θ ≥ 0).
    assert!(!m.admissible(0, HEEL_STRIKE, &[0.02, -0.2, 0.04, -0.4]));
    // Right after a heel strike (g = 0 again, θ > 0).
    assert!(!m.admissible(0, HEEL_STRIKE, &[0.2, -0.2, 0.4, -0.01]));
    // A genuine heel strike: swing foot ahead (θ < 0).
    assert!(m.admissible(0, HEEL_STRIKE, &[-0.2, -0.2, -0.4, 0.3]));
}

#[test]
fn closed_form_jacobians_match_central_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let m = model(0.05);
    for _ in 0..100 {
        let x: Vec<f64> = (0..4).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mut jac = [0.0; 16];
        let mut rjac = [0.0; 16];
        m.flow_jacobian(&mut Scratch::new(), 0, &x, &mut jac);
        m.reset_jacobian(&mut Scratch::new(), 0, 0, &x, &mut rjac);
        let h = 1e-6;
        for j in 0..4 {
            let mut xp = x.clone();
            let mut xm = x.clone();
            xp[j] += h;
            xm[j] -= h;
            let (mut fp, mut fm, mut rp, mut rm) = ([0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4]);
            m.flow(&mut Scratch::new(), 0, &xp, &mut fp);
            m.flow(&mut Scratch::new(), 0, &xm, &mut fm);
            m.reset(&mut Scratch::new(), 0, 0, &xp, &mut rp);
            m.reset(&mut Scratch::new(), 0, 0, &xm, &mut rm);
            for i in 0..4 {
                assert!((jac[i * 4 + j] - (fp[i] - fm[i]) / (2.0 * h)).abs() < 1e-8);
                assert!((rjac[i * 4 + j] - (rp[i] - rm[i]) / (2.0 * h)).abs() < 1e-8);
            }
        }
        let mut grad = [0.0; 4];
        m.guard_gradient(&mut Scratch::new(), 0, HEEL_STRIKE, &x, &mut grad);
        assert_eq!(grad, [-2.0, 0.0, 1.0, 0.0]);
    }
}

#[test]
fn batched_flow_is_bit_identical_to_scalar_flow() {
    // Blocks of lanes whose angles are all small take the trigonometric shortcut, the others the
    // full routine, lanes beyond the reduced range libm: every kind, mixed within and across
    // blocks, on every instruction-set path, must give the scalar flow's bits.
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let m = model(0.009);
    for p in pdw_simd::available_paths() {
        pdw_simd::set_path(p).unwrap();
        for lanes in [1usize, 3, 4, 5, 13, 64, 65, 200] {
            for case in 0..5 {
                let mut x = Mat::<f64>::from_fn(lanes, 4, |_, j| match (case, j) {
                    // Near the gait: θ − γ and φ below the shortcut's bound (0.78).
                    (0, 0) => rng.random_range(-0.38..0.38),
                    (0, 2) => rng.random_range(-0.77..0.77),
                    // Around the bound.
                    (1, 0) | (1, 2) => rng.random_range(-0.9..0.9),
                    _ => rng.random_range(-2.0..2.0),
                });
                if case == 3 {
                    x[(lanes / 2, 0)] = 1.0e4;
                    x[(lanes - 1, 2)] = -3.0e5;
                }
                if case == 4 {
                    x[(lanes / 2, 2)] = f64::NAN;
                    x[(0, 0)] = f64::INFINITY;
                }
                let mut dx = Mat::<f64>::zeros(lanes, 4);
                m.flow_batch(&mut Scratch::new(), 0, x.as_ref(), dx.as_mut());
                for l in 0..lanes {
                    let xi: Vec<f64> = (0..4).map(|j| x[(l, j)]).collect();
                    let mut f = [0.0; 4];
                    m.flow(&mut Scratch::new(), 0, &xi, &mut f);
                    for j in 0..4 {
                        assert!(
                            f[j].to_bits() == dx[(l, j)].to_bits()
                                || (f[j].is_nan() && dx[(l, j)].is_nan()),
                            "path {p} lanes {lanes} case {case} lane {l} comp {j}: {} vs {}",
                            f[j],
                            dx[(l, j)]
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn simd_trigonometry_agrees_with_libm() {
    // pdw-simd's sin/cos vs libm through the vector field: |Δθ̈| within a few ulp.
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let m = model(0.0);
    for _ in 0..1000 {
        let x = [rng.random_range(-3.0..3.0), 0.0, 0.0, 0.0];
        let mut f = [0.0; 4];
        m.flow(&mut Scratch::new(), 0, &x, &mut f);
        assert!((f[1] - x[0].sin()).abs() <= 4.0 * f64::EPSILON);
    }
}

#[test]
fn invalid_parameters_are_rejected_with_the_name() {
    for bad in [f64::NAN, 1.6, -1.6, f64::INFINITY] {
        let err = Simplest::new(SimplestParams {
            slope: bad,
            ..Default::default()
        })
        .unwrap_err();
        assert!(err.to_string().contains("slope"), "{err}");
    }
    assert!(Simplest::new(SimplestParams {
        max_stride_time: 0.0,
        ..Default::default()
    })
    .is_err());
}

#[test]
fn registry_lists_models_and_rejects_unknown_names() {
    let names: Vec<_> = pdw_walkers::models().into_iter().map(|m| m.name).collect();
    for n in ["rimless", "simplest", "compass", "kneed", "seed5"] {
        assert!(names.iter().any(|m| m == n), "{n} not in {names:?}");
    }
    let e = pdw_walkers::build("nosuch", &[]).err().unwrap().to_string();
    assert!(e.contains("simplest") && e.contains("rimless"), "{e}");
    let e = pdw_walkers::build("simplest", &[("mass", 1.0)])
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("slope"), "{e}");
    let w = pdw_walkers::build("simplest", &[("slope", 0.01)]).unwrap();
    assert_eq!(w.param_values()[0], ("slope".to_string(), 0.01));
    assert_eq!(w.section_names(), &["theta", "thetadot"]);
}

/// The stance-foot ground reaction per unit hip weight equals the hip's acceleration (measured
/// by central differences of the hip velocity along the flow) minus gravity (Newton's second
/// law for the point-mass hip on massless legs).
#[test]
fn ground_reaction_is_hip_mass_times_acceleration_minus_gravity() {
    let gamma = 0.009;
    let w = pdw_walkers::build("simplest", &[("slope", gamma)]).unwrap();
    let hip_vel = |x: &[f64]| [-x[0].cos() * x[1], -x[0].sin() * x[1]];
    let mut seed = 0x2545F4914F6CDD1Du64;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for _ in 0..200 {
        let x = [0.6 * rnd(), rnd(), 0.8 * rnd(), rnd()];
        let mut f = [0.0; 4];
        w.flow(&mut Scratch::new(), 0, &x, &mut f);
        let h = 1e-5;
        let xp: Vec<f64> = x.iter().zip(&f).map(|(a, b)| a + h * b).collect();
        let xm: Vec<f64> = x.iter().zip(&f).map(|(a, b)| a - h * b).collect();
        let (vp, vm) = (hip_vel(&xp), hip_vel(&xm));
        let a = [(vp[0] - vm[0]) / (2.0 * h), (vp[1] - vm[1]) / (2.0 * h)];
        let cf = w.constraint_forces(0, &x).unwrap();
        assert!(
            (cf.tangential - (a[0] - gamma.sin())).abs() < 1e-8,
            "{cf:?} {a:?}"
        );
        assert!(
            (cf.normal - (a[1] + gamma.cos())).abs() < 1e-8,
            "{cf:?} {a:?}"
        );
    }
    // standing still, hip vertically above the foot: the reaction is the weight
    let cf = w.constraint_forces(0, &[gamma, 0.0, 0.0, 0.0]).unwrap();
    assert!((cf.normal - gamma.cos()).abs() < 1e-15 && (cf.tangential + gamma.sin()).abs() < 1e-15);
}

/// The simplest walker's guard rates equal the derivative of each guard along the flow
/// (central differences), its values are `guard`'s bits, the batch gives the scalar bits, and
/// every guard is affine as declared.
#[test]
fn simplest_guard_rates_are_the_derivatives_along_the_flow() {
    let w = Simplest::new(SimplestParams::default()).unwrap();
    let mut ws = Scratch::new();
    let states: Vec<[f64; 4]> = (0..23)
        .map(|i| {
            let t = i as f64 / 23.0;
            [
                0.3 - 0.6 * t,
                -0.2 + 0.1 * t,
                0.4 - 0.5 * t,
                0.05 * (t - 0.5),
            ]
        })
        .collect();
    let flows: Vec<[f64; 4]> = states
        .iter()
        .map(|x| {
            let mut f = [0.0; 4];
            w.flow(&mut ws, 0, x, &mut f);
            f
        })
        .collect();
    let n = states.len();
    let xm = Mat::from_fn(n, 4, |l, j| states[l][j]);
    let fm = Mat::from_fn(n, 4, |l, j| flows[l][j]);
    let (mut gb, mut rb) = (Mat::<f64>::zeros(n, 4), Mat::<f64>::zeros(n, 4));
    w.guards_with_rates_batch(
        &mut ws,
        0,
        xm.as_ref(),
        fm.as_ref(),
        gb.as_mut(),
        rb.as_mut(),
    );
    for (l, (x, f)) in states.iter().zip(&flows).enumerate() {
        let (mut g, mut r) = ([0.0; 4], [0.0; 4]);
        w.guards_with_rates(&mut ws, 0, x, f, &mut g, &mut r);
        let eps = 1e-6;
        let xp: Vec<f64> = x.iter().zip(f).map(|(a, b)| a + eps * b).collect();
        let xn: Vec<f64> = x.iter().zip(f).map(|(a, b)| a - eps * b).collect();
        for k in 0..4 {
            assert!(w.guard_is_linear(0, k));
            assert_eq!(g[k].to_bits(), w.guard(&mut ws, 0, k, x).to_bits());
            assert_eq!(gb[(l, k)].to_bits(), g[k].to_bits());
            assert_eq!(rb[(l, k)].to_bits(), r[k].to_bits());
            let fd = (w.guard(&mut ws, 0, k, &xp) - w.guard(&mut ws, 0, k, &xn)) / (2.0 * eps);
            assert!(
                (fd - r[k]).abs() <= 1e-9,
                "guard {k} lane {l}: {} vs {fd}",
                r[k]
            );
        }
    }
}

/// The simplest walker behind a wrapper that gives no guard rates (so every step samples its
/// interior, the detection without the end-point test). It keeps the affine declarations,
/// which choose how a located root is refined.
struct NoRates(Simplest);

pdw_hybrid::integrate_through_dyn!(NoRates);
impl HybridSystem for NoRates {
    fn dim(&self) -> usize {
        self.0.dim()
    }
    fn guards(&self, mode: usize) -> &[pdw_hybrid::GuardSpec] {
        self.0.guards(mode)
    }
    fn flow(&self, ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]) {
        self.0.flow(ws, mode, x, dx)
    }
    fn guard(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64]) -> f64 {
        self.0.guard(ws, mode, k, x)
    }
    fn admissible(&self, mode: usize, k: usize, x: &[f64]) -> bool {
        self.0.admissible(mode, k, x)
    }
    fn guard_is_linear(&self, mode: usize, k: usize) -> bool {
        self.0.guard_is_linear(mode, k)
    }
    fn reset(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], out: &mut [f64]) -> usize {
        self.0.reset(ws, mode, k, x, out)
    }
}

/// Clearing steps from their end points changes nothing: 40 steps from perturbed gaits with
/// every method give the same stop reasons, times and states, bit for bit, with and without the
/// guard rates, while the rates leave only a few steps per stride to sample.
#[test]
fn end_point_test_changes_no_event() {
    use pdw_hybrid::{Integrator, Options, StopReason};
    let w = Simplest::new(SimplestParams::default()).unwrap();
    let plain = NoRates(w.clone());
    let mut rng = ChaCha8Rng::seed_from_u64(40);
    for opts in [
        Options::dopri5(1e-9),
        Options::dop853(1e-11),
        Options::rk4(0.05),
    ] {
        let (mut a, mut b) = (
            Integrator::new(4, opts).unwrap(),
            Integrator::new(4, opts).unwrap(),
        );
        for _ in 0..8 {
            let s = [
                0.2 + rng.random_range(-0.02..0.02),
                -0.2 + rng.random_range(-0.02..0.02),
            ];
            let mut xa = [0.0; 4];
            w.lift(&s, &mut xa);
            let mut xb = xa;
            let (mut ta, mut tb) = (0.0, 0.0);
            for _ in 0..5 {
                let (ea, eb) = (ta + 12.0, tb + 12.0);
                let ra = a.integrate(&w as &dyn pdw_hybrid::HybridSystem, 0, &mut ta, &mut xa, ea);
                let rb = b.integrate(
                    &plain as &dyn pdw_hybrid::HybridSystem,
                    0,
                    &mut tb,
                    &mut xb,
                    eb,
                );
                assert_eq!(ra, rb, "{opts:?}");
                assert_eq!(ta.to_bits(), tb.to_bits(), "{opts:?}");
                for j in 0..4 {
                    assert_eq!(xa[j].to_bits(), xb[j].to_bits(), "{opts:?}");
                }
                match ra {
                    StopReason::Guard { guard: HEEL_STRIKE } => {
                        let mut out = [0.0; 4];
                        w.reset(a.scratch(), 0, HEEL_STRIKE, &xa, &mut out);
                        (xa, xb) = (out, out);
                    }
                    _ => break,
                }
            }
        }
        let (sa, sb) = (a.stats(), b.stats());
        assert_eq!(sa.accepted, sb.accepted);
        assert_eq!(
            sb.sampled, sb.accepted,
            "without rates every step is sampled"
        );
        assert!(
            2 * sa.sampled < sa.accepted,
            "{opts:?}: {} of {} steps sampled",
            sa.sampled,
            sa.accepted
        );
    }
}
