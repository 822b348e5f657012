//! The resets and their exact Jacobians (chain walker docs, "Resets", "Impacts"): the knee strike's
//! plastic lock of the free knee, the heel strike's impact at the swing foot followed by the leg
//! swap (seed eq. 3.29–3.32), and their derivatives by dual numbers through the kernel.

use super::guards::LatchGuard;
use super::{ChainWalker, DMAX, FMAX, FREE, LOCKED, MAX_SEGMENTS};
use pdw_hybrid::{Scratch, Section};

impl ChainWalker {
    /// The knee strike's reset at the pre-impact state `x` into `out`: the free knee `knee`
    /// locked plastically with the stance foot's contact point at rest and the other knees held
    /// (point feet: [`pdw_soa::joint_lock_impact`]; round feet: the floating chain's impact
    /// problem), the knee angle and the locked rates set to exactly 0. Returns the mode after
    /// it: the locked mode, or the free mode again where a swing latch must at once pull more
    /// than it holds.
    pub(super) fn knee_strike_reset(
        &self,
        ws: &mut Scratch,
        knee: usize,
        x: &[f64],
        out: &mut [f64],
    ) -> usize {
        let n = self.n;
        let s = self.scratch(ws);
        let locked = &self.locked[LOCKED];
        let ok = if self.radius > 0.0 {
            // the stance foot rolls: its contact point, not the arc centre, is at rest
            // after the impact (the floating chain's impact problem, every knee held)
            let mut v = [0.0; FMAX];
            let ok = self.impact_map(FREE, x, &mut v, None).is_ok();
            s.v[..n].copy_from_slice(&v[2..n + 2]);
            ok
        } else {
            pdw_soa::joint_lock_impact(
                &self.chain,
                &mut s.ws,
                &x[..n],
                &x[n..2 * n],
                locked,
                &mut s.v[..n],
                &mut s.imp[..locked.len()],
            )
            .is_ok()
        };
        out[..n].copy_from_slice(&x[..n]);
        out[knee] = 0.0;
        if ok {
            out[n..2 * n].copy_from_slice(&s.v[..n]);
            for &j in locked {
                out[n + j] = 0.0;
            }
        } else {
            out[n..2 * n].fill(f64::NAN);
        }
        // a swing latch that must pull more than it holds right after catching the knee
        // lets go at once: no crossing of its guard would show it
        if ok
            && self.latch_torque.is_some()
            && self.latch_guard_value(ws, LOCKED, &out[..2 * n], LatchGuard::Swing) < 0.0
        {
            return FREE;
        }
        LOCKED
    }

    /// The heel strike's reset at the pre-impact state `x` into `out`: the impact at the swing
    /// foot (every knee held, or the trailing free knee released where the model releases it,
    /// [`ChainWalker::trailing_knee_releases_at`]), then the leg swap; the held knees' rates
    /// set to exactly 0. Returns the section's mode.
    pub(super) fn heel_strike_reset(&self, ws: &mut Scratch, x: &[f64], out: &mut [f64]) -> usize {
        let n = self.n;
        let mut v = [0.0; FMAX];
        if self.trailing_knee_releases_at(x) {
            // the mode change: the trailing free knee leaves the impact flexing, every other
            // knee held (their rates exactly 0 in the new mode)
            if self
                .impact_map(self.locked_mode(), x, &mut v[..n + 2], None)
                .is_err()
            {
                v.fill(f64::NAN);
            }
            self.swap(&x[..n], &v[2..n + 2], out);
            for &j in &self.locked[self.section_mode()] {
                out[n + j] = 0.0;
            }
            return self.section_mode();
        }
        self.heel_strike(ws, x, &mut v[..n + 2]);
        self.swap(&x[..n], &v[2..n + 2], out);
        if self.trailing_free.is_some() {
            // every knee held: their rates exactly 0 (the section's swing_knee_rate is 0)
            for k in (1..self.m).chain(self.m + 1..n) {
                out[n + k] = 0.0;
            }
        }
        self.section_mode()
    }

    /// Jacobian of [`ChainWalker::knee_strike_reset`] into `jac` (`2n × 2n`, row-major, zeroed
    /// by the caller): the identity on the angles but the locked knee's, the impact map's
    /// derivatives ([`pdw_soa::joint_lock_impact_derivatives`], or the floating chain's for
    /// round feet) on the rates of the joints left free, zero rows for the locked rates.
    pub(super) fn knee_strike_jacobian(
        &self,
        ws: &mut Scratch,
        knee: usize,
        x: &[f64],
        jac: &mut [f64],
    ) {
        let (n, d) = (self.n, 2 * self.n);
        let s = self.scratch(ws);
        let locked = &self.locked[LOCKED];
        let mut jl = [0.0; DMAX * DMAX / 2];
        let ok = if self.radius > 0.0 {
            self.rolling_knee_strike_jacobian(x, &mut jl)
        } else {
            pdw_soa::joint_lock_impact_derivatives(
                &self.chain,
                &x[..n],
                &x[n..d],
                locked,
                &mut s.v[..n],
                &mut jl[..n * d],
            )
            .is_ok()
        };
        for i in 0..n {
            if i != knee {
                jac[i * d + i] = 1.0;
            }
            if locked.contains(&i) {
                continue;
            }
            for j in 0..d {
                jac[(n + i) * d + j] = if ok { jl[i * d + j] } else { f64::NAN };
            }
        }
    }

    /// The round-footed knee strike's rate Jacobian `∂q̇⁺/∂(q, q̇⁻)` into `jl` (`n × 2n`,
    /// row-major): the floating chain's impact Jacobian, with `q̇⁻_F = (−r q̇₀, 0, q̇)` by the
    /// chain rule (the map does not depend on the base position: translation invariance).
    /// `false` where the impact has no solution.
    fn rolling_knee_strike_jacobian(&self, x: &[f64], jl: &mut [f64]) -> bool {
        let (n, d) = (self.n, 2 * self.n);
        let f = n + 2;
        let mut v = [0.0; FMAX];
        let mut jf = [0.0; FMAX * 2 * FMAX];
        let ok = self
            .impact_map(FREE, x, &mut v, Some(&mut jf[..f * 2 * f]))
            .is_ok();
        for i in 0..n {
            let row = (2 + i) * 2 * f;
            for j in 0..n {
                jl[i * d + j] = jf[row + 2 + j];
                jl[i * d + n + j] = jf[row + f + 2 + j];
            }
            jl[i * d + n] += -self.radius * jf[row + f];
        }
        ok
    }

    /// Jacobian of [`ChainWalker::heel_strike_reset`] into `jac` (`2n × 2n`, row-major, zeroed
    /// by the caller): the floating chain's impact Jacobian composed with the leg swap's matrix,
    /// zero rows for the rates the reset sets to exactly 0.
    pub(super) fn heel_strike_jacobian(&self, ws: &mut Scratch, x: &[f64], jac: &mut [f64]) {
        let (n, d) = (self.n, 2 * self.n);
        let mut jf = [0.0; FMAX * 2 * FMAX];
        let released = self.trailing_knee_releases_at(x);
        let ok = self.heel_impact_jacobian(ws, x, released, &mut jf);
        self.swapped_impact_jacobian(&jf, ok, jac);
        // the held knees' rates are set to exactly 0 by the reset
        if released {
            for &j in &self.locked[self.section_mode()] {
                jac[(n + j) * d..(n + j + 1) * d].fill(0.0);
            }
        } else if self.trailing_free.is_some() {
            for k in (1..self.m).chain(self.m + 1..n) {
                jac[(n + k) * d..(n + k + 1) * d].fill(0.0);
            }
        }
    }

    /// The heel strike's floating-chain Jacobian `[∂q̇_F⁺/∂q_F | ∂q̇_F⁺/∂q̇_F⁻]` into `jf`
    /// (`(n + 2) × 2(n + 2)`, row-major) at the pre-impact state `x`: the model's impact map
    /// with the trailing free knee released (`released`), else the kernel's
    /// [`pdw_soa::contact_impact`] (round feet) or [`pdw_soa::tip_impact_derivatives`]; for round
    /// feet the chain rule through the rolling base rate `ẏ = −r q̇₀`. `false` where the impact
    /// has no solution.
    fn heel_impact_jacobian(
        &self,
        ws: &mut Scratch,
        x: &[f64],
        released: bool,
        jf: &mut [f64],
    ) -> bool {
        let (n, d) = (self.n, 2 * self.n);
        let s = self.scratch(ws);
        let f = n + 2;
        s.q[..2].fill(0.0);
        s.qd[..2].fill(0.0);
        s.q[2..f].copy_from_slice(&x[..n]);
        s.qd[2..f].copy_from_slice(&x[n..d]);
        let ok = if released {
            let mut v = [0.0; FMAX];
            self.impact_map(
                self.locked_mode(),
                x,
                &mut v[..f],
                Some(&mut jf[..f * 2 * f]),
            )
            .is_ok()
        } else if self.radius > 0.0 {
            s.qd[0] = -self.radius * x[n];
            pdw_soa::contact_impact(
                &self.floating,
                &s.q[..f],
                &s.qd[..f],
                self.landing_offset(),
                &self.floating_knees,
                &mut s.v[..f],
                Some(&mut jf[..f * 2 * f]),
            )
            .is_ok()
        } else {
            pdw_soa::tip_impact_derivatives(
                &self.floating,
                &s.q[..f],
                &s.qd[..f],
                &self.floating_knees,
                &mut s.v[..f],
                &mut jf[..f * 2 * f],
            )
            .is_ok()
        };
        // q̇⁻_F = (−r q̇₀, 0, q̇): the chain rule through the rolling base rate
        if self.radius > 0.0 {
            for row in 0..f {
                jf[row * 2 * f + f + 2] += -self.radius * jf[row * 2 * f + f];
            }
        }
        ok
    }

    /// The leg swap composed with the floating-chain impact Jacobian `jf`
    /// ([`ChainWalker::heel_impact_jacobian`]) into `jac`: `∂q'/∂q = S`, and
    /// `∂q̇'/∂(q, q̇) = S ∂v/∂(q, q̇)` with `v` the floating rates `2..` after the impact
    /// (NaN where the impact failed, `ok` false).
    fn swapped_impact_jacobian(&self, jf: &[f64], ok: bool, jac: &mut [f64]) {
        let (n, d) = (self.n, 2 * self.n);
        let f = n + 2;
        let mut sm = [0.0; 4 * MAX_SEGMENTS * MAX_SEGMENTS];
        self.swap_matrix(&mut sm[..n * n]);
        for i in 0..n {
            for j in 0..n {
                // q' = S q
                jac[i * d + j] = sm[i * n + j];
                // q̇' = S v(q, q̇), v = floating rates 2.. of the impact
                let (mut a, mut b) = (0.0, 0.0);
                for l in 0..n {
                    a += sm[i * n + l] * jf[(2 + l) * 2 * f + 2 + j];
                    b += sm[i * n + l] * jf[(2 + l) * 2 * f + f + 2 + j];
                }
                jac[(n + i) * d + j] = if ok { a } else { f64::NAN };
                jac[(n + i) * d + n + j] = if ok { b } else { f64::NAN };
            }
        }
    }
}
