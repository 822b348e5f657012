//! Acceptance: the compass gait's variational multipliers agree with an independent closed-form
//! M/C/G implementation to ≤ 1e-11.
//!
//! [`ClosedCompass`] is Goswami, Thuilot & Espiau's compass gait (IJRR 17(12), 1998) written from
//! the paper's closed-form inertia matrix `M(θ)`, Coriolis matrix `C(θ, θ̇)`, gravity vector
//! `G(θ)` and heel-strike matrices `Q⁻(α)`, `Q⁺(α)`: no kernel, no chain. It is a
//! [`HybridSystem`] + [`Section`] in the chain walker's coordinates and conventions (state
//! `x = (q₁, q₂, q̇₁, q̇₂)`, `q₁` the stance leg's angle from the slope normal, `q₂` the hip
//! angle; the paper's angles from the vertical are `θ_s = q₁ − γ`, `θ_ns = q₁ + q₂ − γ`), with
//! the same guards and section, so that both run through the same stride map, Newton solver and
//! variational equations. Its flow, guard and reset Jacobians are exact: the closed-form
//! functions are generic over [`pdw_soa::Scalar`] and evaluated on [`pdw_soa::Dual`] numbers.
//!
//! The chain walker (`compass` preset: the batched SOA kernel, Jacobians by duals through the
//! kernel's per-link steps) and the closed form must give the same fixed points and the same
//! Floquet multipliers at Goswami's preset and at two other `(hip_mass, slope)` points; the
//! chain walker's batched flow must equal the closed form's vector field in every lane, for any
//! number of lanes.

use faer::Mat;
use pdw_hybrid::{
    Crossing, FallKind, GuardKind, GuardSpec, HybridSystem, Options, Scratch, Section,
};
use pdw_limit::{find_fixed_point, richardson_jacobian, FixedPoint, NewtonOptions, StrideMap};
use pdw_soa::{Dual, Scalar};
use pdw_walkers::{presets, ChainWalker, Walker};
use std::f64::consts::FRAC_PI_2;

/// Goswami et al.'s parameters: leg point mass `m` at `a` from the foot (`b` from the hip),
/// hip mass `m_H`, slope `γ`, gravity `g`.
#[derive(Clone, Copy, Debug)]
struct Gp {
    leg_mass: f64,
    hip_mass: f64,
    a: f64,
    b: f64,
    slope: f64,
    gravity: f64,
}

/// Goswami et al. 1998: m = 5 kg, m_H = 10 kg, a = b = 0.5 m, γ = 3°, g = 9.81.
const GOSWAMI: Gp = Gp {
    leg_mass: 5.0,
    hip_mass: 10.0,
    a: 0.5,
    b: 0.5,
    slope: 0.05235987755982988,
    gravity: 9.81,
};

/// `[A⁻¹ r]` for a 2 × 2 matrix `A` (Cramer's rule).
fn solve2<T: Scalar>(a: [[T; 2]; 2], r: [T; 2]) -> [T; 2] {
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    [
        (r[0] * a[1][1] - a[0][1] * r[1]) / det,
        (a[0][0] * r[1] - a[1][0] * r[0]) / det,
    ]
}

/// Goswami's `M(θ) θ̈ + C(θ, θ̇) θ̇ + G(θ) = 0`, `θ = (θ_ns, θ_s)` from the vertical:
///
/// ```text
/// M = [ m b²                  −m l b cos(θ_s − θ_ns) ]
///     [ −m l b cos(θ_s − θ_ns)   (m_H + m) l² + m a²  ]
/// C = [ 0                          m l b sin(θ_s − θ_ns) θ̇_s ]
///     [ −m l b sin(θ_s − θ_ns) θ̇_ns   0                      ]
/// G = [ m b g sin θ_ns,  −(m_H l + m a + m l) g sin θ_s ]ᵀ
/// ```
/// in the chain walker's coordinates: returns `(q̈₁, q̈₂) = (θ̈_s, θ̈_ns − θ̈_s)`.
fn accel<T: Scalar>(p: &Gp, x: &[T]) -> [T; 2] {
    let c = T::cst;
    let (m, mh, a, b, g) = (p.leg_mass, p.hip_mass, p.a, p.b, p.gravity);
    let l = a + b;
    let th_s = x[0] - c(p.slope);
    let th_ns = x[0] + x[1] - c(p.slope);
    let (w_s, w_ns) = (x[2], x[2] + x[3]);
    let (sd, cd) = (th_s - th_ns).sin_cos();
    let mm = [
        [c(m * b * b), -(c(m * l * b) * cd)],
        [-(c(m * l * b) * cd), c((mh + m) * l * l + m * a * a)],
    ];
    let cc = [
        [c(0.0), c(m * l * b) * sd * w_s],
        [-(c(m * l * b) * sd * w_ns), c(0.0)],
    ];
    let gg = [
        c(m * b * g) * th_ns.sin_cos().0,
        -(c((mh * l + m * a + m * l) * g) * th_s.sin_cos().0),
    ];
    let rhs = [
        -(cc[0][0] * w_ns + cc[0][1] * w_s + gg[0]),
        -(cc[1][0] * w_ns + cc[1][1] * w_s + gg[1]),
    ];
    let [acc_ns, acc_s] = solve2(mm, rhs);
    [acc_s, acc_ns - acc_s]
}

/// Swing-foot position `(y, z)` relative to the stance foot (slope frame, `y` downhill): the
/// hip at `l (−sin q₁, cos q₁)`, the swing foot `l (sin ψ, −cos ψ)` below it, `ψ = q₁ + q₂`.
fn swing_foot<T: Scalar>(p: &Gp, x: &[T]) -> [T; 2] {
    let l = T::cst(p.a + p.b);
    let (s1, c1) = x[0].sin_cos();
    let (sp, cp) = (x[0] + x[1]).sin_cos();
    [l * (sp - s1), l * (c1 - cp)]
}

/// Goswami's heel-strike map with the legs relabelled, `Q⁺(α) θ̇⁺ = Q⁻(α) θ̇⁻`, `α` the half
/// inter-leg angle (`q₂/2`):
///
/// ```text
/// Q⁻ = [ −m a b   −m a b + (m_H l² + 2 m a l) cos 2α ]
///      [ 0        −m a b                             ]
/// Q⁺ = [ m b (b − l cos 2α)   m l (l − b cos 2α) + m a² + m_H l² ]
///      [ m b²                 −m b l cos 2α                      ]
/// ```
/// then the new coordinates: `q₁⁺ = q₁ + q₂` (the old swing leg stands), `q₂⁺ = −q₂`,
/// `q̇₁⁺ = θ̇_s⁺`, `q̇₂⁺ = θ̇_ns⁺ − θ̇_s⁺`.
fn impact<T: Scalar>(p: &Gp, x: &[T]) -> [T; 4] {
    let c = T::cst;
    let (m, mh, a, b) = (p.leg_mass, p.hip_mass, p.a, p.b);
    let l = a + b;
    let c2 = x[1].sin_cos().1; // cos 2α = cos q₂
    let qm = [
        [
            c(-m * a * b),
            c(-m * a * b) + c(mh * l * l + 2.0 * m * a * l) * c2,
        ],
        [c(0.0), c(-m * a * b)],
    ];
    let qp = [
        [
            c(m * b) * (c(b) - c(l) * c2),
            c(m * l) * (c(l) - c(b) * c2) + c(m * a * a + mh * l * l),
        ],
        [c(m * b * b), -(c(m * b * l) * c2)],
    ];
    let (w_ns, w_s) = (x[2] + x[3], x[2]);
    let r = [
        qm[0][0] * w_ns + qm[0][1] * w_s,
        qm[1][0] * w_ns + qm[1][1] * w_s,
    ];
    let [post_ns, post_s] = solve2(qp, r);
    [x[0] + x[1], -x[1], post_s, post_ns - post_s]
}

/// The state as dual numbers seeded with the identity (derivatives along `x₀ … x₃`).
fn seeded(x: &[f64]) -> [Dual<4>; 4] {
    std::array::from_fn(|i| Dual::variable(x[i], i))
}

const GUARDS: [GuardSpec; 4] = [
    GuardSpec {
        name: "heel_strike",
        crossing: Crossing::Falling,
        kind: GuardKind::Reset,
    },
    GuardSpec {
        name: "stance_reverses",
        crossing: Crossing::Rising,
        kind: GuardKind::Terminal(FallKind::Backward),
    },
    GuardSpec {
        name: "hip_on_ground_behind",
        crossing: Crossing::Rising,
        kind: GuardKind::Terminal(FallKind::Backward),
    },
    GuardSpec {
        name: "hip_on_ground_ahead",
        crossing: Crossing::Falling,
        kind: GuardKind::Terminal(FallKind::Forward),
    },
];

const SECTION_NAMES: [&str; 3] = ["stance", "stance_rate", "hip_rate"];

/// Goswami's compass gait in closed form (see the module docs). One mode; guards: 0 heel
/// strike (swing-foot height falling through 0 with the swing foot ahead, on the heel-strike
/// factor `|2q₁ + q₂| < |q₂|`), then the falls (`q̇₁` rising through 0 while `q₁ > γ`,
/// `q₁ − π/2` rising, `q₁ + π/2` falling). Section just after heel strike:
/// `x = (s₀, −2s₀, s₁, s₂)`.
struct ClosedCompass {
    p: Gp,
}

pdw_hybrid::integrate_through_dyn!(ClosedCompass);
impl HybridSystem for ClosedCompass {
    fn dim(&self) -> usize {
        4
    }
    fn guards(&self, _mode: usize) -> &[GuardSpec] {
        &GUARDS
    }
    fn flow(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], dx: &mut [f64]) {
        let acc = accel(&self.p, x);
        dx[0] = x[2];
        dx[1] = x[3];
        dx[2] = acc[0];
        dx[3] = acc[1];
    }
    fn guard(&self, _ws: &mut Scratch, _mode: usize, k: usize, x: &[f64]) -> f64 {
        match k {
            0 => swing_foot(&self.p, x)[1],
            1 => x[2],
            2 => x[0] - FRAC_PI_2,
            _ => x[0] + FRAC_PI_2,
        }
    }
    fn admissible(&self, _mode: usize, k: usize, x: &[f64]) -> bool {
        match k {
            0 => swing_foot(&self.p, x)[0] > 0.0 && (2.0 * x[0] + x[1]).abs() < x[1].abs(),
            1 => x[0] > self.p.slope,
            _ => true,
        }
    }
    fn reset(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        _k: usize,
        x: &[f64],
        out: &mut [f64],
    ) -> usize {
        out[..4].copy_from_slice(&impact(&self.p, x));
        0
    }
    fn flow_jacobian(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], jac: &mut [f64]) {
        let acc = accel(&self.p, &seeded(x));
        jac[..16].fill(0.0);
        jac[2] = 1.0;
        jac[4 + 3] = 1.0;
        jac[8..12].copy_from_slice(&acc[0].d);
        jac[12..16].copy_from_slice(&acc[1].d);
    }
    fn guard_gradient(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        k: usize,
        x: &[f64],
        grad: &mut [f64],
    ) {
        grad[..4].fill(0.0);
        match k {
            0 => grad[..4].copy_from_slice(&swing_foot(&self.p, &seeded(x))[1].d),
            1 => grad[2] = 1.0,
            _ => grad[0] = 1.0,
        }
    }
    fn reset_jacobian(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        _k: usize,
        x: &[f64],
        jac: &mut [f64],
    ) {
        let post = impact(&self.p, &seeded(x));
        for i in 0..4 {
            jac[4 * i..4 * i + 4].copy_from_slice(&post[i].d);
        }
    }
}

impl Section for ClosedCompass {
    fn section_dim(&self) -> usize {
        3
    }
    fn section_names(&self) -> &[&'static str] {
        &SECTION_NAMES
    }
    fn section_mode(&self) -> usize {
        0
    }
    fn section_guard(&self) -> (usize, usize) {
        (0, 0)
    }
    fn lift(&self, s: &[f64], x: &mut [f64]) {
        x[..4].copy_from_slice(&[s[0], -2.0 * s[0], s[1], s[2]]);
    }
    fn project(&self, x: &[f64], s: &mut [f64]) {
        s[..3].copy_from_slice(&[x[0], x[2], x[3]]);
    }
    fn max_stride_time(&self) -> f64 {
        5.0
    }
}

/// Both models at `p`.
fn models(p: &Gp) -> (ClosedCompass, ChainWalker) {
    let chain = presets::compass(&[
        ("leg_mass", p.leg_mass),
        ("hip_mass", p.hip_mass),
        ("a", p.a),
        ("b", p.b),
        ("slope", p.slope),
        ("gravity", p.gravity),
    ])
    .unwrap();
    (ClosedCompass { p: *p }, chain)
}

/// Goswami's preset and two other `(hip_mass, slope)` points.
fn parameter_points() -> [Gp; 3] {
    [
        GOSWAMI,
        Gp {
            hip_mass: 20.0,
            slope: 0.03,
            ..GOSWAMI
        },
        Gp {
            hip_mass: 6.0,
            slope: 0.07,
            ..GOSWAMI
        },
    ]
}

/// A deterministic spread of states (a small linear congruential sequence).
fn states(n: usize, seed: u64, ranges: [f64; 4]) -> Vec<[f64; 4]> {
    let mut z = seed;
    let mut next = move || {
        z = z
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    (0..n)
        .map(|_| std::array::from_fn(|i| ranges[i] * next()))
        .collect()
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn max_abs(a: &[f64]) -> f64 {
    a.iter().fold(0.0f64, |s, v| s.max(v.abs()))
}

#[test]
fn vector_field_guards_and_reset_equal_the_chain_walkers() {
    // this fixes the sign of the coordinate map: θ_s = q₁ − γ, θ_ns = q₁ + q₂ − γ
    let mut ws = Scratch::new();
    for p in parameter_points() {
        let (cf, cw) = models(&p);
        let mut worst: f64 = 0.0;
        for x in states(200, 1, [0.6, 1.2, 3.0, 5.0]) {
            let (mut a, mut b) = ([0.0; 4], [0.0; 4]);
            cf.flow(&mut ws, 0, &x, &mut a);
            cw.flow(&mut ws, 0, &x, &mut b);
            worst = worst.max(max_abs_diff(&a, &b) / max_abs(&b).max(1.0));
            for k in 0..4 {
                let (ga, gb) = (cf.guard(&mut ws, 0, k, &x), cw.guard(&mut ws, 0, k, &x));
                assert!((ga - gb).abs() < 1e-15, "guard {k}: {ga} vs {gb}");
                assert_eq!(
                    cf.admissible(0, k, &x),
                    cw.admissible(0, k, &x),
                    "guard {k}"
                );
            }
        }
        assert!(worst < 1e-12, "flow: worst relative difference {worst:e}");
        // pre-impact states (swing foot ahead; on and off the heel-strike surface)
        let mut worst: f64 = 0.0;
        for y in states(100, 2, [0.5, 1.0, 2.5, 3.0]) {
            let x = [
                -y[0].abs() - 0.05,
                2.0 * y[0].abs() + 0.1 + 0.05 * y[1],
                y[2],
                y[3],
            ];
            let (mut a, mut b) = ([0.0; 4], [0.0; 4]);
            assert_eq!(cf.reset(&mut ws, 0, 0, &x, &mut a), 0);
            assert_eq!(cw.reset(&mut ws, 0, 0, &x, &mut b), 0);
            worst = worst.max(max_abs_diff(&a, &b) / max_abs(&b).max(1.0));
        }
        assert!(worst < 1e-12, "reset: worst relative difference {worst:e}");
    }
}

/// The chain walker's own rows of a batch: `flow_batch` over `xs`, one lane per state.
fn flow_batch_rows(cw: &ChainWalker, ws: &mut Scratch, xs: &[[f64; 4]]) -> Vec<[f64; 4]> {
    let x = Mat::from_fn(xs.len(), 4, |l, j| xs[l][j]);
    let mut dx = Mat::<f64>::zeros(xs.len(), 4);
    cw.flow_batch(ws, 0, x.as_ref(), dx.as_mut());
    (0..xs.len())
        .map(|l| std::array::from_fn(|j| dx[(l, j)]))
        .collect()
}

/// The chain walker's batched flow (`flow_batch`: the articulated-body recursion over SIMD
/// blocks of 64 lanes) against Goswami's closed-form `M θ̈ + C θ̇ + G = 0` ([`accel`]), lane by
/// lane, at the three parameter points, on 300 seeded states spread over
/// `|q₁| ≤ 0.6, |q₂| ≤ 1.2, |q̇₁| ≤ 3, |q̇₂| ≤ 5`.
///
/// Modes: the compass has one (`n_modes() = 1`, both legs rigid, the stance foot pinned), and
/// the closed form covers it; the kneed walkers' free-knee and locked modes and round feet are
/// covered by `round_foot_kneed_reference.rs`.
///
/// Each lane's largest difference, relative to the lane's largest component of `ẋ`, stays below
/// 1e-12 (measured: 2.2e-15 worst over the 900 lanes). Lane counts 1, 7 and 300: the batches are
/// windows of the same states (300 = four blocks of 64 and a remainder of 44; the 7 lanes are
/// lanes 61–67 of the big batch, across its first block boundary; the single lane is its last),
/// and each lane has the same bits in every batch it is part of (no lane reads another's data).
#[test]
fn batched_flow_equals_the_closed_form_in_every_lane_for_every_lane_count() {
    let mut ws = Scratch::new();
    let mut worst: f64 = 0.0;
    for p in parameter_points() {
        let (cf, cw) = models(&p);
        assert_eq!(cw.n_modes(), 1, "the compass has one mode");
        let xs = states(300, 4, [0.6, 1.2, 3.0, 5.0]);
        let all = flow_batch_rows(&cw, &mut ws, &xs);
        for window in [0..300, 61..68, 299..300] {
            let part = flow_batch_rows(&cw, &mut ws, &xs[window.clone()]);
            for (l, f) in part.iter().enumerate() {
                assert_eq!(
                    f.map(f64::to_bits),
                    all[window.start + l].map(f64::to_bits),
                    "{} lanes: lane {l} differs from lane {} of the 300-lane batch",
                    window.len(),
                    window.start + l
                );
            }
        }
        for (l, (x, f)) in xs.iter().zip(&all).enumerate() {
            let mut r = [0.0; 4];
            cf.flow(&mut ws, 0, x, &mut r);
            let rel = max_abs_diff(f, &r) / max_abs(&r);
            assert!(
                rel < 1e-12,
                "hip_mass {}, slope {}: lane {l} at {x:?}: chain walker {f:?} vs closed form {r:?}",
                p.hip_mass,
                p.slope
            );
            worst = worst.max(rel);
        }
    }
    eprintln!("batched flow vs closed form: worst relative difference {worst:.2e}");
}

#[test]
fn dual_number_jacobians_are_exact() {
    // against Richardson-extrapolated differences of the closed form itself, and against the
    // chain walker's kernel Jacobians
    let mut ws = Scratch::new();
    for p in parameter_points() {
        let (cf, cw) = models(&p);
        let (mut worst_fd, mut worst_cw): (f64, f64) = (0.0, 0.0);
        for y in states(40, 3, [0.5, 1.0, 2.5, 3.0]) {
            let x = [
                -y[0].abs() - 0.05,
                2.0 * y[0].abs() + 0.1 + 0.05 * y[1],
                y[2],
                y[3],
            ];
            let (mut ja, mut jb) = ([0.0; 16], [0.0; 16]);
            // flow
            cf.flow_jacobian(&mut ws, 0, &x, &mut ja);
            cw.flow_jacobian(&mut ws, 0, &x, &mut jb);
            let fd = richardson_jacobian(|z, out| cf.flow(&mut Scratch::new(), 0, z, out), &x, 4);
            worst_fd = worst_fd.max(max_abs_diff(&ja, &fd) / max_abs(&ja).max(1.0));
            worst_cw = worst_cw.max(max_abs_diff(&ja, &jb) / max_abs(&ja).max(1.0));
            // reset
            cf.reset_jacobian(&mut ws, 0, 0, &x, &mut ja);
            cw.reset_jacobian(&mut ws, 0, 0, &x, &mut jb);
            let fd = richardson_jacobian(
                |z, out| {
                    cf.reset(&mut Scratch::new(), 0, 0, z, out);
                },
                &x,
                4,
            );
            worst_fd = worst_fd.max(max_abs_diff(&ja, &fd) / max_abs(&ja).max(1.0));
            worst_cw = worst_cw.max(max_abs_diff(&ja, &jb) / max_abs(&ja).max(1.0));
            // guards
            for k in 0..4 {
                let (mut ga, mut gb) = ([0.0; 4], [0.0; 4]);
                cf.guard_gradient(&mut ws, 0, k, &x, &mut ga);
                cw.guard_gradient(&mut ws, 0, k, &x, &mut gb);
                let fd = richardson_jacobian(
                    |z, out| out[0] = cf.guard(&mut Scratch::new(), 0, k, z),
                    &x,
                    1,
                );
                worst_fd = worst_fd.max(max_abs_diff(&ga, &fd) / max_abs(&ga).max(1.0));
                worst_cw = worst_cw.max(max_abs_diff(&ga, &gb) / max_abs(&ga).max(1.0));
            }
        }
        assert!(worst_fd < 1e-8, "closed form vs Richardson: {worst_fd:e}");
        assert!(
            worst_cw < 1e-12,
            "closed form vs chain walker: {worst_cw:e}"
        );
    }
}

fn fixed_point<S: Section>(sys: &S, guess: &[f64]) -> FixedPoint {
    let map = StrideMap::new(sys, Options::dop853(1e-14)).unwrap();
    let opts = NewtonOptions {
        tol: 1e-12,
        ..NewtonOptions::default()
    };
    find_fixed_point(&map, guess, &opts).unwrap()
}

#[test]
fn variational_multipliers_agree_with_the_closed_form_to_1e_11() {
    for p in parameter_points() {
        let (cf, cw) = models(&p);
        let guess = cw.gait_guesses()[0].section.clone();
        let (a, b) = (fixed_point(&cf, &guess), fixed_point(&cw, &guess));
        let ds = max_abs_diff(&a.section, &b.section);
        let dp = (Mat::from_fn(3, 3, |i, j| a.dp[3 * i + j])
            - Mat::from_fn(3, 3, |i, j| b.dp[3 * i + j]))
        .norm_max();
        assert_eq!(a.multipliers.len(), b.multipliers.len());
        let dm = a
            .multipliers
            .iter()
            .zip(&b.multipliers)
            .map(|(x, y)| (x.re - y.re).abs().max((x.im - y.im).abs()))
            .fold(0.0, f64::max);
        eprintln!(
            "hip_mass {}, slope {}: s* = {:?}, |λ| = {:?}, stable {}; closed form vs chain \
             walker: section {ds:.1e}, DP {dp:.1e}, multipliers {dm:.1e}; residuals {:.1e} / \
             {:.1e}",
            p.hip_mass,
            p.slope,
            b.section,
            b.multipliers
                .iter()
                .map(|m| m.modulus())
                .collect::<Vec<_>>(),
            b.stable,
            a.residual,
            b.residual
        );
        assert!(
            ds <= 1e-11,
            "hip_mass {}, slope {}: sections {:?} vs {:?}",
            p.hip_mass,
            p.slope,
            a.section,
            b.section
        );
        assert!(
            dm <= 1e-11,
            "hip_mass {}, slope {}: multipliers {:?} vs {:?}",
            p.hip_mass,
            p.slope,
            a.multipliers,
            b.multipliers
        );
    }
}

/// Goswami et al. 1998 report two period-one gaits of the compass at 3°: the long-period stable
/// one and a short-period unstable one. The preset's `unstable` guess must lead to the second,
/// and that gait must be the same fixed point, with the same multipliers, on the independent
/// closed-form model.
#[test]
fn short_period_unstable_gait_of_goswami_agrees_with_the_closed_form() {
    let (cf, cw) = models(&GOSWAMI);
    let guess = |name: &str| {
        cw.gait_guesses()
            .into_iter()
            .find(|g| g.gait == name)
            .unwrap_or_else(|| panic!("the compass preset has a `{name}` guess"))
            .section
    };
    let stable = fixed_point(&cw, &guess("stable"));
    let (a, b) = (
        fixed_point(&cf, &guess("unstable")),
        fixed_point(&cw, &guess("unstable")),
    );
    eprintln!(
        "unstable gait: s* = {:?}, period {} s (stable {} s), |λ| = {:?}",
        b.section,
        b.metrics.period,
        stable.metrics.period,
        b.multipliers
            .iter()
            .map(|m| m.modulus())
            .collect::<Vec<_>>()
    );
    assert!(stable.stable && !b.stable);
    assert!(
        max_abs_diff(&b.section, &stable.section) > 1e-2,
        "a different gait from the stable one"
    );
    assert!(
        b.metrics.period < 0.9 * stable.metrics.period,
        "short period: {} against {}",
        b.metrics.period,
        stable.metrics.period
    );
    assert!(b.multipliers[0].modulus() > 1.0);
    assert!(max_abs_diff(&a.section, &b.section) <= 1e-11);
    let dm = a
        .multipliers
        .iter()
        .zip(&b.multipliers)
        .map(|(x, y)| (x.re - y.re).abs().max((x.im - y.im).abs()))
        .fold(0.0, f64::max);
    assert!(dm <= 1e-10, "{:?} vs {:?}", a.multipliers, b.multipliers);
}

/// Goswami's compass with `step_down = h` (chain walker module docs, "Step down").
fn stepping(p: &Gp, h: f64) -> ChainWalker {
    presets::compass(&[
        ("leg_mass", p.leg_mass),
        ("hip_mass", p.hip_mass),
        ("a", p.a),
        ("b", p.b),
        ("slope", p.slope),
        ("gravity", p.gravity),
        ("step_down", h),
    ])
    .unwrap()
}

/// Goswami's kinetic energy `½ ω̇ᵀ M(θ) ω̇` (the `M` of [`accel`]) of a state in the chain
/// walker's coordinates, the stance foot at rest.
fn kinetic(p: &Gp, x: &[f64]) -> f64 {
    let (m, mh, a, b) = (p.leg_mass, p.hip_mass, p.a, p.b);
    let l = a + b;
    let cd = (-x[1]).cos();
    let (w_s, w_ns) = (x[2], x[2] + x[3]);
    let mm = [
        [m * b * b, -m * l * b * cd],
        [-m * l * b * cd, (mh + m) * l * l + m * a * a],
    ];
    let w = [w_ns, w_s];
    0.5 * (0..2)
        .map(|i| (0..2).map(|j| w[i] * mm[i][j] * w[j]).sum::<f64>())
        .sum::<f64>()
}

/// A stride of the compass with a step down `h` from the level gait: at the heel strike the
/// swing foot is `h` below the stance foot by the closed-form geometry ([`swing_foot`]), the
/// state after it is Goswami's impact map ([`impact`]) of the configuration at contact, and the
/// walker's energy drops by the closed form's kinetic-energy loss (the potential measured from
/// the new stance foot, `M g⃗·p` lower with `p` the new foothold).
#[test]
fn heel_strike_onto_a_step_lands_h_below_and_loses_the_closed_form_energy() {
    let p = GOSWAMI;
    let (_, level) = models(&p);
    let s = fixed_point(&level, &level.gait_guesses()[0].section).section;
    for h in [0.02, 0.005, -0.002] {
        let cw = stepping(&p, h);
        let map = StrideMap::new(&cw, Options::dop853(1e-12)).unwrap();
        let st = map.stride(&s).unwrap();
        assert!(st.outcome.is_ok(), "h {h}: {:?}", st.outcome);
        let pre = &st.pre_event;
        let foot = swing_foot(&p, pre);
        assert!(
            (foot[1] + h).abs() <= 1e-10 && foot[0] > 0.0,
            "h {h}: swing foot {foot:?}"
        );
        let post = impact(&p, pre);
        let d = max_abs_diff(&post, &st.post_event);
        assert!(d <= 1e-11, "h {h}: impact {post:?} vs {:?}", st.post_event);
        let mass = 2.0 * p.leg_mass + p.hip_mass;
        let g_dot_p = p.gravity * (p.slope.sin() * foot[0] - p.slope.cos() * foot[1]);
        let e = |x: &[f64]| cw.energy(x).unwrap();
        let lost = e(pre) - e(&st.post_event) + mass * g_dot_p;
        let closed = kinetic(&p, pre) - kinetic(&p, &post);
        eprintln!("h {h}: energy lost {lost:.12e} J, closed form {closed:.12e} J");
        assert!(
            closed > 0.0 && (lost - closed).abs() <= 1e-9 * closed.max(1.0),
            "h {h}"
        );
    }
}

/// The compass's fixed point with a constant step down `h` tends continuously (linearly) to the
/// level gait as `h → 0`, and a step down changes the gait (its stride differs from level).
#[test]
fn fixed_point_on_a_constant_step_down_tends_to_the_level_gait() {
    let p = GOSWAMI;
    let (_, level) = models(&p);
    let s0 = fixed_point(&level, &level.gait_guesses()[0].section).section;
    let dist = |h: f64| max_abs_diff(&fixed_point(&stepping(&p, h), &s0).section, &s0);
    let (d1, d2, d3) = (dist(1e-3), dist(1e-4), dist(1e-5));
    eprintln!("|s*(h) − s*(0)|: h 1e-3 {d1:.3e}, 1e-4 {d2:.3e}, 1e-5 {d3:.3e}");
    assert!(d1 > 0.0 && d2 > 0.0 && d3 > 0.0);
    // linear in h: each tenfold smaller step moves the gait about ten times less
    for (big, small) in [(d1, d2), (d2, d3)] {
        let ratio = big / small;
        assert!((5.0..20.0).contains(&ratio), "ratio {ratio}");
    }
}

/// A step of a leg length or more is refused with a message naming `step_down`.
#[test]
fn a_step_beyond_a_leg_is_refused() {
    for h in [1.0, -1.5] {
        let e = presets::compass(&[("step_down", h)]).unwrap_err();
        assert!(e.to_string().contains("step_down"), "{e}");
    }
}
