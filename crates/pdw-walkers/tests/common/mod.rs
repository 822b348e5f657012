//! An independent reference for chain walkers made of point masses: positions, velocities,
//! energies, angular momenta and the equations of motion from d'Alembert's principle, written
//! from the point-mass kinematics (no kernel, no composite links).
//!
//! Slope frame as the walkers': `y` downhill, `z` along the slope normal, up; a unit vector
//! `u(φ) = (−sin φ, cos φ)` at absolute angle `φ` from the slope normal; gravity
//! `g (sin γ, −cos γ)`. Joint angles `q₀ … q_{n−1}`; link `k` has absolute angle
//! `φ_k = q₀ + … + q_k`. A point is `Σ_k c_k u(φ_k)` (its terms `(c_k, k)`).

#![allow(dead_code)]

pub type Pm = Vec<(f64, [f64; 2], [f64; 2])>;

/// Point masses on a planar chain of `n` joints rooted at the stance foot.
pub struct PointChain {
    /// joints
    pub n: usize,
    /// `(mass, terms)`
    pub masses: Vec<(f64, Vec<(f64, usize)>)>,
    pub gravity: f64,
    pub slope: f64,
}

impl PointChain {
    /// Absolute link angles and rates at state `x = (q, q̇)`.
    pub fn angles(&self, x: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let n = self.n;
        let mut phi = vec![0.0; n];
        let mut phid = vec![0.0; n];
        let (mut a, mut b) = (0.0, 0.0);
        for k in 0..n {
            a += x[k];
            b += x[n + k];
            phi[k] = a;
            phid[k] = b;
        }
        (phi, phid)
    }

    /// Position and velocity of the point with `terms`, the stance foot moving with `vb`.
    pub fn point(&self, terms: &[(f64, usize)], x: &[f64], vb: [f64; 2]) -> ([f64; 2], [f64; 2]) {
        let (phi, phid) = self.angles(x);
        let mut r = [0.0; 2];
        let mut v = vb;
        for &(c, k) in terms {
            let (s, co) = phi[k].sin_cos();
            r[0] -= c * s;
            r[1] += c * co;
            v[0] -= c * phid[k] * co;
            v[1] -= c * phid[k] * s;
        }
        (r, v)
    }

    /// `(m, r, v)` of every mass at `x`, the stance foot moving with `vb`.
    pub fn masses(&self, x: &[f64], vb: [f64; 2]) -> Pm {
        self.masses
            .iter()
            .map(|(m, t)| {
                let (r, v) = self.point(t, x, vb);
                (*m, r, v)
            })
            .collect()
    }

    /// Potential energy, zero at the stance foot.
    pub fn potential(&self, x: &[f64]) -> f64 {
        let g = [
            self.gravity * self.slope.sin(),
            -self.gravity * self.slope.cos(),
        ];
        self.masses(x, [0.0; 2])
            .iter()
            .map(|(m, r, _)| -m * (g[0] * r[0] + g[1] * r[1]))
            .sum()
    }

    /// Joint accelerations with the joints `free` moving and every other joint held (its
    /// acceleration 0), by d'Alembert's principle on the point masses: with `φ = A q_free + c`,
    /// `Aᵀ M_φ A q̈_free = Aᵀ (Q_φ − h_φ)`, `M_φ,kl = Σ m c_k c_l cos(φ_k − φ_l)`,
    /// `h_φ,k = Σ_l Σ m c_k c_l sin(φ_k − φ_l) φ̇_l²`, `Q_φ,k = Σ m c_k u′(φ_k)·g`.
    pub fn accel(&self, x: &[f64], free: &[usize]) -> Vec<f64> {
        let n = self.n;
        let (phi, phid) = self.angles(x);
        let g = [
            self.gravity * self.slope.sin(),
            -self.gravity * self.slope.cos(),
        ];
        let mut mphi = vec![vec![0.0; n]; n];
        let mut rhs = vec![0.0; n];
        for (m, terms) in &self.masses {
            for &(ck, k) in terms {
                let du = [-phi[k].cos(), -phi[k].sin()];
                rhs[k] += m * ck * (du[0] * g[0] + du[1] * g[1]);
                for &(cl, l) in terms {
                    mphi[k][l] += m * ck * cl * (phi[k] - phi[l]).cos();
                    rhs[k] -= m * ck * cl * (phi[k] - phi[l]).sin() * phid[l] * phid[l];
                }
            }
        }
        // A: ∂φ_k/∂q_j = 1 for j ≤ k, so (AᵀM_φA)_ij = Σ_{k ≥ free_i, l ≥ free_j} M_φ,kl
        let f = free.len();
        let mut mq = vec![vec![0.0; f]; f];
        let mut bq = vec![0.0; f];
        for (i, &fi) in free.iter().enumerate() {
            bq[i] = rhs[fi..].iter().sum();
            for (j, &fj) in free.iter().enumerate() {
                mq[i][j] = mphi[fi..]
                    .iter()
                    .map(|row| row[fj..].iter().sum::<f64>())
                    .sum();
            }
        }
        let sol = solve(mq, bq);
        let mut qdd = vec![0.0; n];
        for (j, &fj) in free.iter().enumerate() {
            qdd[fj] = sol[j];
        }
        qdd
    }
}

/// Gaussian elimination with partial pivoting.
pub fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap();
        a.swap(c, p);
        b.swap(c, p);
        let pivot = a[c].clone();
        for r in c + 1..n {
            let f = a[r][c] / pivot[c];
            for (ark, pk) in a[r][c..].iter_mut().zip(&pivot[c..]) {
                *ark -= f * pk;
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x
}

pub fn ang_mom(pm: &[(f64, [f64; 2], [f64; 2])], c: [f64; 2]) -> f64 {
    pm.iter()
        .map(|(m, r, v)| m * ((r[0] - c[0]) * v[1] - (r[1] - c[1]) * v[0]))
        .sum()
}

pub fn kinetic(pm: &[(f64, [f64; 2], [f64; 2])]) -> f64 {
    pm.iter()
        .map(|(m, _, v)| 0.5 * m * (v[0] * v[0] + v[1] * v[1]))
        .sum()
}

/// A parameter's value from a walker's `param_values()`.
pub fn param(values: &[(String, f64)], name: &str) -> f64 {
    values
        .iter()
        .find(|p| p.0 == name)
        .map(|p| p.1)
        .unwrap_or_else(|| panic!("no parameter {name}"))
}

/// The chain walker's flow against this point-mass reference at 200 seeded states of a
/// two-segment walker in `mode` (`free`: its moving joints): knee angles straight or (every other
/// state) the stance knee held bent, a bent free swing knee; the stance, hip and free-knee rates
/// drawn up to `rates`. Free accelerations agree to 1e-12, held joints get exactly 0.
pub fn check_flow_against_point_masses(
    w: &pdw_walkers::ChainWalker,
    pc: &PointChain,
    mode: usize,
    free: &[usize],
    seed: u64,
    rates: [f64; 3],
) {
    let [stance_rate, hip_rate, knee_rate] = rates;
    use pdw_hybrid::HybridSystem;
    use rand::{Rng, SeedableRng};
    let mut ws = pdw_hybrid::Scratch::new();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let swing_free = free.contains(&3);
    for i in 0..200 {
        let stance_knee = if i % 2 == 0 {
            0.0
        } else {
            rng.random_range(0.0..0.4)
        };
        let x = [
            rng.random_range(-0.6..0.6),
            stance_knee,
            rng.random_range(-1.2..1.2),
            if swing_free {
                rng.random_range(-1.0..0.0)
            } else {
                0.0
            },
            rng.random_range(-stance_rate..stance_rate),
            0.0,
            rng.random_range(-hip_rate..hip_rate),
            if swing_free {
                rng.random_range(-knee_rate..knee_rate)
            } else {
                0.0
            },
        ];
        let mut dx = [0.0; 8];
        w.flow(&mut ws, mode, &x, &mut dx);
        let qdd = pc.accel(&x, free);
        let scale = 1.0 + qdd.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        for j in 0..4 {
            assert_eq!(dx[j], x[4 + j]);
            if free.contains(&j) {
                assert!(
                    (dx[4 + j] - qdd[j]).abs() < 1e-12 * scale,
                    "mode {mode}, q̈{j}: {} vs point masses {}",
                    dx[4 + j],
                    qdd[j]
                );
            } else {
                assert_eq!(dx[4 + j], 0.0, "held joint {j} in mode {mode}");
            }
        }
    }
}
