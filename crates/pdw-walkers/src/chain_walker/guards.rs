//! The guards of each mode (chain walker docs, "Guards", "Latches with holding limits"): their
//! specs, the impact guards' twins, the latch guards' values and gradients, and admissibility.

use super::{ChainWalker, DMAX, FREE, LOCKED, MAX_SEGMENTS};
#[cfg(doc)]
use pdw_hybrid::HybridSystem;
use pdw_hybrid::{Crossing, FallKind, GuardKind, GuardSpec, Scratch};

const FALLS: [GuardSpec; 3] = [
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

pub(super) const GUARDS_FREE: [GuardSpec; 6] = [
    GuardSpec {
        name: "knee_strike",
        crossing: Crossing::Rising,
        kind: GuardKind::Reset,
    },
    GuardSpec {
        name: "foot_strike_knee_bent",
        crossing: Crossing::Falling,
        kind: GuardKind::Terminal(FallKind::KneeBent),
    },
    FALLS[0],
    FALLS[1],
    FALLS[2],
    GuardSpec {
        name: "knee_strike_buckles",
        crossing: Crossing::Rising,
        kind: GuardKind::Terminal(FallKind::KneeBuckled),
    },
];

pub(super) const GUARDS_LOCKED: [GuardSpec; 5] = [
    GuardSpec {
        name: "heel_strike",
        crossing: Crossing::Falling,
        kind: GuardKind::Reset,
    },
    FALLS[0],
    FALLS[1],
    FALLS[2],
    GuardSpec {
        name: "heel_strike_buckles",
        crossing: Crossing::Falling,
        kind: GuardKind::Terminal(FallKind::KneeBuckled),
    },
];

/// The guard of a stance knee's latch letting go (chain walker docs, "Latches"): its lock torque
/// plus `latch_torque` falling through 0. The stance leg buckles: a fall.
const STANCE_LATCH: GuardSpec = GuardSpec {
    name: "stance_latch_releases",
    crossing: Crossing::Falling,
    kind: GuardKind::Terminal(FallKind::KneeBuckled),
};

/// The guard of the locked swing knee's latch letting go (chain walker docs, "Latches"): reset to
/// the mode with the swing knee free, the state unchanged.
const SWING_LATCH: GuardSpec = GuardSpec {
    name: "swing_latch_releases",
    crossing: Crossing::Falling,
    kind: GuardKind::Reset,
};

/// The free mode's guards of a walker whose latch has a `latch_torque`.
pub(super) const GUARDS_FREE_LATCH: [GuardSpec; 7] = [
    GUARDS_FREE[0],
    GUARDS_FREE[1],
    GUARDS_FREE[2],
    GUARDS_FREE[3],
    GUARDS_FREE[4],
    GUARDS_FREE[5],
    STANCE_LATCH,
];

/// The locked mode's guards of a walker whose latch has a `latch_torque`.
pub(super) const GUARDS_LOCKED_LATCH: [GuardSpec; 7] = [
    GUARDS_LOCKED[0],
    GUARDS_LOCKED[1],
    GUARDS_LOCKED[2],
    GUARDS_LOCKED[3],
    GUARDS_LOCKED[4],
    STANCE_LATCH,
    SWING_LATCH,
];

/// Which latch a latch guard watches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum LatchGuard {
    Stance,
    Swing,
}

/// Index of the twin of guard 0 (the impact guard) in `mode`: the same function, a fall where the
/// impact's complementarity problem releases a stance knee (see the chain walker docs).
const TWIN_FREE: usize = 5;
const TWIN_LOCKED: usize = 4;

impl ChainWalker {
    /// The latch guard guard `k` of `mode` is, if any (chain walker docs, "Latches"): the stance
    /// latch in both modes, the swing latch in the locked mode, after the model's other guards.
    pub(super) fn latch_guard(&self, mode: usize, k: usize) -> Option<LatchGuard> {
        self.latch_torque?;
        let first = if self.free_knee.is_some() && mode == FREE {
            GUARDS_FREE.len()
        } else {
            GUARDS_LOCKED.len()
        };
        match k.checked_sub(first) {
            Some(0) => Some(LatchGuard::Stance),
            Some(1) if mode == LOCKED => Some(LatchGuard::Swing),
            _ => None,
        }
    }

    /// The latch guard's value at `x`: the knee's lock torque towards flexion `τ` (the stance
    /// knee's kernel torque, the swing knee's negated; [`ChainWalker::constraint_forces_ws`])
    /// plus the pull the latch holds, `τ + L`: positive while it holds, falling through 0 where
    /// the pull exceeds `latch_torque`.
    pub(super) fn latch_guard_value(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        g: LatchGuard,
    ) -> f64 {
        let n = self.n;
        let mut qdd = [0.0; 2 * MAX_SEGMENTS];
        let mut lock = [0.0; 2 * MAX_SEGMENTS];
        self.dynamics(ws, mode, x, &mut qdd[..n], &mut lock[..n]);
        let l = self.latch_torque.unwrap_or(0.0);
        match g {
            LatchGuard::Stance => lock[1] + l,
            LatchGuard::Swing => -lock[n - 1] + l,
        }
    }

    /// Gradient of a latch guard (the lock torque): central differences of
    /// [`ChainWalker::latch_guard_value`], step `ε^(1/3) max(|x_j|, 1)` (relative error
    /// ~1e-10). The kernel has no derivative of a locking torque; of this model's gradients it
    /// is the one computed by differences, and a stride map's Jacobian needs it only through
    /// the swing latch's release (the stance latch's is a fall).
    pub(super) fn latch_guard_gradient(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        g: LatchGuard,
        grad: &mut [f64],
    ) {
        let d = 2 * self.n;
        let mut xp = [0.0; DMAX];
        xp[..d].copy_from_slice(&x[..d]);
        for j in 0..d {
            let h = f64::EPSILON.cbrt() * x[j].abs().max(1.0);
            xp[j] = x[j] + h;
            let gp = self.latch_guard_value(ws, mode, &xp[..d], g);
            xp[j] = x[j] - h;
            let gm = self.latch_guard_value(ws, mode, &xp[..d], g);
            xp[j] = x[j];
            grad[j] = (gp - gm) / (2.0 * h);
        }
    }

    /// Index of the twin of the impact guard 0 in `mode` (a fall on the same surface).
    fn twin_guard(&self, mode: usize) -> usize {
        if self.free_knee.is_some() && mode == FREE {
            TWIN_FREE
        } else {
            TWIN_LOCKED
        }
    }

    /// The guard whose function guard `k` of `mode` evaluates (the twin evaluates guard 0).
    pub(super) fn base_guard(&self, mode: usize, k: usize) -> usize {
        if k == self.twin_guard(mode) {
            0
        } else {
            k
        }
    }

    /// [`HybridSystem::admissible`] for the model at slope `slope` and step height `h`: only `stance_reverses`
    /// ("while `q₀ > γ`", the stance leg behind the vertical) sees the slope; every other
    /// condition measures the walker against the ground line.
    pub(super) fn admissible_on(
        &self,
        mode: usize,
        k: usize,
        x: &[f64],
        slope: f64,
        h: f64,
    ) -> bool {
        if self.latch_guard(mode, k).is_some() {
            return true;
        }
        let free = self.free_knee.is_some() && mode == FREE;
        let lead = if free { 2 } else { 1 };
        let twin = k != 0 && k == self.twin_guard(mode);
        let base = match (free, self.base_guard(mode, k)) {
            (true, 0) => true,
            (true, 1) => self.swing_ahead(x),
            (false, 0) if h != 0.0 => self.swing_ahead(x),
            (false, 0) => {
                // the heel-strike factor in the landing line's frame (stance angle + Δ; adding
                // Δ = 0 changes no bit of the factor)
                let qh = x[self.m];
                self.swing_ahead(x)
                    && (2.0 * (self.stance_angle(x) + self.tilt) + qh).abs() < qh.abs()
            }
            (_, k) if k == lead => x[0] > slope,
            _ => true,
        };
        if !base || self.base_guard(mode, k) != 0 {
            return base;
        }
        self.stance_knee_buckles(mode, x) == twin
    }
}
