//! Acceptance: the chain walker with round feet and knees (`seed5_walking` and a variant with
//! inertia about each COM and a larger foot) against an independent closed-form model, to 1e-10.
//!
//! [`Reference`] is a planar kneed walker with arc feet written from the physics only: no
//! kernel, no chain, no recursion. Four rigid segments (stance shank, stance thigh, swing thigh,
//! swing shank) with point masses at their COMs (along and normal to the segment), rotational
//! inertia about each COM and a hip point mass; minimal coordinates are the absolute segment
//! angles `θ = (θ₀, θ₁, θ₂, θ₃)` from the slope normal. The stance foot is an arc of radius `r`
//! whose centre lies on the shank's line `r` above the shank's lower end; it rolls without slip,
//! so the arc centre is at `A = (−r θ₀, r)` (McGeer 1990, "Passive dynamic walking", IJRR 9(2),
//! the rolling arc foot). Every point of the walker is
//!
//! ```text
//! P = A + Σ_k (α_k e(θ_k) + β_k n(θ_k)),   e(θ) = (−sin θ, cos θ),   n(θ) = (cos θ, sin θ)
//! ```
//!
//! (slope frame: `y` downhill, `z` normal up; `e` along the segment, up when upright; `n` normal
//! to it, forward), so that with `u_k = ∂P/∂θ_k = −α_k n(θ_k) + β_k e(θ_k)` and the rolling term
//! `ρ = ∂A/∂θ₀ = (−r, 0)` Lagrange's equations `M(θ) θ̈ + c(θ, θ̇) = Q(θ)` (Garcia et al. 1998
//! and Hsu Chen 2007 write the same sums for their kneed walkers) have the closed forms
//!
//! ```text
//! M_jk = Σ_i m_i [(α_ij α_ik + β_ij β_ik) cos(θ_j − θ_k) + (β_ij α_ik − α_ij β_ik) sin(θ_j − θ_k)
//!                 + δ_j0 ρ·u_ik + δ_k0 ρ·u_ij + δ_j0 δ_k0 r²] + Σ_{i on link j} I_i δ_jk
//! ρ·u_ik = r (α_ik cos θ_k + β_ik sin θ_k)
//! c_j = Σ_i m_i Σ_k θ̇_k² [(α_ij α_ik + β_ij β_ik) sin(θ_j − θ_k) + (α_ij β_ik − β_ij α_ik) cos(θ_j − θ_k)
//!                         − δ_j0 r (α_ik sin θ_k − β_ik cos θ_k)]
//! Q_j = Σ_i m_i g [α_ij sin(θ_j − γ) − β_ij cos(θ_j − γ)] − δ_j0 m_tot g r sin γ
//! V   = Σ_i m_i g Σ_k [α_ik cos(θ_k − γ) + β_ik sin(θ_k − γ)] + m_tot g r (θ₀ sin γ + cos γ)
//! ```
//!
//! Locked knees are constraints `θ̇₁ − θ̇₀ = 0` (stance knee), `θ̇₃ − θ̇₂ = 0` (swing knee) with
//! Lagrange multipliers (the lock torques, positive towards `q` increasing):
//! `[M −Gᵀ; G 0] [θ̈; τ] = [Q − c; 0]`. The ground force on the stance foot is Newton's law for
//! the whole walker, `F = Σ_i m_i (a_i − g⃗)`, `g⃗ = (g sin γ, −g cos γ)`. Impacts are plastic
//! (Hurmuzlu & Marghitu 1994; McGeer 1990 for the arc foot): `[M −Gᵀ; G 0] [θ̇⁺; Λ] = [M θ̇⁻; 0]`,
//! at heel strike on the floating walker `(A_y, A_z, θ)` with the new contact point (r below
//! the swing arc centre) brought to rest and both knees held; at knee strike on the rolling
//! walker with the swing knee stopped and the stance knee held. The linear systems are solved
//! by plain Gaussian elimination with partial pivoting ([`solve`]).
//!
//! The engine's conventions (read from the chain walker's module docs, nothing else): joints
//! `q = (q₀, q₁, q₂, q₃) = (θ₀, θ₁ − θ₀, θ₂ − θ₁, θ₃ − θ₂)`; mode 0 (`FREE`) the swing knee
//! free, mode 1 (`LOCKED`) every knee locked; the leg swap after heel strike relabels the
//! segments, `θ' = (θ₃, θ₂, θ₁, θ₀)`.
//!
//! Checked here: the reference's own energy conservation and impact momenta; the engine's flow,
//! energy, constraint loads and heel strike (impact, ground impulse, leg swap) against it at
//! random states; the engine's batched flow against it in every lane and every mode of every
//! preset, with point feet and with round feet (a one-segment leg is a leg with a massless
//! thigh of zero length); the reference's stride map (its own RK4 with event location and Newton) at
//! the `seed5_walking` gait, where its impacts' impulses are printed and the engine's heel
//! strike is compared again. The reference knee strike ([`Reference::knee_strike`]: rolling
//! stance foot, the contact point at rest, angular momenta about the contact point and, for the
//! swing leg, about the hip conserved) is the map an engine knee strike with round feet must
//! equal.

use faer::Mat;
use pdw_hybrid::{HybridSystem, Options, Scratch, Section};
use pdw_walkers::spec::Num;
use pdw_walkers::{presets, ChainWalker, Walker, WalkerSpec};

/// Mode with the swing knee free (the stance knee locked).
const FREE: usize = 0;
/// Mode with both knees locked.
const LOCKED: usize = 1;

/// A point of the walker: `P = A + Σ_k (α_k e(θ_k) + β_k n(θ_k))` (module docs).
#[derive(Clone, Copy, Debug)]
struct Point {
    alpha: [f64; 4],
    beta: [f64; 4],
}

/// A rigid body: its COM, mass (kg), inertia about the COM (kg m²), the segment it turns with.
#[derive(Clone, Copy, Debug)]
struct Body {
    com: Point,
    mass: f64,
    inertia: f64,
    link: usize,
}

/// Body indices: stance shank, stance thigh, hip mass, swing thigh, swing shank.
const STANCE_LEG: [usize; 2] = [0, 1];
const SWING_LEG: [usize; 2] = [3, 4];

/// `e(θ)`: along a segment (up when the segment is upright).
fn e(th: f64) -> [f64; 2] {
    [-th.sin(), th.cos()]
}

/// `n(θ)`: normal to a segment, forward.
fn n(th: f64) -> [f64; 2] {
    [th.cos(), th.sin()]
}

/// `u_k = ∂P/∂θ_k = −α_k n(θ_k) + β_k e(θ_k)` (without the rolling term).
fn u(p: &Point, k: usize, th: &[f64; 4]) -> [f64; 2] {
    let (a, b, t) = (p.alpha[k], p.beta[k], th[k]);
    [-a * t.cos() - b * t.sin(), -a * t.sin() + b * t.cos()]
}

/// `d_k = ∂u_k/∂θ_k = −α_k e(θ_k) − β_k n(θ_k)` (centripetal direction).
fn d(p: &Point, k: usize, th: &[f64; 4]) -> [f64; 2] {
    let (a, b, t) = (p.alpha[k], p.beta[k], th[k]);
    [a * t.sin() - b * t.cos(), -a * t.cos() - b * t.sin()]
}

/// 2-D cross product `a × b` (positive from `+y` to `+z`, the sense of the angles).
fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// Solves `A x = b` in place (`A` row-major `n × n`, `b` becomes `x`) by Gaussian elimination
/// with partial pivoting.
fn solve(a: &mut [f64], b: &mut [f64], n: usize) {
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&i, &j| a[i * n + col].abs().total_cmp(&a[j * n + col].abs()))
            .unwrap();
        assert!(
            a[piv * n + col].abs() > 0.0,
            "singular system at column {col}"
        );
        if piv != col {
            for k in 0..n {
                a.swap(piv * n + k, col * n + k);
            }
            b.swap(piv, col);
        }
        for i in col + 1..n {
            let f = a[i * n + col] / a[col * n + col];
            if f == 0.0 {
                continue;
            }
            for k in col..n {
                a[i * n + k] -= f * a[col * n + k];
            }
            b[i] -= f * b[col];
        }
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= a[i * n + k] * b[k];
        }
        b[i] = s / a[i * n + i];
    }
}

/// Solves the constrained system `[M −Gᵀ; G 0] [v; λ] = [f; 0]` (`M` `nv × nv`, `G` `nc × nv`,
/// both row-major): returns `(v, λ)`.
fn kkt(mm: &[f64], g: &[f64], f: &[f64], nv: usize, nc: usize) -> (Vec<f64>, Vec<f64>) {
    let nt = nv + nc;
    let mut a = vec![0.0; nt * nt];
    let mut b = vec![0.0; nt];
    for i in 0..nv {
        for j in 0..nv {
            a[i * nt + j] = mm[i * nv + j];
        }
        b[i] = f[i];
    }
    for c in 0..nc {
        for j in 0..nv {
            a[(nv + c) * nt + j] = g[c * nv + j];
            a[j * nt + nv + c] = -g[c * nv + j];
        }
    }
    solve(&mut a, &mut b, nt);
    (b[..nv].to_vec(), b[nv..].to_vec())
}

/// Absolute segment angles (or rates) from the joint angles (or rates).
fn angles(q: &[f64]) -> [f64; 4] {
    [
        q[0],
        q[0] + q[1],
        q[0] + q[1] + q[2],
        q[0] + q[1] + q[2] + q[3],
    ]
}

/// Joint angles (or rates) from the absolute segment angles (or rates).
fn joints(th: &[f64]) -> [f64; 4] {
    [th[0], th[1] - th[0], th[2] - th[1], th[3] - th[2]]
}

/// Knee constraint rows in angle space: stance knee `θ₁ − θ₀`, swing knee `θ₃ − θ₂`.
const KNEE_ROWS: [[f64; 4]; 2] = [[-1.0, 1.0, 0.0, 0.0], [0.0, 0.0, -1.0, 1.0]];

/// Accelerations, lock torques and ground force at one state.
#[derive(Clone, Copy, Debug)]
struct Dynamics {
    /// Joint accelerations `q̈` (rad/s²).
    qdd: [f64; 4],
    /// Lock torques `[stance knee, swing knee]` on `q₁`, `q₃` (N m, positive towards `q`
    /// increasing; `None` where the knee is free).
    lock: [Option<f64>; 2],
    /// Ground force on the stance foot `[f_y, f_z]` (N).
    ground: [f64; 2],
}

/// The reference knee strike (rolling stance foot, stance knee held, swing knee stopped).
#[derive(Clone, Copy, Debug)]
pub(crate) struct KneeStrike {
    /// State just after the impact, swing knee angle and both knee rates set to exactly 0.
    pub x_post: [f64; 8],
    /// Joint rates just after the impact as solved (knee rates 0 to rounding).
    pub rates_post: [f64; 4],
    /// Ground impulse on the stance foot `[Λ_y, Λ_z]` (N s).
    pub ground_impulse: [f64; 2],
    /// Stop impulse of the stance knee (N m s, positive towards flexion).
    pub stance_knee_impulse: f64,
    /// Stop impulse of the striking swing knee (N m s, positive towards flexion).
    pub swing_knee_impulse: f64,
}

/// The reference heel strike (plastic impact at the new contact point, knees held, old stance
/// foot free) and the leg swap.
#[derive(Clone, Copy, Debug)]
struct HeelStrike {
    /// State after the impact and the leg swap.
    x_post: [f64; 8],
    /// Floating rates `(Ȧ_y, Ȧ_z, q̇)` after the impact, before the leg swap.
    floating_post: [f64; 6],
    /// Ground impulse on the new stance foot `[Λ_y, Λ_z]` (N s).
    contact_impulse: [f64; 2],
    /// Stop impulse of the trailing (old stance) knee (N m s, positive towards flexion).
    trailing_knee_impulse: f64,
    /// Stop impulse of the new stance (old swing) knee (N m s, positive towards flexion).
    new_stance_knee_impulse: f64,
    /// Velocity of the trailing foot's contact point after the impact `[slip along +y, normal
    /// separation]` (m/s).
    trailing_foot_velocity: [f64; 2],
}

/// The closed-form round-foot kneed walker (module docs).
#[derive(Clone, Debug)]
pub(crate) struct Reference {
    bodies: [Body; 5],
    /// hip (top of the stance thigh)
    hip: Point,
    /// swing arc centre (on the swing shank's line, `r` above its lower end)
    swing_arc: Point,
    radius: f64,
    gravity: f64,
    slope: f64,
    total_mass: f64,
    leg_length: f64,
}

impl Reference {
    /// The reference with the spec's evaluated geometry (`[L, m, c, c⊥, I]` per segment from
    /// the foot up, hip mass, foot radius, gravity, slope). A one-segment leg (the compass) is
    /// the two-segment leg whose thigh has zero length, mass and inertia: with both knees held
    /// (the locked mode) it moves as the rigid leg — the thigh angles' rows of `M` vanish, but
    /// `M` stays positive definite on the knee constraints' null space, so the KKT system of
    /// [`Reference::dynamics`] stays regular.
    fn new(w: &ChainWalker) -> Self {
        let rs = w.resolved();
        assert!(
            matches!(rs.segments.len(), 1 | 2),
            "one or two segments per leg"
        );
        let [l0, m0, c0, cn0, i0] = rs.segments[0];
        let [l1, m1, c1, cn1, i1] = rs.segments.get(1).copied().unwrap_or([0.0; 5]);
        let r = rs.foot_radius;
        let pt = |alpha: [f64; 4], beta: [f64; 4]| Point { alpha, beta };
        let bodies = [
            Body {
                com: pt([c0 - r, 0.0, 0.0, 0.0], [cn0, 0.0, 0.0, 0.0]),
                mass: m0,
                inertia: i0,
                link: 0,
            },
            Body {
                com: pt([l0 - r, c1, 0.0, 0.0], [0.0, cn1, 0.0, 0.0]),
                mass: m1,
                inertia: i1,
                link: 1,
            },
            Body {
                com: pt([l0 - r, l1, 0.0, 0.0], [0.0; 4]),
                mass: rs.hip_mass,
                inertia: 0.0,
                link: 1,
            },
            Body {
                com: pt([l0 - r, l1, -(l1 - c1), 0.0], [0.0, 0.0, cn1, 0.0]),
                mass: m1,
                inertia: i1,
                link: 2,
            },
            Body {
                com: pt([l0 - r, l1, -l1, -(l0 - c0)], [0.0, 0.0, 0.0, cn0]),
                mass: m0,
                inertia: i0,
                link: 3,
            },
        ];
        Self {
            bodies,
            hip: pt([l0 - r, l1, 0.0, 0.0], [0.0; 4]),
            swing_arc: pt([l0 - r, l1, -l1, -(l0 - r)], [0.0; 4]),
            radius: r,
            gravity: rs.gravity,
            slope: rs.slope,
            total_mass: 2.0 * (m0 + m1) + rs.hip_mass,
            leg_length: l0 + l1,
        }
    }

    /// `g⃗ = (g sin γ, −g cos γ)`.
    fn gvec(&self) -> [f64; 2] {
        [
            self.gravity * self.slope.sin(),
            -self.gravity * self.slope.cos(),
        ]
    }

    /// Stance arc centre `A = (−r θ₀, r)` (contact point at the origin for `θ₀ = 0`).
    fn arc_centre(&self, th: &[f64; 4]) -> [f64; 2] {
        [-self.radius * th[0], self.radius]
    }

    fn position(&self, p: &Point, a: [f64; 2], th: &[f64; 4]) -> [f64; 2] {
        let mut x = a;
        for (k, &t) in th.iter().enumerate() {
            let (ek, nk) = (e(t), n(t));
            x[0] += p.alpha[k] * ek[0] + p.beta[k] * nk[0];
            x[1] += p.alpha[k] * ek[1] + p.beta[k] * nk[1];
        }
        x
    }

    fn velocity(&self, p: &Point, adot: [f64; 2], th: &[f64; 4], thd: &[f64; 4]) -> [f64; 2] {
        let mut v = adot;
        for (k, &w) in thd.iter().enumerate() {
            let uk = u(p, k, th);
            v[0] += uk[0] * w;
            v[1] += uk[1] * w;
        }
        v
    }

    /// Rolling mass matrix `M(θ)` in angle space (module docs), row-major 4 × 4.
    fn mass_matrix(&self, th: &[f64; 4]) -> [f64; 16] {
        let r = self.radius;
        let mut mm = [0.0; 16];
        for b in &self.bodies {
            let (al, be, m) = (b.com.alpha, b.com.beta, b.mass);
            for j in 0..4 {
                for k in 0..4 {
                    let dl = th[j] - th[k];
                    mm[j * 4 + k] += m
                        * ((al[j] * al[k] + be[j] * be[k]) * dl.cos()
                            + (be[j] * al[k] - al[j] * be[k]) * dl.sin());
                }
            }
            for k in 0..4 {
                let rho_u = r * (al[k] * th[k].cos() + be[k] * th[k].sin());
                mm[k] += m * rho_u;
                mm[k * 4] += m * rho_u;
            }
            mm[0] += m * r * r;
            mm[b.link * 5] += b.inertia;
        }
        mm
    }

    /// Floating mass matrix in `(A_y, A_z, θ)` (arc centre free), row-major 6 × 6.
    fn floating_mass_matrix(&self, th: &[f64; 4]) -> [f64; 36] {
        let mut mm = [0.0; 36];
        for b in &self.bodies {
            let (al, be, m) = (b.com.alpha, b.com.beta, b.mass);
            mm[0] += m;
            mm[7] += m;
            for k in 0..4 {
                let uk = u(&b.com, k, th);
                for a in 0..2 {
                    mm[a * 6 + 2 + k] += m * uk[a];
                    mm[(2 + k) * 6 + a] += m * uk[a];
                }
            }
            for j in 0..4 {
                for k in 0..4 {
                    let dl = th[j] - th[k];
                    mm[(2 + j) * 6 + 2 + k] += m
                        * ((al[j] * al[k] + be[j] * be[k]) * dl.cos()
                            + (be[j] * al[k] - al[j] * be[k]) * dl.sin());
                }
            }
            mm[(2 + b.link) * 7] += b.inertia;
        }
        mm
    }

    /// `Q(θ) − c(θ, θ̇)` of the rolling walker (module docs).
    fn forces(&self, th: &[f64; 4], thd: &[f64; 4]) -> [f64; 4] {
        let (g, gam, r) = (self.gravity, self.slope, self.radius);
        let mut f = [0.0; 4];
        for b in &self.bodies {
            let (al, be, m) = (b.com.alpha, b.com.beta, b.mass);
            for j in 0..4 {
                f[j] += m * g * (al[j] * (th[j] - gam).sin() - be[j] * (th[j] - gam).cos());
                for k in 0..4 {
                    let (dl, w2) = (th[j] - th[k], thd[k] * thd[k]);
                    f[j] -= m
                        * w2
                        * ((al[j] * al[k] + be[j] * be[k]) * dl.sin()
                            + (al[j] * be[k] - be[j] * al[k]) * dl.cos());
                }
            }
            for k in 0..4 {
                f[0] += m * thd[k] * thd[k] * r * (al[k] * th[k].sin() - be[k] * th[k].cos());
            }
        }
        f[0] -= self.total_mass * g * r * gam.sin();
        f
    }

    /// Joint accelerations, lock torques and the ground force in `mode` at `x = (q, q̇)`.
    fn dynamics(&self, mode: usize, x: &[f64]) -> Dynamics {
        let (th, thd) = (angles(&x[..4]), angles(&x[4..8]));
        let mm = self.mass_matrix(&th);
        let f = self.forces(&th, &thd);
        let nc = if mode == FREE { 1 } else { 2 };
        let g: Vec<f64> = KNEE_ROWS[..nc].iter().flatten().copied().collect();
        let (thdd, tau) = kkt(&mm, &g, &f, 4, nc);
        let thdd: [f64; 4] = thdd.try_into().unwrap();
        // Newton: F = Σ m (a − g⃗), a = Ä + Σ_k (u_k θ̈_k + d_k θ̇_k²), Ä = (−r θ̈₀, 0)
        let gv = self.gvec();
        let mut ground = [0.0; 2];
        for b in &self.bodies {
            let mut a = [-self.radius * thdd[0], 0.0];
            for k in 0..4 {
                let (uk, dk) = (u(&b.com, k, &th), d(&b.com, k, &th));
                for c in 0..2 {
                    a[c] += uk[c] * thdd[k] + dk[c] * thd[k] * thd[k];
                }
            }
            for c in 0..2 {
                ground[c] += b.mass * (a[c] - gv[c]);
            }
        }
        Dynamics {
            qdd: joints(&thdd),
            lock: [Some(tau[0]), if nc == 2 { Some(tau[1]) } else { None }],
            ground,
        }
    }

    /// The flow `ẋ = (q̇, q̈)` in `mode`.
    fn flow(&self, mode: usize, x: &[f64]) -> [f64; 8] {
        let qdd = self.dynamics(mode, x).qdd;
        let mut dx = [0.0; 8];
        dx[..4].copy_from_slice(&x[4..8]);
        dx[4..].copy_from_slice(&qdd);
        dx
    }

    /// Kinetic energy `½ Σ m |v|² + ½ Σ I θ̇²` from the point velocities (rolling arc centre).
    fn kinetic_energy(&self, x: &[f64]) -> f64 {
        let (th, thd) = (angles(&x[..4]), angles(&x[4..8]));
        let adot = [-self.radius * thd[0], 0.0];
        self.bodies
            .iter()
            .map(|b| {
                let v = self.velocity(&b.com, adot, &th, &thd);
                0.5 * b.mass * (v[0] * v[0] + v[1] * v[1])
                    + 0.5 * b.inertia * thd[b.link] * thd[b.link]
            })
            .sum()
    }

    /// Total energy `T + V`, `V = −Σ m g⃗·P` (zero at the contact point's height, arc centre
    /// at height `r`).
    fn energy(&self, x: &[f64]) -> f64 {
        let th = angles(&x[..4]);
        let a = self.arc_centre(&th);
        let gv = self.gvec();
        let v: f64 = self
            .bodies
            .iter()
            .map(|b| {
                let p = self.position(&b.com, a, &th);
                -b.mass * (gv[0] * p[0] + gv[1] * p[1])
            })
            .sum();
        self.kinetic_energy(x) + v
    }

    /// Angular momentum of `bodies` about the point `o` (fixed in space), with the arc centre
    /// moving at `adot`: `Σ m (P − o) × v + I θ̇`.
    fn angular_momentum(
        &self,
        bodies: &[usize],
        o: [f64; 2],
        a: [f64; 2],
        adot: [f64; 2],
        th: &[f64; 4],
        thd: &[f64; 4],
    ) -> f64 {
        bodies
            .iter()
            .map(|&i| {
                let b = &self.bodies[i];
                let p = self.position(&b.com, a, th);
                let v = self.velocity(&b.com, adot, th, thd);
                b.mass * cross([p[0] - o[0], p[1] - o[1]], v) + b.inertia * thd[b.link]
            })
            .sum()
    }

    /// Linear momentum `Σ m v`.
    fn momentum(&self, adot: [f64; 2], th: &[f64; 4], thd: &[f64; 4]) -> [f64; 2] {
        let mut p = [0.0; 2];
        for b in &self.bodies {
            let v = self.velocity(&b.com, adot, th, thd);
            p[0] += b.mass * v[0];
            p[1] += b.mass * v[1];
        }
        p
    }

    /// Knee strike at `x` (free swing knee at 0): plastic stop of the swing knee with the
    /// stance knee held and the stance foot rolling (the contact point at rest, the arc centre
    /// at `−r θ̇₀` before and after): `[M −Gᵀ; G 0] [θ̇⁺; μ] = [M θ̇⁻; 0]`, `G` the two knee
    /// rows; the ground impulse is the change of the linear momentum.
    pub(crate) fn knee_strike(&self, x: &[f64]) -> KneeStrike {
        let (th, thd) = (angles(&x[..4]), angles(&x[4..8]));
        let mm = self.mass_matrix(&th);
        let mut f = [0.0; 4];
        for j in 0..4 {
            f[j] = (0..4).map(|k| mm[j * 4 + k] * thd[k]).sum();
        }
        let g: Vec<f64> = KNEE_ROWS.iter().flatten().copied().collect();
        let (thd_post, mu) = kkt(&mm, &g, &f, 4, 2);
        let thd_post: [f64; 4] = thd_post.try_into().unwrap();
        let p0 = self.momentum([-self.radius * thd[0], 0.0], &th, &thd);
        let p1 = self.momentum([-self.radius * thd_post[0], 0.0], &th, &thd_post);
        let mut x_post = [0.0; 8];
        x_post[..4].copy_from_slice(&x[..4]);
        x_post[3] = 0.0;
        x_post[4..].copy_from_slice(&joints(&thd_post));
        x_post[5] = 0.0;
        x_post[7] = 0.0;
        KneeStrike {
            x_post,
            rates_post: joints(&thd_post),
            ground_impulse: [p1[0] - p0[0], p1[1] - p0[1]],
            // a stance knee flexes with q₁ > 0, a swing knee with q₃ < 0
            stance_knee_impulse: mu[0],
            swing_knee_impulse: -mu[1],
        }
    }

    /// Rows of the new contact point's velocity in floating rates `(Ȧ_y, Ȧ_z, θ̇)`: the material
    /// point of the swing foot `r` below the swing arc centre, `v = Ȧ + Σ u_k θ̇_k + θ̇₃ (r, 0)`.
    fn contact_rows(&self, th: &[f64; 4]) -> [[f64; 6]; 2] {
        let mut g = [[0.0; 6]; 2];
        for (c, row) in g.iter_mut().enumerate() {
            row[c] = 1.0;
            for k in 0..4 {
                row[2 + k] = u(&self.swing_arc, k, th)[c];
            }
        }
        g[0][5] += self.radius;
        g
    }

    /// Heel strike at `x` (knees locked): `[M_F −Gᵀ; G 0] [ṗ⁺; λ] = [M_F ṗ⁻; 0]` on the floating
    /// walker `p = (A, θ)` with `Ȧ⁻ = (−r θ̇₀, 0)`, `G` the new contact point's two rows and the
    /// two knee rows; then the leg swap `θ' = (θ₃, θ₂, θ₁, θ₀)`.
    fn heel_strike(&self, x: &[f64]) -> HeelStrike {
        self.heel_strike_rows(x, true)
    }

    /// The heel strike of a walker whose knees are held by stops that only push: as
    /// [`Reference::heel_strike`], unless the trailing (old stance) knee's stop would have to
    /// pull (`trailing_knee_impulse < 0`); then that knee is free through the impact — the same
    /// impact without its row — and the new swing knee leaves it flexing.
    fn heel_strike_unilateral(&self, x: &[f64]) -> HeelStrike {
        let held = self.heel_strike_rows(x, true);
        if held.trailing_knee_impulse >= 0.0 {
            return held;
        }
        self.heel_strike_rows(x, false)
    }

    /// The heel strike with the trailing knee's row (`hold_trailing`) or without it.
    fn heel_strike_rows(&self, x: &[f64], hold_trailing: bool) -> HeelStrike {
        let (th, thd) = (angles(&x[..4]), angles(&x[4..8]));
        let mm = self.floating_mass_matrix(&th);
        let mut pd = [0.0; 6];
        pd[0] = -self.radius * thd[0];
        pd[2..].copy_from_slice(&thd);
        let mut f = [0.0; 6];
        for j in 0..6 {
            f[j] = (0..6).map(|k| mm[j * 6 + k] * pd[k]).sum();
        }
        let mut g = Vec::with_capacity(24);
        for row in self.contact_rows(&th) {
            g.extend_from_slice(&row);
        }
        let knees = if hold_trailing {
            &KNEE_ROWS[..]
        } else {
            &KNEE_ROWS[1..]
        };
        for row in knees {
            g.extend_from_slice(&[0.0, 0.0]);
            g.extend_from_slice(row);
        }
        let (pd_post, lam) = kkt(&mm, &g, &f, 6, 2 + knees.len());
        let thd_post = [pd_post[2], pd_post[3], pd_post[4], pd_post[5]];
        let mut floating_post = [0.0; 6];
        floating_post[..2].copy_from_slice(&pd_post[..2]);
        floating_post[2..].copy_from_slice(&joints(&thd_post));
        let th_new = [th[3], th[2], th[1], th[0]];
        let thd_new = [thd_post[3], thd_post[2], thd_post[1], thd_post[0]];
        let mut x_post = [0.0; 8];
        x_post[..4].copy_from_slice(&joints(&th_new));
        x_post[4..].copy_from_slice(&joints(&thd_new));
        HeelStrike {
            x_post,
            floating_post,
            contact_impulse: [lam[0], lam[1]],
            trailing_knee_impulse: if hold_trailing { lam[2] } else { 0.0 },
            new_stance_knee_impulse: -lam[1 + knees.len()],
            // the old stance foot's contact point, r below A on the shank: Ȧ + θ̇₀ (r, 0)
            trailing_foot_velocity: [pd_post[0] + self.radius * thd_post[0], pd_post[1]],
        }
    }

    /// Natural scales: `g/l` (accelerations), `√(g/l)` (rates), `m g` (forces), `m g l`
    /// (torques, energies), `m √(g l)` (impulses), `m l √(g l)` (angular momenta).
    fn scales(&self) -> Scales {
        let (m, g, l) = (self.total_mass, self.gravity, self.leg_length);
        Scales {
            acc: g / l,
            rate: (g / l).sqrt(),
            force: m * g,
            torque: m * g * l,
            impulse: m * (g * l).sqrt(),
            ang: m * l * (g * l).sqrt(),
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct Scales {
    acc: f64,
    rate: f64,
    force: f64,
    torque: f64,
    impulse: f64,
    ang: f64,
}

/// SplitMix64: a seeded generator of uniform numbers in `[lo, hi)`.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        lo + (hi - lo) * ((z >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// A random state of `mode`: the stance knee (and in the locked mode the swing knee) straight
/// and still, the free swing knee flexed up to 0.6 rad, rates up to 1.5 `√(g/l)`.
fn random_state(rng: &mut Rng, mode: usize, rate: f64) -> [f64; 8] {
    let mut x = [0.0; 8];
    x[0] = rng.uniform(-0.5, 0.5);
    x[2] = rng.uniform(-1.0, 1.0);
    x[4] = rate * rng.uniform(-1.5, 1.5);
    x[6] = rate * rng.uniform(-1.5, 1.5);
    if mode == FREE {
        x[3] = rng.uniform(-0.6, 0.05);
        x[7] = rate * rng.uniform(-1.5, 1.5);
    }
    x
}

/// The `seed5_walking` spec file.
fn seed5_walking() -> ChainWalker {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/seed5_walking.toml");
    ChainWalker::from_spec(WalkerSpec::from_file(&path).unwrap()).unwrap()
}

/// A kneed walker with inertia about each COM, COM offsets normal to both segments, a hip mass
/// and round feet of radius 0.1 m (leg 0.95 m).
const VARIANT: &str = r#"
name = "round_foot_kneed_variant"
description = "kneed walker with segment inertias, normal COM offsets and 0.1 m round feet"
hip_mass = "hip_mass"
foot_radius = "foot_radius"

[parameters]
slope = { value = 0.03, unit = "rad" }
hip_mass = { value = 4.0, unit = "kg" }
foot_radius = { value = 0.1, unit = "m" }

[[segments]]
name = "shank"
length = 0.5
mass = 1.5
com = 0.2
com_normal = -0.03
inertia = 0.04

[[segments]]
name = "thigh"
length = 0.45
mass = 3.2
com = 0.25
com_normal = 0.05
inertia = 0.07

[[knees]]
mode = "free-swing"
"#;

fn variant() -> ChainWalker {
    ChainWalker::from_spec(WalkerSpec::from_toml(VARIANT, "variant").unwrap()).unwrap()
}

fn walkers() -> Vec<(&'static str, ChainWalker)> {
    vec![("seed5_walking", seed5_walking()), ("variant", variant())]
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn rk4(r: &Reference, mode: usize, x: &[f64; 8], h: f64) -> [f64; 8] {
    let add = |x: &[f64; 8], k: &[f64; 8], s: f64| -> [f64; 8] {
        let mut y = *x;
        for i in 0..8 {
            y[i] += s * k[i];
        }
        y
    };
    let k1 = r.flow(mode, x);
    let k2 = r.flow(mode, &add(x, &k1, 0.5 * h));
    let k3 = r.flow(mode, &add(x, &k2, 0.5 * h));
    let k4 = r.flow(mode, &add(x, &k3, h));
    let mut y = *x;
    for i in 0..8 {
        y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    y
}

/// Self-check: `T = ½ θ̇ᵀ M θ̇` (the closed-form mass matrix against the point velocities) and
/// `T + V` constant along the reference's own flow (RK4, 400 steps of 0.5 ms per mode).
#[test]
fn reference_conserves_energy_along_its_flow() {
    for (name, w) in walkers() {
        let r = Reference::new(&w);
        let s = r.scales();
        let mut rng = Rng(7);
        let mut worst_t = 0.0f64;
        let mut worst_drift = 0.0f64;
        for mode in [FREE, LOCKED] {
            for _ in 0..5 {
                let x0 = random_state(&mut rng, mode, s.rate);
                let (th, thd) = (angles(&x0[..4]), angles(&x0[4..8]));
                let mm = r.mass_matrix(&th);
                let mut t = 0.0;
                for j in 0..4 {
                    for k in 0..4 {
                        t += 0.5 * thd[j] * mm[j * 4 + k] * thd[k];
                    }
                }
                worst_t = worst_t.max((t - r.kinetic_energy(&x0)).abs() / s.torque);
                let e0 = r.energy(&x0);
                let mut x = x0;
                for _ in 0..400 {
                    x = rk4(&r, mode, &x, 5e-4);
                    worst_drift = worst_drift.max((r.energy(&x) - e0).abs() / s.torque);
                }
            }
        }
        eprintln!("{name}: |T − ½θ̇ᵀMθ̇| ≤ {worst_t:.2e}, energy drift ≤ {worst_drift:.2e} m g l");
        assert!(
            worst_t < 1e-14,
            "{name}: kinetic energy from M differs from the point velocities by {worst_t:e} m g l"
        );
        assert!(
            worst_drift < 1e-11,
            "{name}: energy drift {worst_drift:e} m g l along the reference flow (RK4, h = 0.5 ms)"
        );
    }
}

/// Self-check of the reference impacts: heel strike conserves the walker's angular momentum
/// about the new contact point and the trailing leg's about the hip, brings the new contact
/// point to rest and holds the knees (with the trailing knee released where its stop would pull:
/// the same, and the trailing shank's about the free knee); knee strike conserves the walker's angular momentum about
/// the stance contact point and the swing leg's about the hip, keeps the contact point at rest
/// (arc centre at `−r θ̇₀`) and stops the knees. All to 1e-12 of `m l √(g l)` (`√(g l)`).
#[test]
fn reference_impacts_conserve_angular_momenta() {
    for (name, w) in walkers() {
        let r = Reference::new(&w);
        let s = r.scales();
        let mut rng = Rng(11);
        let (mut worst_h, mut worst_v) = (0.0f64, 0.0f64);
        let mut released = 0;
        for _ in 0..20 {
            // heel strike
            let x = random_state(&mut rng, LOCKED, s.rate);
            let hs = r.heel_strike(&x);
            let th = angles(&x[..4]);
            let (thd0, thd1) = (angles(&x[4..8]), angles(&hs.floating_post[2..6]));
            let a = r.arc_centre(&th);
            let (ad0, ad1) = (
                [-r.radius * thd0[0], 0.0],
                [hs.floating_post[0], hs.floating_post[1]],
            );
            let sa = r.position(&r.swing_arc, a, &th);
            let contact = [sa[0], sa[1] - r.radius];
            let all = [0, 1, 2, 3, 4];
            let dh_all = r.angular_momentum(&all, contact, a, ad1, &th, &thd1)
                - r.angular_momentum(&all, contact, a, ad0, &th, &thd0);
            let hip = r.position(&r.hip, a, &th);
            let dh_trail = r.angular_momentum(&STANCE_LEG, hip, a, ad1, &th, &thd1)
                - r.angular_momentum(&STANCE_LEG, hip, a, ad0, &th, &thd0);
            let sv = r.velocity(&r.swing_arc, ad1, &th, &thd1);
            let contact_v = [sv[0] + r.radius * thd1[3], sv[1]];
            worst_h = worst_h.max(dh_all.abs().max(dh_trail.abs()) / s.ang);
            // with the trailing knee released (where its stop would pull): the same momenta,
            // and the trailing shank's about the free trailing knee
            if hs.trailing_knee_impulse < 0.0 {
                let hu = r.heel_strike_unilateral(&x);
                let thd1 = angles(&hu.floating_post[2..6]);
                let ad1 = [hu.floating_post[0], hu.floating_post[1]];
                let mut knee = r.hip;
                knee.alpha[1] = 0.0;
                let knee = r.position(&knee, a, &th);
                for (bodies, o) in [
                    (&all[..], contact),
                    (&STANCE_LEG[..], hip),
                    (&[0usize][..], knee),
                ] {
                    let dh = r.angular_momentum(bodies, o, a, ad1, &th, &thd1)
                        - r.angular_momentum(bodies, o, a, ad0, &th, &thd0);
                    worst_h = worst_h.max(dh.abs() / s.ang);
                }
                released += 1;
            }
            worst_v = worst_v.max(
                contact_v[0]
                    .abs()
                    .max(contact_v[1].abs())
                    .max((thd1[1] - thd1[0]).abs())
                    .max((thd1[3] - thd1[2]).abs())
                    / s.rate,
            );
            // knee strike
            let x = random_state(&mut rng, FREE, s.rate);
            let ks = r.knee_strike(&x);
            let th = angles(&x[..4]);
            let (thd0, thd1) = (angles(&x[4..8]), angles(&ks.rates_post));
            let a = r.arc_centre(&th);
            let (ad0, ad1) = ([-r.radius * thd0[0], 0.0], [-r.radius * thd1[0], 0.0]);
            let contact = [a[0], a[1] - r.radius];
            let dh_all = r.angular_momentum(&all, contact, a, ad1, &th, &thd1)
                - r.angular_momentum(&all, contact, a, ad0, &th, &thd0);
            let hip = r.position(&r.hip, a, &th);
            let dh_swing = r.angular_momentum(&SWING_LEG, hip, a, ad1, &th, &thd1)
                - r.angular_momentum(&SWING_LEG, hip, a, ad0, &th, &thd0);
            worst_h = worst_h.max(dh_all.abs().max(dh_swing.abs()) / s.ang);
            let post_knees = ks.rates_post[1].abs().max(ks.rates_post[3].abs());
            worst_v = worst_v.max(post_knees / s.rate);
        }
        eprintln!(
            "{name}: impacts |ΔH| ≤ {worst_h:.2e} m l √(gl), constraint rates ≤ {worst_v:.2e} √(g/l)"
        );
        assert!(
            worst_h < 1e-12,
            "{name}: angular momentum through the reference impacts changes by {worst_h:e} m l √(g l)"
        );
        assert!(
            released > 0,
            "{name}: no released heel strike among the states"
        );
        assert!(
            worst_v < 1e-12,
            "{name}: constraint rates after the reference impacts {worst_v:e} √(g/l)"
        );
    }
}

/// The engine's flow (rolling-base recursion) equals the closed form to 1e-10 `g/l` at 20
/// random states per mode; the engine's energy equals the reference's up to the constant
/// `m g r cos γ` (the engine's potential is zero at the arc centre's height).
#[test]
fn flow_matches_reference_to_1e_10() {
    for (name, w) in walkers() {
        let r = Reference::new(&w);
        let s = r.scales();
        let mut rng = Rng(3);
        let mut ws = Scratch::new();
        let (mut worst, mut worst_e) = (0.0f64, 0.0f64);
        let e_shift = r.total_mass * r.gravity * r.radius * r.slope.cos();
        for mode in [FREE, LOCKED] {
            for _ in 0..20 {
                let x = random_state(&mut rng, mode, s.rate);
                let mut dx = [0.0; 8];
                w.flow(&mut ws, mode, &x, &mut dx);
                let rf = r.flow(mode, &x);
                worst = worst.max(max_abs_diff(&dx, &rf) / s.acc);
                let ee = w.energy(&x).unwrap();
                worst_e = worst_e.max((r.energy(&x) - e_shift - ee).abs() / s.torque);
            }
        }
        eprintln!("{name}: flow |Δẋ| ≤ {worst:.2e} g/l, energy ≤ {worst_e:.2e} m g l");
        assert!(
            worst < 1e-10,
            "{name}: engine flow differs from the reference by {worst:e} g/l"
        );
        assert!(
            worst_e < 1e-10,
            "{name}: engine energy differs from the reference by {worst_e:e} m g l"
        );
    }
}

/// Every preset (compass, kneed, seed5 with locked knees, seed5 with a free swing knee) with
/// point feet and with round feet of radius 0.15 leg lengths, and the two round-foot walkers of
/// [`walkers`].
fn presets_flat_and_round() -> Vec<(String, ChainWalker)> {
    let mut out = Vec::new();
    for (name, w) in [
        ("compass", presets::compass(&[]).unwrap()),
        ("kneed", presets::kneed(&[]).unwrap()),
        ("seed5", presets::seed5(&[]).unwrap()),
        (
            "seed5 free knee",
            presets::seed5(&[("free_swing_knee", 1.0)]).unwrap(),
        ),
    ] {
        let mut spec = w.spec().clone();
        spec.foot_radius = Num::Value(0.15 * w.leg_length());
        let values: Vec<f64> = w.param_values().into_iter().map(|(_, v)| v).collect();
        let round = ChainWalker::new(spec, &values).unwrap();
        assert!(w.resolved().foot_radius == 0.0 && round.resolved().foot_radius > 0.0);
        out.push((format!("{name} (round feet)"), round));
        out.push((name.to_string(), w));
    }
    out.extend(walkers().into_iter().map(|(n, w)| (n.to_string(), w)));
    out
}

/// The reference mode of the chain walker's `mode`, once the mode is checked to mean it: with
/// a free swing knee (joint 3), mode 0 frees it and holds the stance knee (joint 1) and mode 1
/// holds both; without one there is a single mode holding every knee (none for the compass).
fn reference_mode(w: &ChainWalker, mode: usize) -> usize {
    let knees: &[usize] = if w.dim() == 8 { &[1, 3] } else { &[] };
    match (w.free_knee(), mode) {
        (Some(3), 0) => {
            assert_eq!(w.n_modes(), 2);
            assert_eq!(w.locked_joints(mode), &[1]);
            FREE
        }
        (Some(3), 1) | (None, 0) => {
            assert_eq!(w.n_modes(), 1 + usize::from(w.free_knee().is_some()));
            assert_eq!(w.locked_joints(mode), knees);
            LOCKED
        }
        other => panic!("unexpected (free knee, mode) {other:?}"),
    }
}

/// The chain walker's state of the reference state `x` (the compass drops the held knees).
fn chain_state(w: &ChainWalker, x: &[f64; 8]) -> Vec<f64> {
    match w.dim() {
        8 => x.to_vec(),
        _ => vec![x[0], x[2], x[4], x[6]],
    }
}

/// The chain walker's `flow_batch` over `xs`, one lane per state: the rows of `ẋ`.
fn flow_batch_rows(
    w: &ChainWalker,
    ws: &mut Scratch,
    mode: usize,
    xs: &[Vec<f64>],
) -> Vec<Vec<f64>> {
    let d = w.dim();
    let x = Mat::from_fn(xs.len(), d, |l, j| xs[l][j]);
    let mut dx = Mat::<f64>::zeros(xs.len(), d);
    w.flow_batch(ws, mode, x.as_ref(), dx.as_mut());
    (0..xs.len())
        .map(|l| (0..d).map(|j| dx[(l, j)]).collect())
        .collect()
}

/// The chain walker's batched flow (`flow_batch`: the articulated-body recursion over SIMD
/// blocks of 64 lanes for point feet, the rolling-base dynamics lane by lane for round feet)
/// against the reference's Lagrange/KKT vector field ([`Reference::flow`]), lane by lane, in
/// every mode of every preset with point feet and with round feet, and of the two round-foot
/// walkers: 300 seeded states per mode (the reference's [`random_state`]).
///
/// Modes covered: the free-knee mode (swing knee free, stance knee held) and the locked mode of
/// kneed, seed5 free knee, seed5_walking and the variant; the single locked mode of seed5 and of
/// the compass (a leg with a massless thigh of zero length, [`Reference::new`]). The compass'
/// one mode with point feet is also covered by `compass_closed_form.rs` (Goswami's M/C/G).
///
/// Each lane's largest difference, relative to the lane's largest component of `ẋ`, stays below
/// 1e-12 (measured: 1.9e-14 worst, seed5_walking; 1.5e-15 to 1.3e-14 for the others). Lane
/// counts 1, 7 and 300: the batches are windows of the same states (300 = four blocks of 64 and
/// a remainder of 44; the 7 lanes are lanes 61–67 of the big batch, across its first block
/// boundary; the single lane is its last), and each lane has the same bits in every batch it is
/// part of (no lane reads another's data).
#[test]
fn batched_flow_matches_reference_in_every_mode_and_lane_for_every_lane_count() {
    let mut ws = Scratch::new();
    let mut report = Vec::new();
    for (name, w) in presets_flat_and_round() {
        let r = Reference::new(&w);
        let s = r.scales();
        let mut rng = Rng(19);
        let mut worst = 0.0f64;
        for mode in 0..w.n_modes() {
            let rm = reference_mode(&w, mode);
            let ref_states: Vec<[f64; 8]> = (0..300)
                .map(|_| random_state(&mut rng, rm, s.rate))
                .collect();
            let xs: Vec<Vec<f64>> = ref_states.iter().map(|x| chain_state(&w, x)).collect();
            let all = flow_batch_rows(&w, &mut ws, mode, &xs);
            for window in [0..300, 61..68, 299..300] {
                let part = flow_batch_rows(&w, &mut ws, mode, &xs[window.clone()]);
                for (l, f) in part.iter().enumerate() {
                    let same = f
                        .iter()
                        .zip(&all[window.start + l])
                        .all(|(a, b)| a.to_bits() == b.to_bits());
                    assert!(
                        same,
                        "{name} mode {mode}, {} lanes: lane {l} differs from lane {} of the \
                         300-lane batch",
                        window.len(),
                        window.start + l
                    );
                }
            }
            for (l, (x, f)) in ref_states.iter().zip(&all).enumerate() {
                let rf = chain_state(&w, &r.flow(rm, x));
                let rel = max_abs_diff(f, &rf) / rf.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                assert!(
                    rel < 1e-12,
                    "{name} mode {mode} lane {l} at {x:?}: chain walker {f:?} vs reference {rf:?}"
                );
                worst = worst.max(rel);
            }
        }
        report.push(format!("{name} {worst:.1e}"));
    }
    eprintln!(
        "batched flow vs reference, worst relative difference: {}",
        report.join(", ")
    );
}

/// The engine's constraint loads (ground normal and tangential force, stance knee lock torque,
/// swing knee lock torque in the locked mode) equal the reference's Newton–Euler ground force
/// and Lagrange multipliers to 1e-10 of `m g` and `m g l`.
#[test]
fn constraint_loads_match_reference_to_1e_10() {
    for (name, w) in walkers() {
        let r = Reference::new(&w);
        let s = r.scales();
        let mut rng = Rng(5);
        let (mut worst_f, mut worst_t) = (0.0f64, 0.0f64);
        for mode in [FREE, LOCKED] {
            for _ in 0..20 {
                let x = random_state(&mut rng, mode, s.rate);
                let cf = w.constraint_forces(mode, &x).unwrap();
                let rd = r.dynamics(mode, &x);
                worst_f = worst_f
                    .max((cf.normal - rd.ground[1]).abs() / s.force)
                    .max((cf.tangential - rd.ground[0]).abs() / s.force);
                // engine: positive towards flexion (stance q₁ > 0, swing q₃ < 0)
                let stance = cf.knee_torque[0].expect("stance knee locked");
                worst_t = worst_t.max((stance - rd.lock[0].unwrap()).abs() / s.torque);
                match (mode, cf.knee_torque[1], rd.lock[1]) {
                    (LOCKED, Some(e), Some(t)) => worst_t = worst_t.max((e + t).abs() / s.torque),
                    (FREE, None, None) => {}
                    other => panic!("{name}: swing knee lock mismatch in mode {mode}: {other:?}"),
                }
            }
        }
        eprintln!("{name}: ground force ≤ {worst_f:.2e} m g, knee torques ≤ {worst_t:.2e} m g l");
        assert!(
            worst_f < 1e-10,
            "{name}: ground force differs from the reference by {worst_f:e} m g"
        );
        assert!(
            worst_t < 1e-10,
            "{name}: knee lock torques differ from the reference by {worst_t:e} m g l"
        );
    }
}

/// The engine's heel strike (impact + leg swap) equals the reference's to 1e-10 `√(g/l)` at
/// 20 random locked states, and its ground impulse to 1e-10 `m √(g l)`.
#[test]
fn heel_strike_matches_reference_to_1e_10() {
    for (name, w) in walkers() {
        let r = Reference::new(&w);
        let s = r.scales();
        let mut rng = Rng(13);
        let mut ws = Scratch::new();
        let (mut worst_x, mut worst_i) = (0.0f64, 0.0f64);
        let mut released = 0;
        for _ in 0..40 {
            let x = random_state(&mut rng, LOCKED, s.rate);
            let mut out = [0.0; 8];
            let next = w.reset(&mut ws, LOCKED, 0, &x, &mut out);
            assert_eq!(next, FREE, "{name}: heel strike leads to the free mode");
            // the model's map: the trailing knee released where its stop would pull
            let hu = r.heel_strike_unilateral(&x);
            let hs = r.heel_strike(&x);
            let rel = hs.trailing_knee_impulse < 0.0;
            released += usize::from(rel);
            assert_eq!(
                w.trailing_knee_releases_at(&x),
                rel,
                "{name}: the engine's release decision differs from the reference's at {x:?}"
            );
            worst_x = worst_x
                .max(max_abs_diff(&out[..4], &hu.x_post[..4]))
                .max(max_abs_diff(&out[4..], &hu.x_post[4..]) / s.rate);
            if rel {
                // the new swing knee (joint 3) leaves flexing (q < 0 for a swing knee)
                assert!(
                    out[7] < 0.0,
                    "{name}: released trailing knee must leave flexing, rate {}",
                    out[7]
                );
            }
            let mut fl = [0.0; 6];
            let imp = w.heel_strike(&mut ws, &x, &mut fl);
            worst_x = worst_x.max(max_abs_diff(&fl, &hs.floating_post) / s.rate);
            worst_i = worst_i.max(max_abs_diff(&imp, &hs.contact_impulse) / s.impulse);
        }
        eprintln!(
            "{name}: heel strike |Δx| ≤ {worst_x:.2e}, impulse ≤ {worst_i:.2e} m √(gl); {released} \
             of 40 states release the trailing knee"
        );
        assert!(
            released > 0 && released < 40,
            "{name}: the random states must exercise both maps ({released} of 40 released)"
        );
        assert!(
            worst_x < 1e-10,
            "{name}: heel strike differs from the reference by {worst_x:e} (rates in √(g/l))"
        );
        assert!(
            worst_i < 1e-10,
            "{name}: heel strike impulse differs from the reference by {worst_i:e} m √(g l)"
        );
    }
}

/// One RK4 step from `x` over `h` then steps of `h` until `guard` rises through 0 (after it
/// has been negative); the crossing is located by bisection on the length of the last RK4 step
/// (to rounding). Returns the state at the crossing, or `None` after `t_max`.
fn integrate_to_event(
    r: &Reference,
    mode: usize,
    x0: &[f64; 8],
    guard: impl Fn(&[f64; 8]) -> Option<f64>,
    h: f64,
    t_max: f64,
) -> Option<[f64; 8]> {
    let mut x = *x0;
    let mut armed = false;
    let mut t = 0.0;
    while t < t_max {
        let y = rk4(r, mode, &x, h);
        let gy = guard(&y);
        if armed && gy.is_some_and(|g| g >= 0.0) {
            let (mut lo, mut hi) = (0.0, h);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                if guard(&rk4(r, mode, &x, mid)).is_some_and(|g| g >= 0.0) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            return Some(rk4(r, mode, &x, hi));
        }
        armed = gy.is_some_and(|g| g < 0.0);
        x = y;
        t += h;
    }
    None
}

/// States of one stride of the reference from the section point `s = (q₀, q̇₀, q̇_m)` (every
/// knee straight, `q_m = −2q₀`): before the knee strike, before the heel strike, and the next
/// section point. The knee strike is the free knee rising through 0; the heel strike the swing
/// foot's lowest point (r below its arc centre) falling through the slope with the swing foot
/// ahead. RK4, 0.5 ms steps.
fn reference_stride(r: &Reference, s: &[f64; 3]) -> Option<([f64; 8], [f64; 8], [f64; 3])> {
    let x0 = [s[0], 0.0, -2.0 * s[0], 0.0, s[1], 0.0, s[2], 0.0];
    let h = 5e-4;
    let x_ks = integrate_to_event(r, FREE, &x0, |x| Some(x[3]), h, 10.0)?;
    let x1 = r.knee_strike(&x_ks).x_post;
    let foot = |x: &[f64; 8]| {
        let th = angles(&x[..4]);
        let a = r.arc_centre(&th);
        let p = r.position(&r.swing_arc, a, &th);
        // −height (falling through 0 is −height rising), only with the swing foot ahead
        (p[0] > a[0]).then_some(-(p[1] - a[1]))
    };
    let x_hs = integrate_to_event(r, LOCKED, &x1, foot, h, 10.0)?;
    let x2 = r.heel_strike(&x_hs).x_post;
    Some((x_ks, x_hs, [x2[0], x2[4], x2[6]]))
}

/// The reference's fixed point of the stride map near `guess` (Newton, central differences)
/// and the states just before its knee strike and heel strike.
fn reference_gait(r: &Reference, guess: &[f64]) -> ([f64; 8], [f64; 8], [f64; 3], f64) {
    let mut s = [guess[0], guess[1], guess[2]];
    let f = |s: &[f64; 3]| -> [f64; 3] {
        let p = reference_stride(r, s)
            .expect("the reference stride completes")
            .2;
        [p[0] - s[0], p[1] - s[1], p[2] - s[2]]
    };
    let mut res = f64::INFINITY;
    for _ in 0..12 {
        let f0 = f(&s);
        res = f0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if res < 1e-11 {
            break;
        }
        let mut jac = [0.0; 9];
        for j in 0..3 {
            let dh = 1e-6;
            let (mut sp, mut sm) = (s, s);
            sp[j] += dh;
            sm[j] -= dh;
            let (fp, fm) = (f(&sp), f(&sm));
            for i in 0..3 {
                jac[i * 3 + j] = (fp[i] - fm[i]) / (2.0 * dh);
            }
        }
        let mut step = f0;
        solve(&mut jac, &mut step, 3);
        for i in 0..3 {
            s[i] -= step[i];
        }
    }
    let (x_ks, x_hs, _) = reference_stride(r, &s).unwrap();
    (x_ks, x_hs, s, res)
}

/// The seed5_walking gait of the reference (from the spec's gait guess): pre-impact states.
fn gait_pre_impact_states(w: &ChainWalker) -> ([f64; 8], [f64; 8], [f64; 3]) {
    let r = Reference::new(w);
    let (x_ks, x_hs, s, res) = reference_gait(&r, &w.gait_guesses()[0].section);
    assert!(res < 1e-10, "reference fixed point residual {res:e}");
    (x_ks, x_hs, s)
}

/// At the seed5_walking gait: the engine's heel strike equals the reference's to 1e-10, the
/// reference impacts conserve their angular momenta, the new contact's normal impulse pushes;
/// the reference impulses are printed (`--nocapture`).
#[test]
fn impulses_at_the_seed5_walking_gait() {
    let w = seed5_walking();
    let r = Reference::new(&w);
    let s = r.scales();
    let (x_ks, x_hs, section) = gait_pre_impact_states(&w);
    let ks = r.knee_strike(&x_ks);
    let hs = r.heel_strike(&x_hs);
    let hu = r.heel_strike_unilateral(&x_hs);
    eprintln!("seed5_walking fixed point {section:?}");
    eprintln!("knee strike pre {x_ks:?}");
    eprintln!(
        "knee strike: ground impulse normal {:.6e} N s, tangential {:.6e} N s, stance knee stop \
         {:.6e} N m s, striking knee stop {:.6e} N m s",
        ks.ground_impulse[1], ks.ground_impulse[0], ks.stance_knee_impulse, ks.swing_knee_impulse
    );
    eprintln!("heel strike pre {x_hs:?}");
    eprintln!(
        "heel strike: new contact normal {:.6e} N s, tangential {:.6e} N s, trailing knee stop \
         {:.6e} N m s, new stance knee stop {:.6e} N m s, trailing foot separation {:.6e} m/s, \
         slip {:.6e} m/s",
        hs.contact_impulse[1],
        hs.contact_impulse[0],
        hs.trailing_knee_impulse,
        hs.new_stance_knee_impulse,
        hs.trailing_foot_velocity[1],
        hs.trailing_foot_velocity[0]
    );
    let mut ws = Scratch::new();
    let mut out = [0.0; 8];
    w.reset(&mut ws, LOCKED, 0, &x_hs, &mut out);
    // its stop would pull (the held impulse is negative): the model releases the trailing knee
    assert!(
        hs.trailing_knee_impulse < 0.0 && w.trailing_knee_releases_at(&x_hs),
        "the seed5_walking gait's trailing knee must be released (held impulse {:e} N m s)",
        hs.trailing_knee_impulse
    );
    eprintln!(
        "heel strike with the trailing knee released: new swing knee rate {:.6} rad/s, new \
         stance knee stop {:.6e} N m s, trailing foot separation {:.6e} m/s",
        hu.x_post[7], hu.new_stance_knee_impulse, hu.trailing_foot_velocity[1]
    );
    let dx = max_abs_diff(&out[..4], &hu.x_post[..4])
        .max(max_abs_diff(&out[4..], &hu.x_post[4..]) / s.rate);
    let mut fl = [0.0; 6];
    let imp = w.heel_strike(&mut ws, &x_hs, &mut fl);
    let di = max_abs_diff(&imp, &hs.contact_impulse) / s.impulse;
    eprintln!("gait heel strike vs engine: state {dx:.2e}, impulse {di:.2e} m √(gl)");
    assert!(dx < 1e-10, "gait heel strike state differs by {dx:e}");
    assert!(
        di < 1e-10,
        "gait heel strike impulse differs by {di:e} m √(g l)"
    );
    assert!(
        hs.contact_impulse[1] > 0.0,
        "the new stance foot's normal impulse must push: {:e} N s",
        hs.contact_impulse[1]
    );
    assert!(
        ks.swing_knee_impulse > 0.0,
        "the striking knee's stop must push towards flexion: {:e} N m s",
        ks.swing_knee_impulse
    );
    assert!(
        ks.x_post.iter().chain(&hs.x_post).all(|v| v.is_finite()),
        "finite post-impact states"
    );
}

/// The engine's knee strike (impact map of the free mode's guard 0) equals the reference's
/// (rolling stance foot) to 1e-10 `√(g/l)` at 20 random free states with the knee at 0.
#[test]
fn knee_strike_matches_reference_to_1e_10() {
    for (name, w) in walkers() {
        let r = Reference::new(&w);
        let s = r.scales();
        let mut rng = Rng(17);
        let mut ws = Scratch::new();
        let mut worst = 0.0f64;
        let mut worst_hip = 0.0f64;
        for _ in 0..20 {
            let mut x = random_state(&mut rng, FREE, s.rate);
            x[3] = 0.0;
            x[7] = x[7].abs();
            let mut out = [0.0; 8];
            let next = w.reset(&mut ws, FREE, 0, &x, &mut out);
            assert_eq!(next, LOCKED, "{name}: knee strike leads to the locked mode");
            let ks = r.knee_strike(&x);
            worst = worst
                .max(max_abs_diff(&out[..4], &ks.x_post[..4]))
                .max(max_abs_diff(&out[4..], &ks.x_post[4..]) / s.rate);
            worst_hip = worst_hip.max((out[6] - ks.x_post[6]).abs() / s.rate);
        }
        if name == "seed5_walking" {
            let (x_ks, _, _) = gait_pre_impact_states(&w);
            let mut out = [0.0; 8];
            w.reset(&mut ws, FREE, 0, &x_ks, &mut out);
            let ks = r.knee_strike(&x_ks);
            eprintln!("gait knee strike: engine {out:?}");
            eprintln!("gait knee strike: reference {:?}", ks.x_post);
            let dg = max_abs_diff(&out[4..], &ks.x_post[4..]) / s.rate;
            worst = worst.max(dg);
            eprintln!("gait knee strike: |Δq̇| ≤ {dg:.2e} √(g/l)");
        }
        eprintln!("{name}: knee strike |Δx| ≤ {worst:.2e} (hip rate {worst_hip:.2e}) √(g/l)");
        assert!(
            worst < 1e-10,
            "{name}: knee strike differs from the reference by {worst:e} √(g/l)"
        );
    }
}

// Latches with holding limits (chain walker module docs, "Latches"): the pull a latch must
// hold, and where it lets go, against the reference's explicit multipliers — the lock torque
// `τ` of `[M −Gᵀ; G 0] [θ̈; τ] = [Q − c; 0]` and the impulses `Λ` of the impact systems — on
// Hsu Chen's kneed walker (point feet: the reference with `r = 0`).

/// The kneed preset with its latch's limits (`None`: the ideal latch).
fn kneed_latch(torque: Option<f64>, impulse: Option<f64>) -> ChainWalker {
    let text = pdw_walkers::preset_text("kneed").unwrap();
    let mut spec = WalkerSpec::from_toml(text, "kneed").unwrap();
    spec.knees[0].latch_torque = torque.map(Num::Value);
    spec.knees[0].latch_impulse = impulse.map(Num::Value);
    ChainWalker::from_spec(spec).unwrap()
}

/// The stance knee's lock torque towards flexion along the reference's stride from the
/// section point `s` (every knee straight), every `h`: `(t, τ, x)` in the free mode (up to the
/// knee strike), then in the locked mode (up to the heel strike); the reference's lock torque is
/// its multiplier on `θ̇₁ − θ̇₀ = 0`, positive towards `q₁` increasing (flexion).
fn reference_stance_torques(r: &Reference, s: &[f64], h: f64) -> Vec<(f64, f64, [f64; 8])> {
    let mut out = Vec::new();
    let mut x = [s[0], 0.0, -2.0 * s[0], 0.0, s[1], 0.0, s[2], 0.0];
    let mut t = 0.0;
    // the free mode up to the knee rising through 0 (after it went negative)
    let mut armed = false;
    while t < 5.0 {
        out.push((t, r.dynamics(FREE, &x).lock[0].unwrap(), x));
        let y = rk4(r, FREE, &x, h);
        if armed && y[3] >= 0.0 {
            break;
        }
        armed = y[3] < 0.0;
        x = y;
        t += h;
    }
    out
}

/// Refines the minimum of a sampled function by the parabola through the smallest sample and
/// its two neighbours: `(t, value)`.
fn parabola_min(samples: &[(f64, f64)]) -> (f64, f64) {
    let j = (1..samples.len() - 1)
        .min_by(|&a, &b| samples[a].1.total_cmp(&samples[b].1))
        .unwrap();
    let ((t0, f0), (t1, f1), (_, f2)) = (samples[j - 1], samples[j], samples[j + 1]);
    let h = t1 - t0;
    let (a, b) = ((f0 - 2.0 * f1 + f2) / (2.0 * h * h), (f2 - f0) / (2.0 * h));
    (t1 - b / (2.0 * a), f1 - b * b / (4.0 * a))
}

/// The reference's gait of the kneed walker (its own stride map, Newton to 1e-11) and its
/// stance pull, knee-strike and heel-strike impulses.
struct KneedGait {
    section: [f64; 3],
    x_ks: [f64; 8],
    x_hs: [f64; 8],
    /// The smallest stance lock torque over the free mode (N m-like; negative: a pull).
    min_torque: f64,
    t_min_torque: f64,
    ks: KneeStrike,
    hs: HeelStrike,
}

fn kneed_gait(r: &Reference, w: &ChainWalker) -> KneedGait {
    let (x_ks, x_hs, section, res) = reference_gait(r, &w.gait_guesses()[0].section);
    assert!(res < 1e-10, "reference fixed point residual {res:e}");
    let samples: Vec<(f64, f64)> = reference_stance_torques(r, &section, 1e-4)
        .iter()
        .map(|p| (p.0, p.1))
        .collect();
    let (t_min_torque, min_torque) = parabola_min(&samples);
    KneedGait {
        section,
        x_ks,
        x_hs,
        min_torque,
        t_min_torque,
        ks: r.knee_strike(&x_ks),
        hs: r.heel_strike(&x_hs),
    }
}

/// A latch that holds twice the gait's pulls: validity reports every knee margin as limit −
/// pull with the reference's pulls (the torque on `m g l`, the impulses on `m l √(g l)`, to
/// 1e-7 of the scale), and the gait valid where the reference's own loads say so: every
/// knee's pull within its limit, the stance foot pushed, the striking knee's stop and the new
/// contact pushing, the trailing foot leaving the ground, the swing foot above the slope.
#[test]
fn latch_margins_are_the_limit_minus_the_reference_pull() {
    latch_margins_against_the_reference(&kneed_latch, &|pt, pi, _| (2.0 * pt, 2.0 * pi), true);
}

/// `models/seed5_latched.toml` (the seed's walker with a free swing knee at slope 0.1) with the
/// latch limits replaced by `torque`, `impulse` (`None`: the ideal latch).
fn seed5_latch(torque: Option<f64>, impulse: Option<f64>) -> ChainWalker {
    let text = include_str!("../../models/seed5_latched.toml");
    let mut spec = WalkerSpec::from_toml(text, "seed5_latched").unwrap();
    spec.knees[0].latch_torque = torque.map(Num::Value);
    spec.knees[0].latch_impulse = impulse.map(Num::Value);
    ChainWalker::from_spec(spec).unwrap()
}

/// The seed's walker (Table 3.1) with its smallest latch: the pulls plus 1 % of their scales,
/// as `models/seed5_latched.toml` documents. Every latch margin is the reference's limit − pull
/// and at least 1 %; the gait stays invalid, and the reference says so from its own loads (its
/// swing foot passes below the slope before the knee strike).
#[test]
fn the_seed_walkers_smallest_latch_against_the_reference() {
    latch_margins_against_the_reference(
        &seed5_latch,
        &|pt, pi, sc| (pt + 0.01 * sc.torque, pi + 0.01 * sc.ang),
        false,
    );
}

/// The engine's latch margins and verdict at the reference's gait of the ideal-latch walker
/// `build(None, None)`, with limits `limits(torque pull, impulse pull, scales)`: every knee
/// margin limit − the reference's pull (to 1e-7 of its scale) and the verdict the reference's
/// own loads give (`valid`, which the caller states).
fn latch_margins_against_the_reference(
    build: &dyn Fn(Option<f64>, Option<f64>) -> ChainWalker,
    limits: &dyn Fn(f64, f64, &Scales) -> (f64, f64),
    valid: bool,
) {
    let ideal = build(None, None);
    let r = Reference::new(&ideal);
    let sc = r.scales();
    let g = kneed_gait(&r, &ideal);
    let pull_t = -g.min_torque;
    let pull_i = (-g.ks.stance_knee_impulse)
        .max(-g.hs.trailing_knee_impulse)
        .max(-g.hs.new_stance_knee_impulse);
    eprintln!(
        "kneed gait {:?}: stance pull {pull_t:.9e} at t = {:.6}, knee strike stance knee \
         {:.9e}, heel strike trailing knee {:.9e}, new stance knee {:.9e}",
        g.section,
        g.t_min_torque,
        g.ks.stance_knee_impulse,
        g.hs.trailing_knee_impulse,
        g.hs.new_stance_knee_impulse
    );
    assert!(pull_t > 0.0 && pull_i > 0.0, "the ideal latch pulls");
    let (lt, li) = limits(pull_t, pull_i, &sc);
    let w = build(Some(lt), Some(li));
    let mut x0 = vec![0.0; w.dim()];
    let s4 = [g.section[0], g.section[1], g.section[2], 0.0];
    w.lift(&s4[..w.section_dim()], &mut x0);
    let v = pdw_limit::Validity::along_step(&w, &x0).unwrap();
    let margin = |name: &str| v.margin(name).unwrap_or_else(|| panic!("{name}")).clone();
    let m = margin("stance_knee_torque");
    let e = (m.raw - (lt + g.min_torque)).abs() / sc.torque;
    eprintln!(
        "stance_knee_torque margin {:.9e} (relative {:.3e}), reference {:.9e}: {e:.1e} m g l",
        m.raw,
        m.relative,
        lt + g.min_torque
    );
    assert!(e < 1e-7, "stance latch margin off by {e:e} m g l");
    assert!((m.relative - m.raw / sc.torque).abs() < 1e-12 * m.raw.abs().max(1e-3));
    for (name, pull) in [
        ("knee_strike:stance_knee", g.ks.stance_knee_impulse),
        ("heel_strike:trailing_knee", g.hs.trailing_knee_impulse),
        ("heel_strike:new_stance_knee", g.hs.new_stance_knee_impulse),
    ] {
        let m = margin(name);
        let e = (m.raw - (li + pull)).abs() / sc.ang;
        eprintln!(
            "{name} margin {:.9e}, reference {:.9e}: {e:.1e} m l sqrt(g l)",
            m.raw,
            li + pull
        );
        assert!(e < 1e-7, "{name} margin off by {e:e} m l √(g l)");
        assert!((m.relative - m.raw / sc.ang).abs() < 1e-12);
    }
    // the reference's verdict, from its own loads along its own stride: the free swing, then
    // the locked swing from its knee strike to the swing foot's return to the slope
    let h = 1e-3;
    let mut pts: Vec<(usize, [f64; 8])> = reference_stance_torques(&r, &g.section, h)
        .iter()
        .map(|p| (FREE, p.2))
        .collect();
    let mut x = g.ks.x_post;
    loop {
        pts.push((LOCKED, x));
        x = rk4(&r, LOCKED, &x, h);
        let th = angles(&x[..4]);
        let p = r.position(&r.swing_arc, [0.0; 2], &th);
        if p[0] > 0.0 && p[1] <= 0.0 {
            break;
        }
    }
    let normal_ok = pts.iter().all(|(m, x)| r.dynamics(*m, x).ground[1] > 0.0);
    let clear_ok = pts.iter().skip(1).all(|(_, x)| {
        let th = angles(&x[..4]);
        r.position(&r.swing_arc, [0.0; 2], &th)[1] > 0.0
    });
    let knees_ok = pts.iter().all(|(m, x)| {
        let lock = r.dynamics(*m, x).lock;
        // towards flexion: the stance knee's multiplier, the swing knee's negated
        lock[0].unwrap() + lt > 0.0 && lock[1].is_none_or(|t| -t + lt > 0.0)
    });
    let locked_min = pts
        .iter()
        .filter(|(m, _)| *m == LOCKED)
        .map(|(_, x)| r.dynamics(LOCKED, x).lock[0].unwrap())
        .fold(f64::INFINITY, f64::min);
    assert!(
        locked_min > g.min_torque,
        "the stance pull peaks in the free swing"
    );
    let ref_valid = normal_ok
        && clear_ok
        && knees_ok
        && lt + g.min_torque > 0.0
        && li + g.ks.stance_knee_impulse > 0.0
        && li + g.hs.trailing_knee_impulse > 0.0
        && li + g.hs.new_stance_knee_impulse > 0.0
        && g.ks.swing_knee_impulse > 0.0
        && g.hs.contact_impulse[1] > 0.0
        && g.hs.trailing_foot_velocity[1] > 0.0;
    eprintln!(
        "engine: valid {}, binding {:?}; reference valid {ref_valid}",
        v.valid(),
        v.binding()
    );
    assert_eq!(
        v.valid(),
        ref_valid,
        "engine and reference verdicts differ: {:?}",
        v.failures()
    );
    assert_eq!(ref_valid, valid, "the reference's verdict");
    // the ideal latch is flagged where it pulls (margin = the torque itself)
    let mut x3 = vec![0.0; ideal.dim()];
    ideal.lift(&g.section, &mut x3);
    let vi = pdw_limit::Validity::along_step(&ideal, &x3).unwrap();
    assert!(!vi.valid() && vi.knee_unlocks);
    let e = (vi.margin("stance_knee_torque").unwrap().raw - g.min_torque).abs() / sc.torque;
    assert!(e < 1e-7, "ideal latch torque off by {e:e}");
}

/// Limits above every pull of the gait change no bit of the stride map (its first three
/// coordinates; the released knee's rate is exactly 0) nor the gait Newton finds, and the
/// multipliers are the ideal latch's and a 0 (the held trailing knee's rate is set to 0).
#[test]
fn limits_above_the_peak_pull_leave_the_ideal_latchs_gait_bit_for_bit() {
    let ideal = kneed_latch(None, None);
    let r = Reference::new(&ideal);
    let g = kneed_gait(&r, &ideal);
    let pull_i = (-g.ks.stance_knee_impulse).max(-g.hs.trailing_knee_impulse);
    let w = kneed_latch(Some(-2.0 * g.min_torque), Some(2.0 * pull_i));
    assert_eq!(w.section_dim(), 4);
    let opts = Options::dop853(1e-12);
    let (mi, ml) = (
        pdw_limit::StrideMap::new(&ideal as &dyn Walker, opts).unwrap(),
        pdw_limit::StrideMap::new(&w as &dyn Walker, opts).unwrap(),
    );
    for ds in [0.0, 1e-3, -2e-3] {
        let s = [
            g.section[0] + ds,
            g.section[1] - ds,
            g.section[2] + 0.5 * ds,
        ];
        let (pi, pl) = (
            mi.stride(&s).unwrap(),
            ml.stride(&[s[0], s[1], s[2], 0.0]).unwrap(),
        );
        assert!(
            pi.outcome.is_ok() && pl.outcome.is_ok(),
            "{:?} {:?}",
            pi.outcome,
            pl.outcome
        );
        for k in 0..3 {
            assert_eq!(
                pi.next[k].to_bits(),
                pl.next[k].to_bits(),
                "P(s)[{k}] at ds = {ds}"
            );
        }
        assert_eq!(pl.next[3], 0.0);
        assert_eq!(pi.period.to_bits(), pl.period.to_bits());
    }
    let nopts = pdw_limit::NewtonOptions {
        tol: 1e-12,
        ..pdw_limit::NewtonOptions::default()
    };
    let fi = pdw_limit::find_fixed_point(&mi, &g.section, &nopts).unwrap();
    let pl = ml
        .stride(&[fi.section[0], fi.section[1], fi.section[2], 0.0])
        .unwrap();
    for k in 0..3 {
        assert_eq!(
            pl.next[k].to_bits(),
            mi.apply(&fi.section).unwrap()[k].to_bits()
        );
    }
    let (_, dp) =
        pdw_limit::dp_variational(&ml, &[fi.section[0], fi.section[1], fi.section[2], 0.0])
            .unwrap();
    let mut lam: Vec<f64> = pdw_limit::multipliers(&dp, 4)
        .unwrap()
        .iter()
        .map(|l| l.re.hypot(l.im))
        .collect();
    lam.sort_by(|a, b| b.total_cmp(a));
    let mut lam_i: Vec<f64> = fi.multipliers.iter().map(|l| l.re.hypot(l.im)).collect();
    lam_i.sort_by(|a, b| b.total_cmp(a));
    eprintln!("|λ| ideal {lam_i:?}, limited {lam:?}");
    for k in 0..3 {
        assert!(
            (lam[k] - lam_i[k]).abs() < 1e-9,
            "|λ{k}| {} vs {}",
            lam[k],
            lam_i[k]
        );
    }
    assert!(lam[3].abs() < 1e-12);
}

/// A torque limit 10 % below the gait's stance pull: the stride ends where the reference's
/// pull crosses the limit (its RK4 at 1e-4 s, crossing bisected: to 1e-8 s) in the fall "stance
/// knee buckled" (`stance_latch_releases`), not in a flagged heel strike.
#[test]
fn a_torque_limit_below_the_pull_releases_the_stance_knee_where_the_reference_crosses_it() {
    let ideal = kneed_latch(None, None);
    let r = Reference::new(&ideal);
    let g = kneed_gait(&r, &ideal);
    let lt = -0.9 * g.min_torque;
    let w = kneed_latch(Some(lt), None);
    // the reference: the first step where τ + L < 0, bisected
    let h = 1e-4;
    let samples = reference_stance_torques(&r, &g.section, h);
    let j = samples
        .iter()
        .position(|p| p.1 + lt < 0.0)
        .expect("the pull crosses");
    let (t0, _, x0) = samples[j - 1];
    let (mut lo, mut hi) = (0.0, h);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if r.dynamics(FREE, &rk4(&r, FREE, &x0, mid)).lock[0].unwrap() + lt < 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let t_ref = t0 + hi;
    let map = pdw_limit::StrideMap::new(&w as &dyn Walker, Options::dop853(1e-12)).unwrap();
    let st = map.stride(&g.section).unwrap();
    eprintln!(
        "release: engine {:?} at {:.12}, reference {t_ref:.12}",
        st.outcome, st.period
    );
    match st.outcome {
        pdw_limit::StrideOutcome::Fall { kind, guard } => {
            assert_eq!(kind, pdw_hybrid::FallKind::KneeBuckled);
            assert_eq!(w.guards(FREE)[guard].name, "stance_latch_releases");
        }
        o => panic!("the stance latch must let go: {o:?}"),
    }
    assert!(
        (st.period - t_ref).abs() < 1e-8,
        "release at {} vs {t_ref}",
        st.period
    );
    // 10 % above the pull it holds: the stride reaches the heel strike
    let w = kneed_latch(Some(-1.1 * g.min_torque), None);
    let map = pdw_limit::StrideMap::new(&w as &dyn Walker, Options::dop853(1e-12)).unwrap();
    assert!(map.stride(&g.section).unwrap().outcome.is_ok());
}

/// The locked swing knee's latch lets go where the reference's swing lock torque crosses the
/// limit, and the walker goes on with the swing knee free: from random locked states whose
/// swing knee comes to pull, the engine's event time matches the reference's crossing (1e-8 s),
/// the mode after it is the free mode, and 0.05 s later the engine's state equals the
/// reference's free-mode flow from its crossing (1e-8), the knee flexed.
#[test]
fn a_swing_latch_below_its_pull_lets_the_swing_knee_swing_free() {
    let probe = kneed_latch(Some(1.0), None);
    let r = Reference::new(&probe);
    let sc = r.scales();
    let mut rng = Rng(29);
    let h = 1e-4;
    let swing_flex = |x: &[f64; 8]| -r.dynamics(LOCKED, x).lock[1].unwrap();
    let mut checked = 0;
    for _ in 0..400 {
        if checked == 3 {
            break;
        }
        let x0 = random_state(&mut rng, LOCKED, sc.rate);
        // the reference over 0.3 s (or until the swing foot reaches the slope)
        let (mut x, mut tau) = (x0, vec![(0.0, swing_flex(&x0), x0)]);
        for i in 1..=3000 {
            x = rk4(&r, LOCKED, &x, h);
            let th = angles(&x[..4]);
            if r.position(&r.swing_arc, [0.0; 2], &th)[1] <= 0.0 || x[0].abs() > 1.2 {
                break;
            }
            tau.push((i as f64 * h, swing_flex(&x), x));
        }
        let tmin = tau.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        if !(tmin < 0.0 && tau[0].1 + tmin > 0.0) {
            continue;
        }
        let lt = -0.5 * tmin;
        let w = kneed_latch(Some(lt), None);
        let j = tau.iter().position(|p| p.1 + lt < 0.0).unwrap();
        let (t0, _, xa) = tau[j - 1];
        let (mut lo, mut hi) = (0.0, h);
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if swing_flex(&rk4(&r, LOCKED, &xa, mid)) + lt < 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let t_ref = t0 + hi;
        let x_ref = rk4(&r, LOCKED, &xa, hi);
        // the engine from x0 in the locked mode
        let mut integ = pdw_hybrid::Integrator::new(8, Options::dop853(1e-12)).unwrap();
        let (mut t, mut xe) = (0.0, x0.to_vec());
        let stop = integ.integrate(&w, LOCKED, &mut t, &mut xe, 0.3);
        let pdw_hybrid::StopReason::Guard { guard } = stop else {
            continue;
        };
        if w.guards(LOCKED)[guard].name != "swing_latch_releases" {
            continue;
        }
        assert!(
            (t - t_ref).abs() < 1e-8,
            "release at {t} vs reference {t_ref}"
        );
        let mut ws = Scratch::new();
        let mut xp = vec![0.0; 8];
        assert_eq!(w.reset(&mut ws, LOCKED, guard, &xe, &mut xp), FREE);
        let t_end = t + 0.05;
        let mut integ = pdw_hybrid::Integrator::new(8, Options::dop853(1e-12)).unwrap();
        let stop = integ.integrate(&w, FREE, &mut t, &mut xp, t_end);
        if !matches!(stop, pdw_hybrid::StopReason::EndTime) {
            // another event within 0.05 s of the release (a knee strike, a fall): not this check
            continue;
        }
        let mut xr = x_ref;
        for _ in 0..500 {
            xr = rk4(&r, FREE, &xr, 1e-4);
        }
        let e = max_abs_diff(&xp[..4], &xr[..4]).max(max_abs_diff(&xp[4..], &xr[4..]) / sc.rate);
        eprintln!("swing release at {t_ref:.9} (limit {lt:.4e}): free flow after 0.05 s differs by {e:.1e}; knee {:.4}", xp[3]);
        assert!(e < 1e-8, "free flow after the release differs by {e:e}");
        assert!(xp[3] < 0.0, "the released swing knee flexes: {}", xp[3]);
        checked += 1;
    }
    assert_eq!(checked, 3, "three releases checked");
}

/// An impulse limit below the heel strike's trailing pull: the model's heel strike releases
/// the trailing knee and equals the reference's impact without that knee's row (1e-10), the
/// new swing knee leaving flexing; the engine's post-impact state conserves, by the
/// reference's sums, the walker's angular momentum about the new contact point, the trailing
/// leg's about the hip and the trailing shank's about the released knee. At the knee strike a
/// limit below the stance knee's pull buckles the stance leg (the twin guard), one above holds.
#[test]
fn an_impulse_limit_below_the_pull_releases_the_knee_as_the_reference_impact() {
    let ideal = kneed_latch(None, None);
    let r = Reference::new(&ideal);
    let sc = r.scales();
    let g = kneed_gait(&r, &ideal);
    let pull = -g.hs.trailing_knee_impulse;
    let w = kneed_latch(None, Some(0.5 * pull));
    assert!(w.trailing_knee_releases_at(&g.x_hs));
    let mut ws = Scratch::new();
    let mut out = [0.0; 8];
    assert_eq!(w.reset(&mut ws, LOCKED, 0, &g.x_hs, &mut out), FREE);
    let hu = r.heel_strike_rows(&g.x_hs, false);
    let e = max_abs_diff(&out[..4], &hu.x_post[..4])
        .max(max_abs_diff(&out[4..], &hu.x_post[4..]) / sc.rate);
    eprintln!(
        "released heel strike: new swing knee rate {:.9} (reference {:.9}), |Δx| {e:.1e}",
        out[7], hu.x_post[7]
    );
    assert!(e < 1e-10, "released heel strike differs by {e:e}");
    assert!(
        out[7] < -1e-3 * sc.rate,
        "the new swing knee flexes: {}",
        out[7]
    );
    // momenta: before, rooted at the old stance foot (at the origin, at rest); after, rooted at
    // the new stance foot (the old swing foot, at rest): the same points in space
    let (th, thd) = (angles(&g.x_hs[..4]), angles(&g.x_hs[4..]));
    let o = r.position(&r.swing_arc, [0.0; 2], &th);
    let (th2, thd2) = (angles(&out[..4]), angles(&out[4..]));
    let a2 = o;
    let hip = r.position(&r.hip, [0.0; 2], &th);
    // the trailing (old stance) knee: the top of the old stance shank
    let knee_pt = Point {
        alpha: [r.hip.alpha[0], 0.0, 0.0, 0.0],
        beta: [0.0; 4],
    };
    let knee = r.position(&knee_pt, [0.0; 2], &th);
    // old body i is new body 4 − i
    let before = |b: &[usize], p: [f64; 2]| r.angular_momentum(b, p, [0.0; 2], [0.0; 2], &th, &thd);
    let after = |b: &[usize], p: [f64; 2]| r.angular_momentum(b, p, a2, [0.0; 2], &th2, &thd2);
    let hip2 = r.position(&r.hip, a2, &th2);
    assert!(
        max_abs_diff(&hip, &hip2) < 1e-12,
        "the hip is the same point"
    );
    for (what, b_old, b_new, p) in [
        (
            "walker about the new contact",
            &[0, 1, 2, 3, 4][..],
            &[0, 1, 2, 3, 4][..],
            o,
        ),
        ("trailing leg about the hip", &[0, 1][..], &[3, 4][..], hip),
        ("trailing shank about its knee", &[0][..], &[4][..], knee),
    ] {
        let (l0, l1) = (before(b_old, p), after(b_new, p));
        let e = (l1 - l0).abs() / sc.ang;
        eprintln!("{what}: {l0:.12e} -> {l1:.12e} ({e:.1e} m l sqrt(g l))");
        assert!(e < 1e-11, "{what} not conserved: {e:e}");
    }
    // knee strike: buckles exactly where the reference's stance knee pulls beyond the limit
    let pk = -g.ks.stance_knee_impulse;
    for (f, buckles) in [(0.5, true), (2.0, false)] {
        let w = kneed_latch(None, Some(f * pk));
        assert_eq!(
            w.stance_knee_buckles(FREE, &g.x_ks),
            buckles,
            "limit {f} x the pull"
        );
        let twin = w
            .guards(FREE)
            .iter()
            .position(|s| s.name == "knee_strike_buckles")
            .unwrap();
        assert_eq!(w.admissible(FREE, twin, &g.x_ks), buckles);
        assert_eq!(w.admissible(FREE, 0, &g.x_ks), !buckles);
    }
}

/// Bad knee hardware is a clear error naming the field: a negative limit, a limit on a stop,
/// an unknown hold, a limited latch on a knee locked all step.
#[test]
fn bad_latch_hardware_is_a_clear_error() {
    let text = pdw_walkers::preset_text("kneed").unwrap();
    let base = WalkerSpec::from_toml(text, "kneed").unwrap();
    let err = |f: &dyn Fn(&mut WalkerSpec)| {
        let mut s = base.clone();
        f(&mut s);
        ChainWalker::from_spec(s).unwrap_err().to_string()
    };
    let e = err(&|s| s.knees[0].latch_torque = Some(Num::Value(-1.0)));
    assert!(
        e.contains("knees[0].latch_torque") && e.contains(">= 0"),
        "{e}"
    );
    let e = err(&|s| s.knees[0].latch_impulse = Some(Num::Value(-1e-3)));
    assert!(
        e.contains("knees[0].latch_impulse") && e.contains(">= 0"),
        "{e}"
    );
    let e = err(&|s| {
        s.knees[0].hold = Some("stop".into());
        s.knees[0].latch_torque = Some(Num::Value(1.0));
    });
    assert!(
        e.contains("knees[0].latch_torque") && e.contains("hold = \"latch\""),
        "{e}"
    );
    let e = err(&|s| s.knees[0].hold = Some("magnet".into()));
    assert!(
        e.contains("knees[0].hold") && e.contains("\"magnet\""),
        "{e}"
    );
    let e = err(&|s| {
        s.knees[0].mode = "locked".into();
        s.knees[0].latch_impulse = Some(Num::Value(1.0));
    });
    assert!(e.contains("free-swing"), "{e}");
    let e = err(&|s| s.knees[0].latch_torque = Some(Num::Expr("nope".into())));
    assert!(e.contains("unknown parameter `nope`"), "{e}");
    // limits as parameters: `--set` addresses them like any other
    let toml = text.replace(
        "hold = \"latch\"",
        "hold = \"latch\"\nlatch_torque = \"lt\"\nlatch_impulse = \"li\"",
    ).replace(
        "[parameters]",
        "[parameters]\nlt = { value = 0.2, unit = \"M L^2/T^2\" }\nli = { value = 0.005, unit = \"M L^2/T\" }",
    );
    let spec = WalkerSpec::from_toml(&toml, "kneed_latched").unwrap();
    let mut t = spec.param_table();
    let i = t.names.iter().position(|n| n == "lt").unwrap();
    t.values[i] = 0.3;
    let w = ChainWalker::new(spec, &t.values).unwrap();
    assert_eq!(w.latch_limits(), (Some(0.3), Some(0.005)));
}
