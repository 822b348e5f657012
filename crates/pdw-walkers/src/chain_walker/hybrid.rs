//! The chain walker as a hybrid system ([`HybridSystem`]): flow, guards and their rates and
//! gradients, resets and Jacobians; and at any step height ([`StepHeight`]).

use super::guards::{
    LatchGuard, GUARDS_FREE, GUARDS_FREE_LATCH, GUARDS_LOCKED, GUARDS_LOCKED_LATCH,
};
use super::{ChainWalker, DMAX, FREE, MAX_SEGMENTS};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{MatMut, MatRef};
use pdw_hybrid::{GuardSpec, HybridSystem, Scratch};
use pdw_model::StepHeight;
use std::f64::consts::FRAC_PI_2;

pdw_hybrid::integrate_concretely!(ChainWalker);
impl HybridSystem for ChainWalker {
    fn dim(&self) -> usize {
        2 * self.n
    }

    fn n_modes(&self) -> usize {
        self.masks.len()
    }

    fn guards(&self, mode: usize) -> &[GuardSpec] {
        match (
            self.free_knee.is_some() && mode == FREE,
            self.latch_torque.is_some(),
        ) {
            (true, false) => &GUARDS_FREE,
            (false, false) => &GUARDS_LOCKED,
            (true, true) => &GUARDS_FREE_LATCH,
            (false, true) => &GUARDS_LOCKED_LATCH,
        }
    }

    /// One lane of [`HybridSystem::flow_batch`]: with point feet the one-lane instance of the
    /// same recursion ([`pdw_soa::aba_masked`] in the scalar workspace: the same bits, without
    /// wrapping the state in matrix views and the batched call's shape checks; event location
    /// and dense output evaluate one lane at a time).
    fn flow(&self, ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]) {
        let n = self.n;
        let d = 2 * n;
        if self.radius <= 0.0 {
            let s = self.scratch(ws);
            dx[..n].copy_from_slice(&x[n..d]);
            let (q, qd) = x[..d].split_at(n);
            let r = pdw_soa::aba_masked(
                &self.chain,
                &mut s.ws,
                q,
                qd,
                &self.masks[mode],
                &mut dx[n..d],
            );
            if r.is_err() {
                dx[..d].fill(f64::NAN);
            }
            return;
        }
        let xv = MatRef::from_column_major_slice(&x[..d], 1, d);
        let dxv = MatMut::from_column_major_slice_mut(&mut dx[..d], 1, d);
        self.flow_views(ws, mode, xv, dxv);
    }

    fn flow_batch(&self, ws: &mut Scratch, mode: usize, x: MatRef<'_, f64>, dx: MatMut<'_, f64>) {
        self.flow_views(ws, mode, x.rb(), dx);
    }

    /// The guards over all lanes: columns of `x` directly, the swing-foot height four lanes at a
    /// time (same bits as [`HybridSystem::guard`]).
    fn guard_batch(
        &self,
        ws: &mut Scratch,
        mode: usize,
        k: usize,
        x: MatRef<'_, f64>,
        out: &mut [f64],
    ) {
        let n = self.n;
        let lanes = x.nrows();
        if let Some(g) = self.latch_guard(mode, k) {
            // a latch's lock torque: lane by lane through the scalar dynamics
            let mut xi = [0.0; DMAX];
            for (l, o) in out.iter_mut().enumerate().take(lanes) {
                for (j, v) in xi.iter_mut().enumerate().take(2 * n) {
                    *v = x[(l, j)];
                }
                *o = self.latch_guard_value(ws, mode, &xi[..2 * n], g);
            }
            return;
        }
        let k = self.base_guard(mode, k);
        let free = self.free_knee.is_some() && mode == FREE;
        let lead = if free { 2 } else { 1 };
        let column = |j: usize, out: &mut [f64], shift: f64| {
            for (l, o) in out.iter_mut().enumerate().take(lanes) {
                *o = x[(l, j)] + shift;
            }
        };
        match (free, k) {
            (true, 0) => column(self.free_knee.unwrap_or(0), out, 0.0),
            (_, k) if k < lead && self.tilt != 0.0 => {
                // a tilted landing line (one walker's step of random slopes): lane by lane
                let mut xi = [0.0; 2 * MAX_SEGMENTS];
                for (l, o) in out.iter_mut().enumerate().take(lanes) {
                    for (j, v) in xi.iter_mut().enumerate().take(n) {
                        *v = x[(l, j)];
                    }
                    *o = self.above_tilted(self.swing_foot(&xi[..n]), [0.0; 2]).0;
                }
            }
            (_, k) if k < lead => {
                pdw_simd::dispatch(
                    #[inline(always)]
                    || self.foot_height_lanes(x, out),
                );
                self.above_foothold_lanes(&mut out[..lanes]);
            }
            (_, k) => match k - lead {
                0 => column(n, out, 0.0),
                1 => column(0, out, -FRAC_PI_2),
                _ => column(0, out, FRAC_PI_2),
            },
        }
    }

    /// Every guard with its exact rate `∇g·f`: the knee angle (rate `q̇_knee`), the swing-foot
    /// height (`ChainWalker::foot_height_and_rate`), the stance rate (rate `q̈₀`), the stance
    /// angle (rate `q̇₀`); `f = (q̇, q̈)`.
    fn guards_with_rates(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        f: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
    ) {
        self.guards_with_rates_at(ws, mode, x, f, g, rate, self.r.step_down);
    }

    /// [`HybridSystem::guards_with_rates`] over all lanes: columns of `x` and `f` directly, the
    /// swing-foot height and its rate four lanes at a time (same bits per lane).
    fn guards_with_rates_batch(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: MatRef<'_, f64>,
        f: MatRef<'_, f64>,
        mut g: MatMut<'_, f64>,
        mut rate: MatMut<'_, f64>,
    ) {
        let (n, lanes) = (self.n, x.nrows());
        let free = self.free_knee.is_some() && mode == FREE;
        let lead = if free { 2 } else { 1 };
        let ng = self.guards(mode).len();
        if self.tilt != 0.0 {
            // a tilted landing line (one walker's step of random slopes): lane by lane
            return pdw_hybrid::guards_with_rates_by_lane(self, ws, mode, x, f, g, rate);
        }
        let mut xc: [&[f64]; 4 * MAX_SEGMENTS] = [&[]; 4 * MAX_SEGMENTS];
        let mut fc: [&[f64]; 4 * MAX_SEGMENTS] = [&[]; 4 * MAX_SEGMENTS];
        for j in 0..2 * n {
            match (x.col(j).try_as_col_major(), f.col(j).try_as_col_major()) {
                (Some(a), Some(b)) => (xc[j], fc[j]) = (a.as_slice(), b.as_slice()),
                _ => return pdw_hybrid::guards_with_rates_by_lane(self, ws, mode, x, f, g, rate),
            }
        }
        if g.row_stride() != 1 || rate.row_stride() != 1 {
            return pdw_hybrid::guards_with_rates_by_lane(self, ws, mode, x, f, g, rate);
        }
        for k in 0..ng {
            let (Some(gk), Some(rk)) = (
                g.rb_mut().col_mut(k).try_as_col_major_mut(),
                rate.rb_mut().col_mut(k).try_as_col_major_mut(),
            ) else {
                unreachable!("columns of a view with unit row stride are contiguous")
            };
            let (gk, rk) = (gk.as_slice_mut(), rk.as_slice_mut());
            // x[j] itself (shift None) or x[j] ± π/2: the expressions of `guard`.
            let mut copy = |j: usize, shift: Option<f64>| {
                for l in 0..lanes {
                    gk[l] = shift.map_or(xc[j][l], |s| xc[j][l] + s);
                    rk[l] = fc[j][l];
                }
            };
            if let Some(lg) = self.latch_guard(mode, k) {
                // a latch's lock torque, lane by lane; its rate unknown (+∞: the integrator
                // samples every step's interior for it)
                let mut xi = [0.0; DMAX];
                for l in 0..lanes {
                    for (j, v) in xi.iter_mut().enumerate().take(2 * n) {
                        *v = xc[j][l];
                    }
                    gk[l] = self.latch_guard_value(ws, mode, &xi[..2 * n], lg);
                    rk[l] = f64::INFINITY;
                }
                continue;
            }
            match (free, self.base_guard(mode, k)) {
                (true, 0) => copy(self.free_knee.unwrap_or(0), None),
                (_, k) if k < lead => {
                    pdw_simd::dispatch(
                        #[inline(always)]
                        || self.foot_height_rate_lanes(&xc[..n], &fc[..n], lanes, gk, rk),
                    );
                    self.above_foothold_lanes(&mut gk[..lanes]);
                }
                (_, k) => match k - lead {
                    0 => copy(n, None),
                    1 => copy(0, Some(-FRAC_PI_2)),
                    _ => copy(0, Some(FRAC_PI_2)),
                },
            }
        }
    }

    /// Every guard but the swing-foot height and a latch's lock torque is a state coordinate
    /// (plus a constant).
    fn guard_is_linear(&self, mode: usize, k: usize) -> bool {
        if self.latch_guard(mode, k).is_some() {
            return false;
        }
        let k = self.base_guard(mode, k);
        let lead = if self.free_knee.is_some() && mode == FREE {
            2
        } else {
            1
        };
        !(k < lead && !(lead == 2 && k == 0))
    }

    fn guard(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64]) -> f64 {
        self.guard_at(ws, mode, k, x, self.r.step_down)
    }

    /// The impact guard (0) counts where the impact's complementarity problem keeps every
    /// stance knee locked, its twin (a fall) where it releases one
    /// ([`ChainWalker::stance_knee_buckles`]); both need the impact guard's own conditions.
    fn admissible(&self, mode: usize, k: usize, x: &[f64]) -> bool {
        self.admissible_on(mode, k, x, self.r.slope, self.r.step_down)
    }

    fn reset(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], out: &mut [f64]) -> usize {
        let n = self.n;
        if self.latch_guard(mode, k) == Some(LatchGuard::Swing) {
            // the swing knee's latch lets go: the knee swings free, nothing jumps
            out[..2 * n].copy_from_slice(&x[..2 * n]);
            return FREE;
        }
        if let (Some(knee), FREE) = (self.free_knee, mode) {
            return self.knee_strike_reset(ws, knee, x, out);
        }
        self.heel_strike_reset(ws, x, out)
    }

    /// Exact flow Jacobian: `∂q̇/∂x = [0 | I]`, and `∂q̈/∂(q, q̇)` by forward-mode dual numbers
    /// through the kernel's per-link steps with the mode's knees locked
    /// ([`pdw_soa::aba_derivatives`]: `∂q̈_f = −𝓜_ff⁻¹ ∂ID_f`, Carpentier & Mansard 2018).
    fn flow_jacobian(&self, ws: &mut Scratch, mode: usize, x: &[f64], jac: &mut [f64]) {
        let (n, d) = (self.n, 2 * self.n);
        let s = self.scratch(ws);
        let mut dq = [0.0; 4 * MAX_SEGMENTS * MAX_SEGMENTS];
        let mut dqd = [0.0; 4 * MAX_SEGMENTS * MAX_SEGMENTS];
        let ok = if self.radius > 0.0 {
            pdw_soa::rolling_base_derivatives(
                &self.floating,
                self.radius,
                &x[..n],
                &x[n..d],
                &self.masks[mode],
                &mut s.v[..n],
                &mut dq[..n * n],
                &mut dqd[..n * n],
            )
        } else {
            pdw_soa::aba_derivatives(
                &self.chain,
                &x[..n],
                &x[n..d],
                &s.zeros[..n],
                &self.masks[mode],
                &mut s.v[..n],
                &mut dq[..n * n],
                &mut dqd[..n * n],
            )
        }
        .is_ok();
        jac[..d * d].fill(0.0);
        for i in 0..n {
            jac[i * d + n + i] = 1.0;
            for j in 0..n {
                jac[(n + i) * d + j] = if ok { dq[i * n + j] } else { f64::NAN };
                jac[(n + i) * d + n + j] = if ok { dqd[i * n + j] } else { f64::NAN };
            }
        }
    }

    /// Exact gradients: the knee angle, the swing-foot height (kernel tip-position derivatives),
    /// the stance rate, the stance angle.
    fn guard_gradient(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], grad: &mut [f64]) {
        if let Some(g) = self.latch_guard(mode, k) {
            return self.latch_guard_gradient(ws, mode, x, g, grad);
        }
        let k = self.base_guard(mode, k);
        let (n, d) = (self.n, 2 * self.n);
        grad[..d].fill(0.0);
        let free = self.free_knee.is_some() && mode == FREE;
        let lead = if free { 2 } else { 1 };
        match (free, k) {
            (true, 0) => grad[self.free_knee.unwrap_or(0)] = 1.0,
            (_, k) if k < lead => {
                let mut pos = [0.0; 2];
                let mut j = [0.0; 2 * 2 * MAX_SEGMENTS];
                match pdw_soa::tip_position_derivatives(
                    &self.chain,
                    &x[..n],
                    &mut pos,
                    &mut j[..2 * n],
                ) {
                    Ok(()) if self.tilt != 0.0 => {
                        // ∇(p·n): rows y and z of the tip Jacobian weighted by n = (sin Δ, cos Δ)
                        let (s, c) = self.tilt_sc;
                        for i in 0..n {
                            grad[i] = s * j[i] + c * j[n + i];
                        }
                    }
                    Ok(()) => grad[..n].copy_from_slice(&j[n..2 * n]),
                    Err(_) => grad[..d].fill(f64::NAN),
                }
            }
            (_, k) if k == lead => grad[n] = 1.0,
            _ => grad[0] = 1.0,
        }
    }

    /// Exact reset Jacobians: the impact maps' derivatives by dual numbers through the kernel
    /// ([`pdw_soa::joint_lock_impact_derivatives`], [`pdw_soa::tip_impact_derivatives`]), the
    /// leg swap as its matrix.
    fn reset_jacobian(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], jac: &mut [f64]) {
        let d = 2 * self.n;
        jac[..d * d].fill(0.0);
        if self.latch_guard(mode, k) == Some(LatchGuard::Swing) {
            // the identity: a mode change without a jump
            for i in 0..d {
                jac[i * d + i] = 1.0;
            }
            return;
        }
        if let (Some(knee), FREE) = (self.free_knee, mode) {
            return self.knee_strike_jacobian(ws, knee, x, jac);
        }
        self.heel_strike_jacobian(ws, x, jac);
    }
}

/// The chain walker at any step height (chain walker docs, "Step down"): the swing-foot guards
/// measure the foot's height over the foothold's line and the heel strike's admissibility
/// drops the level-ground factor; the impacts, the gradients (`h` is a constant) and the lift
/// of the trailing leg (not part of a stride) do not see it.
impl StepHeight for ChainWalker {
    fn guard_at(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], h: f64) -> f64 {
        if let Some(g) = self.latch_guard(mode, k) {
            return self.latch_guard_value(ws, mode, x, g);
        }
        let k = self.base_guard(mode, k);
        let n = self.n;
        let free = self.free_knee.is_some() && mode == FREE;
        let lead = if free { 2 } else { 1 };
        match (free, k) {
            (true, 0) => x[self.free_knee.unwrap_or(0)],
            (_, k) if k < lead && self.tilt != 0.0 => {
                self.above_tilted(self.swing_foot(x), [0.0; 2]).0
            }
            (_, k) if k < lead => Self::above_foothold(self.swing_foot(x)[1], h),
            (_, k) => match k - lead {
                0 => x[n],
                1 => x[0] - FRAC_PI_2,
                _ => x[0] + FRAC_PI_2,
            },
        }
    }

    fn guards_with_rates_at(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        f: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
        h: f64,
    ) {
        let n = self.n;
        let free = self.free_knee.is_some() && mode == FREE;
        let lead = if free { 2 } else { 1 };
        let ng = self.guards(mode).len();
        for k in 0..ng {
            if let Some(lg) = self.latch_guard(mode, k) {
                // rate unknown: +∞ (the integrator samples every step's interior for it)
                (g[k], rate[k]) = (self.latch_guard_value(ws, mode, x, lg), f64::INFINITY);
                continue;
            }
            (g[k], rate[k]) = match (free, self.base_guard(mode, k)) {
                (true, 0) => {
                    let j = self.free_knee.unwrap_or(0);
                    (x[j], f[j])
                }
                (_, k) if k < lead && self.tilt != 0.0 => {
                    let (p, pd) = self.swing_foot_and_rate(x, f);
                    self.above_tilted(p, pd)
                }
                (_, k) if k < lead => {
                    let (z, zr) = self.foot_height_and_rate(x, f);
                    (Self::above_foothold(z, h), zr)
                }
                (_, k) => match k - lead {
                    0 => (x[n], f[n]),
                    1 => (x[0] - FRAC_PI_2, f[0]),
                    _ => (x[0] + FRAC_PI_2, f[0]),
                },
            };
        }
    }

    fn guard_gradient_at(
        &self,
        ws: &mut Scratch,
        mode: usize,
        k: usize,
        x: &[f64],
        grad: &mut [f64],
        _h: f64,
    ) {
        self.guard_gradient(ws, mode, k, x, grad)
    }

    fn admissible_at(&self, mode: usize, k: usize, x: &[f64], h: f64) -> bool {
        self.admissible_on(mode, k, x, self.r.slope, h)
    }

    fn reset_at(
        &self,
        ws: &mut Scratch,
        mode: usize,
        k: usize,
        x: &[f64],
        out: &mut [f64],
        _h: f64,
    ) -> usize {
        self.reset(ws, mode, k, x, out)
    }

    fn guard_is_linear_at_every_height(&self, mode: usize, k: usize) -> bool {
        self.guard_is_linear(mode, k)
    }
}
