//! Physical validity along a gait: constraint forces (stance-foot ground reaction, knee-lock
//! torques) and the flags a gait raises when a passive walker could not realise it; parameter
//! checks shared by the models.

use crate::error::WalkerError;

/// Checks that `value` is finite and in the half-open interval `[lo, hi)`.
pub(crate) fn check_closed_open(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    allowed: &'static str,
) -> Result<f64, WalkerError> {
    if value.is_finite() && value >= lo && value < hi {
        Ok(value)
    } else {
        Err(WalkerError::InvalidParam {
            name,
            value,
            allowed,
        })
    }
}

/// Constraint forces at one state along the flow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConstraintForces {
    /// Normal ground reaction on the stance foot (N); positive: the ground pushes up.
    pub normal: f64,
    /// Tangential ground reaction on the stance foot (N), along `+y` (downhill).
    pub tangential: f64,
    /// Friction coefficient the ground must supply, `|f_t / f_n|` (`+∞` if `f_n ≤ 0`).
    pub friction_required: f64,
    /// Locking torques of the knees `[stance knee, swing knee]` (N m) where the knee is locked
    /// (`None` where it is free or absent). Sign: the torque the lock applies to the shank
    /// relative to the thigh, positive towards knee flexion; the hyper-extension stop can only
    /// push, so a **negative** torque means the knee would unlock (flex).
    pub knee_torque: [Option<f64>; 2],
}

impl ConstraintForces {
    pub(crate) fn from_ground(f: [f64; 3], knee_torque: [Option<f64>; 2]) -> Self {
        let (ft, fnrm) = (f[1], f[2]);
        let friction_required = if fnrm > 0.0 {
            (ft / fnrm).abs()
        } else {
            f64::INFINITY
        };
        Self {
            normal: fnrm,
            tangential: ft,
            friction_required,
            knee_torque,
        }
    }
}

/// Validity flags of a step (all `false` for a valid step).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepFlags {
    /// The normal ground reaction on the stance foot became negative (the foot would lift off).
    pub normal_force_negative: bool,
    /// A locked knee needed a locking torque of the wrong sign (it would unlock).
    pub knee_unlocks: bool,
    /// The swing foot was below the ground while ahead of the stance foot, i.e. between
    /// mid-stance (the feet passing each other) and heel strike. The unavoidable dip of a
    /// straight swing leg *before* the feet pass is not flagged (as in Garcia et al. 1998).
    pub swing_foot_scuffs: bool,
}

impl StepFlags {
    /// Flags at one state from its constraint forces and swing-foot position `[y, z]`
    /// (relative to the stance foot); `scale` sets the tolerance of the scuff test
    /// (`z < −1e-12·scale`).
    pub fn from_state(cf: &ConstraintForces, swing_foot: [f64; 2], scale: f64) -> Self {
        Self {
            normal_force_negative: cf.normal < 0.0,
            knee_unlocks: cf.knee_torque.iter().flatten().any(|&t| t < 0.0),
            swing_foot_scuffs: swing_foot[0] > 0.0 && swing_foot[1] < -1e-12 * scale,
        }
    }

    /// Union of two sets of flags.
    pub fn merge(self, o: Self) -> Self {
        Self {
            normal_force_negative: self.normal_force_negative || o.normal_force_negative,
            knee_unlocks: self.knee_unlocks || o.knee_unlocks,
            swing_foot_scuffs: self.swing_foot_scuffs || o.swing_foot_scuffs,
        }
    }

    /// Whether any flag is raised.
    pub fn any(&self) -> bool {
        self.normal_force_negative || self.knee_unlocks || self.swing_foot_scuffs
    }
}
