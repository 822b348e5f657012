//! The stance dynamics: joint accelerations with the mode's knees locked (pseudo joints, seed
//! §3.4; the rolling base for round feet), the constraint forces and validity flags they give,
//! and the batched flow over all lanes (chain walker docs, "Modes", "Round feet").

use super::{ChainWalker, FMAX, FREE, MAX_SEGMENTS};
use crate::validity::{ConstraintForces, StepFlags};
use faer::reborrow::ReborrowMut;
use faer::{MatMut, MatRef};
use pdw_hybrid::Scratch;

impl ChainWalker {
    /// Joint accelerations in `mode`, the locking torques (kernel sign, per joint, 0 where
    /// free) and the ground's force on the stance foot `[τ, f_y, f_z]`, by the kernel's
    /// [`pdw_soa::pseudo_joint_dynamics`].
    pub fn dynamics(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        qdd: &mut [f64],
        lock: &mut [f64],
    ) -> [f64; 3] {
        let n = self.n;
        if self.radius > 0.0 {
            // round feet: the rolling base; the ground force and the locks from ID_F
            let mut tau = [0.0; FMAX];
            let ok = pdw_soa::rolling_base_dynamics(
                &self.floating,
                self.radius,
                &x[..n],
                &x[n..2 * n],
                &self.masks[mode],
                qdd,
                &mut tau[..n + 2],
            )
            .is_ok();
            if !ok {
                qdd.iter_mut().for_each(|v| *v = f64::NAN);
                lock.iter_mut().for_each(|v| *v = f64::NAN);
                return [f64::NAN; 3];
            }
            for k in 0..n {
                lock[k] = if self.masks[mode][k] { tau[k + 2] } else { 0.0 };
            }
            return [tau[2], tau[0], tau[1]];
        }
        let s = self.scratch(ws);
        let r = pdw_soa::pseudo_joint_dynamics(
            &self.chain,
            &mut s.ws,
            &x[..n],
            &x[n..2 * n],
            &s.zeros[..n],
            &self.locked[mode],
            None,
            qdd,
            lock,
        )
        .map(|_| s.ws.joint_forces()[0]);
        match r {
            Ok(f) => f,
            Err(_) => {
                qdd.iter_mut().for_each(|v| *v = f64::NAN);
                lock.iter_mut().for_each(|v| *v = f64::NAN);
                [f64::NAN; 3]
            }
        }
    }

    /// Ground reaction at the stance foot and the knee-lock torques, positive towards flexion
    /// (a stance knee's kernel torque as is, a swing knee's negated); of several knees per leg
    /// the smallest (the one nearest to unlocking) is reported.
    pub fn constraint_forces_ws(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
    ) -> ConstraintForces {
        let n = self.n;
        let mut qdd = [0.0; 2 * MAX_SEGMENTS];
        let mut lock = [0.0; 2 * MAX_SEGMENTS];
        let f = self.dynamics(ws, mode, x, &mut qdd[..n], &mut lock[..n]);
        let m = self.m;
        let stance = (1..m).map(|k| lock[k]).reduce(f64::min);
        let swing = (m + 1..n)
            .filter(|k| self.masks[mode][*k])
            .map(|k| -lock[k])
            .reduce(f64::min);
        ConstraintForces::from_ground(f, [stance, swing])
    }

    /// Validity flags at one state; a hyper-extended free knee (`q > 0` in the free mode) also
    /// raises `knee_unlocks`. A latch with a `latch_torque` `L` unlocks where its lock torque
    /// `τ` (positive towards flexion) pulls more than it holds, `τ + L < 0`.
    pub fn check_state_ws(&self, ws: &mut Scratch, mode: usize, x: &[f64]) -> StepFlags {
        let cf = self.constraint_forces_ws(ws, mode, x);
        let mut f = StepFlags::from_state(&cf, self.swing_foot(x), self.leg_length);
        if let Some(l) = self.latch_torque {
            f.knee_unlocks = cf.knee_torque.iter().flatten().any(|&t| t + l < 0.0);
        }
        if let (Some(k), FREE) = (self.free_knee, mode) {
            if x[k] > 1e-9 {
                f.knee_unlocks = true;
            }
        }
        f
    }

    pub(super) fn flow_views(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: MatRef<'_, f64>,
        mut dx: MatMut<'_, f64>,
    ) {
        let n = self.n;
        for j in 0..n {
            dx.rb_mut().col_mut(j).copy_from(x.col(n + j));
        }
        let s = self.scratch(ws);
        if self.radius > 0.0 {
            // round feet: lane by lane through the rolling-base dynamics (the scalar flow is
            // the one-lane case of this loop, hence the same bits)
            let mut q = [0.0; 2 * MAX_SEGMENTS];
            let mut qd = [0.0; 2 * MAX_SEGMENTS];
            let mut qdd = [0.0; 2 * MAX_SEGMENTS];
            let mut tau = [0.0; FMAX];
            for l in 0..x.nrows() {
                for j in 0..n {
                    q[j] = x[(l, j)];
                    qd[j] = x[(l, n + j)];
                }
                let ok = pdw_soa::rolling_base_dynamics(
                    &self.floating,
                    self.radius,
                    &q[..n],
                    &qd[..n],
                    &self.masks[mode],
                    &mut qdd[..n],
                    &mut tau[..n + 2],
                )
                .is_ok();
                for j in 0..n {
                    dx[(l, n + j)] = if ok { qdd[j] } else { f64::NAN };
                }
            }
            return;
        }
        let r = pdw_soa::batch_aba_view(
            &self.chain,
            &mut s.bw,
            x.subcols(0, n),
            x.subcols(n, n),
            None,
            None,
            Some(&self.masks[mode]),
            dx.rb_mut().subcols_mut(n, n),
        );
        if r.is_err() {
            dx.fill(f64::NAN);
        }
    }
}
