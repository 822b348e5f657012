//! Physics claims about the compass gait (the `compass` preset of the chain walker,
//! `models/compass.toml`), each against an independent reference: Goswami's closed-form M, C, G
//! and heel-strike matrices Q⁻, Q⁺ (written here from the paper, not from the kernel),
//! conservation laws computed from point-mass positions and velocities, Garcia's simplest walker
//! as the small-leg-mass limit.

use pdw_hybrid::{HybridSystem, Integrator, Options, Scratch, Section, StopReason};
use pdw_walkers::{presets, ChainWalker, StepFlags, Walker, WalkerError};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Guard index of the heel strike (the compass has one mode, 0).
const HEEL_STRIKE: usize = 0;

/// Goswami et al.'s parameters, held by the test (the reference computations use these, never
/// the walker's own geometry).
#[derive(Clone, Copy, Debug)]
struct Gp {
    leg_mass: f64,
    hip_mass: f64,
    a: f64,
    b: f64,
    slope: f64,
    gravity: f64,
}

/// Goswami et al. 1998's preset: m = 5, m_H = 10, a = b = 0.5, 3°, g = 9.81.
const GOSWAMI: Gp = Gp {
    leg_mass: 5.0,
    hip_mass: 10.0,
    a: 0.5,
    b: 0.5,
    slope: 0.05235987755982988,
    gravity: 9.81,
};

fn walker(p: &Gp) -> ChainWalker {
    presets::compass(&[
        ("leg_mass", p.leg_mass),
        ("hip_mass", p.hip_mass),
        ("a", p.a),
        ("b", p.b),
        ("slope", p.slope),
        ("gravity", p.gravity),
    ])
    .unwrap()
}

fn goswami() -> ChainWalker {
    // the preset's defaults are Goswami's: building with no overrides must equal GOSWAMI
    let w = presets::compass(&[]).unwrap();
    let v = w.param_values();
    let get = |n: &str| v.iter().find(|p| p.0 == n).map(|p| p.1).unwrap();
    assert_eq!(
        [
            get("leg_mass"),
            get("hip_mass"),
            get("a"),
            get("b"),
            get("slope"),
            get("gravity")
        ],
        [
            GOSWAMI.leg_mass,
            GOSWAMI.hip_mass,
            GOSWAMI.a,
            GOSWAMI.b,
            GOSWAMI.slope,
            GOSWAMI.gravity
        ]
    );
    w
}

/// Goswami et al. (1998) equations of motion `M(θ)θ̈ + C(θ,θ̇)θ̇ + G(θ) = 0` with
/// `θ = (θ_ns, θ_s)` measured from the vertical; returns θ̈.
fn goswami_accel(p: &Gp, th: [f64; 2], thd: [f64; 2]) -> [f64; 2] {
    let (m, mh, a, b, g) = (p.leg_mass, p.hip_mass, p.a, p.b, p.gravity);
    let l = a + b;
    let (ns, s) = (th[0], th[1]);
    let mm = [
        [m * b * b, -m * l * b * (s - ns).cos()],
        [-m * l * b * (s - ns).cos(), (mh + m) * l * l + m * a * a],
    ];
    let cc = [
        [0.0, m * l * b * (s - ns).sin() * thd[1]],
        [-m * l * b * (s - ns).sin() * thd[0], 0.0],
    ];
    let gg = [
        m * b * g * ns.sin(),
        -(mh * l + m * a + m * l) * g * s.sin(),
    ];
    let rhs = [
        -(cc[0][0] * thd[0] + cc[0][1] * thd[1] + gg[0]),
        -(cc[1][0] * thd[0] + cc[1][1] * thd[1] + gg[1]),
    ];
    solve2(mm, rhs)
}

fn solve2(a: [[f64; 2]; 2], b: [f64; 2]) -> [f64; 2] {
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    [
        (b[0] * a[1][1] - a[0][1] * b[1]) / det,
        (a[0][0] * b[1] - a[1][0] * b[0]) / det,
    ]
}

/// Goswami et al. (1998) heel-strike map `Q⁺(α) θ̇⁺ = Q⁻(α) θ̇⁻`, `θ̇ = (θ̇_ns, θ̇_s)`, with the
/// legs relabelled (the new stance leg is the old swing leg); `α` the half inter-leg angle.
fn goswami_impact(p: &Gp, alpha: f64, thd: [f64; 2]) -> [f64; 2] {
    let (m, mh, a, b) = (p.leg_mass, p.hip_mass, p.a, p.b);
    let l = a + b;
    let c2 = (2.0 * alpha).cos();
    let qm = [
        [-m * a * b, -m * a * b + (mh * l * l + 2.0 * m * a * l) * c2],
        [0.0, -m * a * b],
    ];
    let qp = [
        [
            m * b * (b - l * c2),
            m * l * (l - b * c2) + m * a * a + mh * l * l,
        ],
        [m * b * b, -m * b * l * c2],
    ];
    let r = [
        qm[0][0] * thd[0] + qm[0][1] * thd[1],
        qm[1][0] * thd[0] + qm[1][1] * thd[1],
    ];
    solve2(qp, r)
}

type Pm = Vec<(f64, [f64; 2], [f64; 2])>;

/// Point masses of the compass (mass, position, velocity) at state `x`, stance foot at origin
/// (slope frame: `y` downhill, `z` along the slope normal).
fn point_masses(p: &Gp, x: &[f64]) -> Pm {
    let l = p.a + p.b;
    let (q1, psi) = (x[0], x[0] + x[1]);
    let (w1, wp) = (x[2], x[2] + x[3]);
    let up = [-q1.sin(), q1.cos()];
    let dup = [-q1.cos() * w1, -q1.sin() * w1];
    let down = [psi.sin(), -psi.cos()];
    let ddown = [psi.cos() * wp, psi.sin() * wp];
    let hip = [l * up[0], l * up[1]];
    let vhip = [l * dup[0], l * dup[1]];
    vec![
        (
            p.leg_mass,
            [p.a * up[0], p.a * up[1]],
            [p.a * dup[0], p.a * dup[1]],
        ),
        (p.hip_mass, hip, vhip),
        (
            p.leg_mass,
            [hip[0] + p.b * down[0], hip[1] + p.b * down[1]],
            [vhip[0] + p.b * ddown[0], vhip[1] + p.b * ddown[1]],
        ),
    ]
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn ang_mom(pm: &[(f64, [f64; 2], [f64; 2])], c: [f64; 2]) -> f64 {
    pm.iter()
        .map(|(m, r, v)| m * cross([r[0] - c[0], r[1] - c[1]], *v))
        .sum()
}

fn kinetic(pm: &[(f64, [f64; 2], [f64; 2])]) -> f64 {
    pm.iter()
        .map(|(m, _, v)| 0.5 * m * (v[0] * v[0] + v[1] * v[1]))
        .sum()
}

/// Potential energy in the slope frame (gravity `g (sin γ, −cos γ)`), zero at the stance foot.
fn potential(p: &Gp, pm: &[(f64, [f64; 2], [f64; 2])]) -> f64 {
    let gvec = [p.gravity * p.slope.sin(), -p.gravity * p.slope.cos()];
    pm.iter()
        .map(|(m, r, _)| -m * (gvec[0] * r[0] + gvec[1] * r[1]))
        .sum()
}

fn random_state(rng: &mut ChaCha8Rng) -> [f64; 4] {
    [
        rng.random_range(-0.6..0.6),
        rng.random_range(-1.2..1.2),
        rng.random_range(-3.0..3.0),
        rng.random_range(-5.0..5.0),
    ]
}

#[test]
fn vector_field_equals_goswami_closed_form() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut ws = Scratch::new();
    for params in [
        GOSWAMI,
        Gp {
            leg_mass: 2.0,
            hip_mass: 7.0,
            a: 0.3,
            b: 0.6,
            slope: 0.1,
            ..GOSWAMI
        },
    ] {
        let w = walker(&params);
        let mut worst: f64 = 0.0;
        for _ in 0..200 {
            let x = random_state(&mut rng);
            let mut dx = [0.0; 4];
            w.flow(&mut ws, 0, &x, &mut dx);
            // θ_s = q₁ − γ, θ_ns = q₁ + q₂ − γ
            let g = params.slope;
            let th = [x[0] + x[1] - g, x[0] - g];
            let thd = [x[2] + x[3], x[2]];
            let acc = goswami_accel(&params, th, thd);
            let expect = [x[2], x[3], acc[1], acc[0] - acc[1]];
            let scale = expect.iter().fold(1.0f64, |s, v| s.max(v.abs()));
            for i in 0..4 {
                worst = worst.max((dx[i] - expect[i]).abs() / scale);
            }
        }
        assert!(
            worst < 1e-12,
            "chain walker vector field vs Goswami: worst relative error {worst:e}"
        );
    }
}

/// Pre-impact states on the heel-strike surface `q₂ = −2q₁` with the swing foot ahead.
fn heel_strike_states(rng: &mut ChaCha8Rng, n: usize) -> Vec<[f64; 4]> {
    (0..n)
        .map(|_| {
            let a: f64 = rng.random_range(0.05..0.5);
            [
                -a,
                2.0 * a,
                rng.random_range(-2.5..-0.2),
                rng.random_range(-3.0..3.0),
            ]
        })
        .collect()
}

#[test]
fn heel_strike_equals_goswami_impact_map() {
    let w = goswami();
    let p = GOSWAMI;
    assert_eq!(w.section_guard(), (0, HEEL_STRIKE));
    let mut ws = Scratch::new();
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    for x in heel_strike_states(&mut rng, 100) {
        let mut out = [0.0; 4];
        assert_eq!(w.reset(&mut ws, 0, HEEL_STRIKE, &x, &mut out), 0);
        let alpha = 0.5 * x[1];
        let post = goswami_impact(&p, alpha, [x[2] + x[3], x[2]]);
        // after relabelling: new stance rate = θ̇_s⁺, new swing absolute rate = θ̇_ns⁺
        let expect = [-x[0], 2.0 * x[0], post[1], post[0] - post[1]];
        for i in 0..4 {
            assert!(
                (out[i] - expect[i]).abs() < 1e-12 * (1.0 + expect[i].abs()),
                "component {i}: chain walker impact {} vs Goswami {}",
                out[i],
                expect[i]
            );
        }
    }
}

#[test]
fn impact_conserves_angular_momentum_about_contact_and_trailing_leg_about_hip() {
    let w = goswami();
    let p = GOSWAMI;
    let l = p.a + p.b;
    let mut ws = Scratch::new();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for x in heel_strike_states(&mut rng, 100) {
        let mut v = [0.0; 4];
        let impulse = w.heel_strike(&mut ws, &x, &mut v);
        let pre = point_masses(&p, &x);
        // post-impact motion in the old coordinates: base (old stance foot) moves with (v0, v1)
        let post_rel = point_masses(&p, &[x[0], x[1], v[2], v[3]]);
        let post: Vec<_> = post_rel
            .iter()
            .map(|(m, r, u)| (*m, *r, [u[0] + v[0], u[1] + v[1]]))
            .collect();
        // the contact point from the test's own kinematics (and the walker's agrees)
        let (q1, psi) = (x[0], x[0] + x[1]);
        let contact = [l * (psi.sin() - q1.sin()), l * (q1.cos() - psi.cos())];
        let sf = w.swing_foot(&x);
        assert!((sf[0] - contact[0]).abs() < 1e-15 && (sf[1] - contact[1]).abs() < 1e-15);
        let hip = [-l * x[0].sin(), l * x[0].cos()];
        let h0 = ang_mom(&pre, contact);
        let h1 = ang_mom(&post, contact);
        let scale = pre
            .iter()
            .map(|(m, _, u)| m * l * u[0].hypot(u[1]))
            .sum::<f64>();
        assert!(
            (h0 - h1).abs() < 1e-12 * scale,
            "about contact: {h0} vs {h1}"
        );
        // trailing leg (old stance leg: its mass, index 0) about the hip
        let t0 = ang_mom(&pre[0..1], hip);
        let t1 = ang_mom(&post[0..1], hip);
        assert!(
            (t0 - t1).abs() < 1e-12 * scale,
            "trailing leg about hip: {t0} vs {t1}"
        );
        // energy: T⁻ − T⁺ equals the impulse's work −½ Λ·v_c⁻ (plastic, v_c⁺ = 0)
        let vc = [
            l * (-q1.cos() * x[2] + psi.cos() * (x[2] + x[3])),
            l * (-q1.sin() * x[2] + psi.sin() * (x[2] + x[3])),
        ];
        let (k0, k1) = (kinetic(&pre), kinetic(&post));
        let work = 0.5 * (impulse[0] * vc[0] + impulse[1] * vc[1]);
        assert!(
            ((k1 - k0) - work).abs() < 1e-12 * k0,
            "ΔT = {} vs impulse work {}",
            k1 - k0,
            work
        );
        // the post-swap state's kinetic energy (new chain, base at rest) is the same
        let mut post_state = [0.0; 4];
        w.reset(&mut ws, 0, HEEL_STRIKE, &x, &mut post_state);
        let pm_new = point_masses(&p, &post_state);
        assert!((kinetic(&pm_new) - k1).abs() < 1e-12 * k0);
    }
}

/// Runs one step with DOP853 from the section state `s`: stop reason, time, pre-impact state,
/// relative energy drift.
fn one_step(w: &ChainWalker, s: &[f64], tol: f64) -> (StopReason, f64, [f64; 4], f64) {
    let mut x = [0.0; 4];
    w.lift(s, &mut x);
    let e0 = w.energy(&x).unwrap();
    let mut integ = Integrator::new(4, Options::dop853(tol)).unwrap();
    let mut t = 0.0;
    let mut drift: f64 = 0.0;
    let stop = integ.integrate_observed(
        w as &dyn pdw_hybrid::HybridSystem,
        0,
        &mut t,
        &mut x,
        5.0,
        &mut |_, y| {
            drift = drift.max((w.energy(y).unwrap() - e0).abs());
        },
    );
    (stop, t, x, drift / e0.abs().max(1.0))
}

#[test]
fn energy_is_point_mass_energy_and_conserved_between_impacts() {
    let w = goswami();
    // the walker's energy is T + V of the point masses (potential zero at the stance foot)
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..50 {
        let x = random_state(&mut rng);
        let pm = point_masses(&GOSWAMI, &x);
        let e = kinetic(&pm) + potential(&GOSWAMI, &pm);
        let we = w.energy(&x).unwrap();
        assert!(
            (we - e).abs() < 1e-12 * (1.0 + e.abs()),
            "energy {we} vs point masses {e}"
        );
    }
    // a post-impact state near the 3° gait
    let s = [0.271, -1.09, 0.715];
    let (stop, t, x, drift) = one_step(&w, &s, 1e-13);
    assert_eq!(
        stop,
        StopReason::Guard { guard: HEEL_STRIKE },
        "t = {t}, x = {x:?}"
    );
    assert!(
        drift < 1e-10,
        "relative energy drift over a step: {drift:e}"
    );
}

#[test]
fn scuffing_crossing_is_never_heel_strike() {
    let w = goswami();
    // on the scuff factor (legs together), swing foot height crosses zero: never admissible
    for q1 in [-0.3, -0.1, 0.0, 0.05, 0.2] {
        for q2 in [-1e-15, 0.0, 1e-15, 1e-9] {
            let x = [q1, q2, 0.5, -2.0];
            assert!(
                !w.admissible(0, HEEL_STRIKE, &x),
                "scuff at q1={q1}, q2={q2} admitted"
            );
        }
    }
    // on the heel-strike factor with the swing foot ahead: admissible
    for a in [1e-4, 0.01, 0.2, 0.6] {
        let x = [-a, 2.0 * a, -1.0, 0.3];
        assert!(w.admissible(0, HEEL_STRIKE, &x));
        // with the swing foot behind (just after the previous heel strike): not admissible
        let y = [a, -2.0 * a, -1.0, 0.3];
        assert!(!w.admissible(0, HEEL_STRIKE, &y));
    }
    // a whole step from the section: the first heel strike is the symmetric one, past the scuff
    let (stop, _t, x, _) = one_step(&w, &[0.271, -1.09, 0.715], 1e-10);
    assert_eq!(stop, StopReason::Guard { guard: HEEL_STRIKE });
    assert!((2.0 * x[0] + x[1]).abs() < 1e-9 && x[1] > 0.1, "x = {x:?}");
}

#[test]
fn ground_reaction_equals_total_momentum_rate_minus_weight() {
    let w = goswami();
    let p = GOSWAMI;
    let mut ws = Scratch::new();
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let gvec = [p.gravity * p.slope.sin(), -p.gravity * p.slope.cos()];
    for _ in 0..50 {
        let x = random_state(&mut rng);
        let mut dx = [0.0; 4];
        w.flow(&mut ws, 0, &x, &mut dx);
        // Σ m a by central differences in time of the point-mass velocities along the flow is
        // replaced by the exact second derivative: v(x + h ẋ) − v(x − h ẋ), h small.
        let h = 1e-6;
        let xp: Vec<f64> = (0..4).map(|i| x[i] + h * dx[i]).collect();
        let xm: Vec<f64> = (0..4).map(|i| x[i] - h * dx[i]).collect();
        let (pp, pm) = (point_masses(&p, &xp), point_masses(&p, &xm));
        let mut f = [0.0; 2];
        for k in 0..3 {
            for c in 0..2 {
                f[c] += pp[k].0 * ((pp[k].2[c] - pm[k].2[c]) / (2.0 * h) - gvec[c]);
            }
        }
        let cf = w.constraint_forces_ws(&mut ws, 0, &x);
        let scale = (p.leg_mass * 2.0 + p.hip_mass) * (p.gravity + 10.0);
        assert!(
            (cf.normal - f[1]).abs() < 1e-6 * scale,
            "{} vs {}",
            cf.normal,
            f[1]
        );
        assert!((cf.tangential - f[0]).abs() < 1e-6 * scale);
        assert_eq!(cf.knee_torque, [None, None]);
    }
}

/// The compass with leg mass `β` (hip mass 1) near the feet: the spec rejects a point mass at
/// a joint (`a = 0`, Garcia's foot masses), so the leg masses sit at `a = βl` from the foot; the
/// offset is O(β), as the leg masses' own effect.
fn near_simplest(beta: f64, l: f64, gamma: f64, g: f64) -> ChainWalker {
    walker(&Gp {
        leg_mass: beta,
        hip_mass: 1.0,
        a: beta * l,
        b: l - beta * l,
        slope: gamma,
        gravity: g,
    })
}

#[test]
fn foot_point_masses_need_a_hip_mass_to_keep_the_chain_regular() {
    // Leg masses at the feet (a = 0, Garcia's simplest walker): the stance leg's only inertia
    // about the stance foot is the hip mass's. With it the chain is regular and the dynamics
    // equal Goswami's closed form; without it the spec is refused with the rule.
    let w = presets::compass(&[("a", 0.0), ("b", 1.0)]).unwrap();
    let p = Gp {
        a: 0.0,
        b: 1.0,
        ..GOSWAMI
    };
    let x = [0.2, -0.4, -1.1, 0.3];
    let mut f = [0.0; 4];
    w.flow(&mut Scratch::new(), 0, &x, &mut f);
    let th = goswami_accel(
        &p,
        [x[0] + x[1] - p.slope, x[0] - p.slope],
        [x[2] + x[3], x[2]],
    );
    assert!(
        (f[2] - th[1]).abs() <= 1e-12 * th[1].abs().max(1.0),
        "{f:?} vs {th:?}"
    );
    match presets::compass(&[("a", 0.0), ("b", 1.0), ("hip_mass", 0.0)]) {
        Err(WalkerError::InvalidSpec { field, rule, .. }) => {
            assert_eq!(field, "segments[0].com");
            assert!(rule.contains("zero inertia"), "{rule}");
        }
        other => panic!("expected InvalidSpec, got {other:?}"),
    }
}

#[test]
fn compass_tends_to_simplest_walker_as_leg_mass_vanishes() {
    // time in √(l/g), φ = −q₂.
    let (l, g, gamma): (f64, f64, f64) = (1.3, 9.81, 0.009);
    let tscale = (g / l).sqrt();
    let mut ws = Scratch::new();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let states: Vec<[f64; 4]> = (0..50).map(|_| random_state(&mut rng)).collect();
    let mut errs = vec![];
    for beta in [1e-2, 1e-3, 1e-4] {
        let w = near_simplest(beta, l, gamma, g);
        let mut worst: f64 = 0.0;
        for x in &states {
            let (th, ph) = (x[0], -x[1]);
            let thd = x[2] / tscale;
            let thdd = (th - gamma).sin();
            let phdd = thdd + thd * thd * ph.sin() - (th - gamma).cos() * ph.sin();
            let mut dx = [0.0; 4];
            w.flow(&mut ws, 0, x, &mut dx);
            let e = ((dx[2] / (tscale * tscale)) - thdd)
                .abs()
                .max((-dx[3] / (tscale * tscale) - phdd).abs());
            worst = worst.max(e);
        }
        errs.push(worst);
    }
    // the error is O(β): each tenfold reduction of β reduces it tenfold (within 20 %)
    for k in 0..2 {
        let ratio = errs[k + 1] / errs[k];
        assert!((ratio - 0.1).abs() < 0.02, "errors {errs:?}: ratio {ratio}");
    }
    assert!(errs[2] < 1e-3, "errors {errs:?}");
}

#[test]
fn heel_strike_tends_to_garcia_jump_map_as_leg_mass_vanishes() {
    let mut ws = Scratch::new();
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let states = heel_strike_states(&mut rng, 20);
    let mut errs = vec![];
    for beta in [1e-2, 1e-3, 1e-4] {
        let w = near_simplest(beta, 1.0, 0.009, 1.0);
        let mut worst: f64 = 0.0;
        for x in &states {
            let mut out = [0.0; 4];
            w.reset(&mut ws, 0, HEEL_STRIKE, x, &mut out);
            // Garcia: θ̇⁺ = cos 2θ θ̇⁻, φ̇⁺ = cos 2θ (1 − cos 2θ) θ̇⁻ (θ = q₁, φ̇ = −q̇₂)
            let c2 = (2.0 * x[0]).cos();
            let thd = c2 * x[2];
            let phd = c2 * (1.0 - c2) * x[2];
            worst = worst.max((out[2] - thd).abs()).max((-out[3] - phd).abs());
        }
        errs.push(worst);
    }
    for k in 0..2 {
        let ratio = errs[k + 1] / errs[k];
        assert!((ratio - 0.1).abs() < 0.02, "errors {errs:?}: ratio {ratio}");
    }
}

#[test]
fn bad_parameters_are_rejected_as_spec_errors_naming_field_value_and_rule() {
    // (override, field, a piece of the value, a piece of the rule)
    let cases: [(&str, f64, &str, &str, &str); 6] = [
        ("leg_mass", -1.0, "segments[0].mass", "-1", "must be > 0"),
        ("hip_mass", f64::NAN, "parameters.hip_mass", "NaN", "finite"),
        ("hip_mass", -2.0, "hip_mass", "-2", "must be >= 0"),
        ("b", 0.0, "segments[0].com", "0.5", "zero inertia"),
        ("slope", 2.0, "parameters.slope", "2", "(-pi/2, pi/2)"),
        ("gravity", 0.0, "parameters.gravity", "0", "must be > 0"),
    ];
    for (name, v, field, value, rule) in cases {
        match presets::compass(&[(name, v)]) {
            Err(e @ WalkerError::InvalidSpec { .. }) => {
                let msg = e.to_string();
                let WalkerError::InvalidSpec {
                    source_name,
                    field: f,
                    value: val,
                    rule: r,
                } = e
                else {
                    unreachable!()
                };
                assert_eq!(source_name, "compass", "{name}");
                assert_eq!(f, field, "{name}: {msg}");
                assert!(val.contains(value), "{name}: value {val:?} in {msg}");
                assert!(r.contains(rule), "{name}: rule {r:?} in {msg}");
                // the message shows all three
                assert!(
                    msg.contains(field) && msg.contains(&val) && msg.contains(&r),
                    "{msg}"
                );
            }
            other => panic!("{name} = {v}: expected InvalidSpec, got {other:?}"),
        }
    }
    // a name the model does not have
    assert!(matches!(
        presets::compass(&[("mass", 1.0)]),
        Err(WalkerError::UnknownParam { .. })
    ));
}

#[test]
fn falling_scuff_crossing_is_skipped_and_flagged() {
    // The swing leg passes the stance leg slowly while the stance leg is already past the
    // vertical: the swing-foot height falls through zero on the scuffing factor q₂ = 0 (the foot
    // enters the ground as it passes). That crossing must not end the step.
    let w = goswami();
    let mut ws = Scratch::new();
    let mut x = [-0.1, -0.05, -1.0, 1.0];
    let mut integ = Integrator::new(4, Options::dop853(1e-11)).unwrap();
    let mut t = 0.0;
    let mut saw_falling_scuff = false;
    let mut prev: Option<[f64; 4]> = None;
    let mut flags = StepFlags::default();
    let stop = integ.integrate_observed(
        &w as &dyn pdw_hybrid::HybridSystem,
        0,
        &mut t,
        &mut x,
        3.0,
        &mut |_, y| {
            if let Some(p) = prev {
                if w.swing_foot(&p)[1] > 0.0
                    && w.swing_foot(y)[1] <= 0.0
                    && p[1] < 0.0
                    && y[1] > -0.01
                {
                    saw_falling_scuff = true;
                }
            }
            prev = Some([y[0], y[1], y[2], y[3]]);
            flags = flags.merge(w.check_state_ws(&mut ws, 0, y));
        },
    );
    assert!(
        saw_falling_scuff,
        "the scenario did not produce a falling scuff crossing"
    );
    assert!(
        flags.swing_foot_scuffs,
        "scuffing after mid-stance not flagged"
    );
    if let StopReason::Guard { guard: HEEL_STRIKE } = stop {
        assert!(
            (2.0 * x[0] + x[1]).abs() < 1e-9 && x[1] > 0.05,
            "stopped at {x:?}"
        );
    }
}
