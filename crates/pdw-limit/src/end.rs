//! How a stride or a basin cell ends: one vocabulary, [`End`], for the stride map, the basin,
//! the walks of the mean-first-passage time, the files and Python.
//!
//! A **stride** runs from a heel strike to the next one (one application of the stride map);
//! a **step** is one step of the integrator. A stride ends at its heel strike
//! ([`End::HeelStrike`]), by a fall of the model's kind (a terminal guard), with no heel strike
//! within the stride time budget ([`End::FallNoHeelStrike`]), with a non-finite state, or with
//! an integrator failure. A basin cell, a sequence of strides, ends at the gait, at another
//! attractor, at a fall, or unclassified after its stride budget ([`End::Timeout`]).
//!
//! The `u8` codes are those of `/basin/outcome` (the file format; they never change):
//!
//! | code | name | a stride | a cell |
//! |---:|---|:-:|:-:|
//! | 0 | `gait` | | ✓ |
//! | 1 | `other` | | ✓ |
//! | 2 | `fall_forward` | ✓ | ✓ |
//! | 3 | `fall_backward` | ✓ | ✓ |
//! | 4 | `fall_hip_below_ground` | | ✓ (no shipped model) |
//! | 5 | `fall_no_heel_strike` | ✓ | ✓ |
//! | 6 | `fall` | ✓ | ✓ |
//! | 7 | `timeout` | | ✓ |
//! | 8 | `nonfinite` | ✓ | ✓ |
//! | 9 | `integrator_failure` | ✓ | ✓ |
//! | 10 | `fall_knee_bent` | ✓ | ✓ |
//! | 11 | `fall_knee_buckled` | ✓ | ✓ |
//! | 12 | `fall_rolls_back` | ✓ | ✓ |
//! | 13 | `heel_strike` | ✓ | |
//!
//! Code 13 is taken from the range 13–15 that the basin files keep free below the attractor
//! codes ([`crate::basin::ATTRACTOR_CODE_BASE`] = 16); 14 and 15 stay free. A stride's detail
//! beyond its end (the fall's guard, which of the three integrator failures) is in its
//! [`StrideOutcome`](crate::StrideOutcome); [`StrideOutcome::end`](crate::StrideOutcome::end)
//! gives its end in this vocabulary.

use pdw_hybrid::FallKind;

/// How a stride or a basin cell ends (module docs). The `u8` codes are part of the file
/// format and never change.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum End {
    /// A cell converged to the selected fixed point.
    Gait = 0,
    /// A cell reached another attractor (a known one, or detected by recurrence).
    Other = 1,
    /// Fell forward (a terminal guard of the model).
    FallForward = 2,
    /// Fell backward (a terminal guard of the model).
    FallBackward = 3,
    /// The hip went below the ground (a terminal guard of the model).
    FallHipBelowGround = 4,
    /// No heel strike within the stride time budget.
    FallNoHeelStrike = 5,
    /// A fall of another kind (a terminal guard whose kind is none of the above, e.g. a rimless
    /// wheel rolling back to rest), or, for a cell, a walk that died out: the walker comes to a
    /// stand ([`crate::basin::stands_still`]).
    Fall = 6,
    /// A cell not classified within its stride budget (`max_strides`).
    Timeout = 7,
    /// The state became non-finite (or the cell itself was not finite).
    NonFinite = 8,
    /// The integrator failed: its step size collapsed, its step budget ran out, or a stride
    /// had more than [`crate::MAX_EVENTS_PER_STRIDE`] intermediate events.
    IntegratorFailure = 9,
    /// The swing foot struck the ground before the swing knee locked ([`FallKind::KneeBent`]).
    FallKneeBent = 10,
    /// A stance knee buckled: its stop would have to pull, or its latch let go
    /// ([`FallKind::KneeBuckled`]).
    FallKneeBuckled = 11,
    /// A rimless wheel rolled back, not reaching its next spoke ([`FallKind::RollsBack`]).
    FallRollsBack = 12,
    /// A stride reached its heel strike (the section): a complete stride. Never a cell's end.
    HeelStrike = 13,
}

impl End {
    /// Every end, by code: the one table.
    pub const ALL: [End; 14] = [
        End::Gait,
        End::Other,
        End::FallForward,
        End::FallBackward,
        End::FallHipBelowGround,
        End::FallNoHeelStrike,
        End::Fall,
        End::Timeout,
        End::NonFinite,
        End::IntegratorFailure,
        End::FallKneeBent,
        End::FallKneeBuckled,
        End::FallRollsBack,
        End::HeelStrike,
    ];

    /// The ends a basin cell can have, by code (every end but [`End::HeelStrike`]): the fixed
    /// part of a basin file's legend.
    pub const CELL_ENDS: [End; 13] = [
        End::Gait,
        End::Other,
        End::FallForward,
        End::FallBackward,
        End::FallHipBelowGround,
        End::FallNoHeelStrike,
        End::Fall,
        End::Timeout,
        End::NonFinite,
        End::IntegratorFailure,
        End::FallKneeBent,
        End::FallKneeBuckled,
        End::FallRollsBack,
    ];

    /// Stable code (the value stored in `/basin/outcome`).
    pub fn code(self) -> u8 {
        self as u8
    }

    /// The end of a code, if it is one.
    pub fn from_code(code: u8) -> Option<End> {
        End::ALL.iter().copied().find(|o| o.code() == code)
    }

    /// Stable name, e.g. `"gait"`, `"fall_forward"`, `"heel_strike"`.
    pub fn name(self) -> &'static str {
        match self {
            End::Gait => "gait",
            End::Other => "other",
            End::FallForward => "fall_forward",
            End::FallBackward => "fall_backward",
            End::FallHipBelowGround => "fall_hip_below_ground",
            End::FallNoHeelStrike => "fall_no_heel_strike",
            End::Fall => "fall",
            End::Timeout => "timeout",
            End::NonFinite => "nonfinite",
            End::IntegratorFailure => "integrator_failure",
            End::FallKneeBent => "fall_knee_bent",
            End::FallKneeBuckled => "fall_knee_buckled",
            End::FallRollsBack => "fall_rolls_back",
            End::HeelStrike => "heel_strike",
        }
    }

    /// The end of a name ([`End::name`]), if it is one.
    pub fn from_name(name: &str) -> Option<End> {
        End::ALL.iter().copied().find(|o| o.name() == name)
    }

    /// True for every fall kind.
    pub fn is_fall(self) -> bool {
        matches!(
            self,
            End::FallForward
                | End::FallBackward
                | End::FallHipBelowGround
                | End::FallNoHeelStrike
                | End::Fall
                | End::FallKneeBent
                | End::FallKneeBuckled
                | End::FallRollsBack
        )
    }

    /// True for the ends a basin cell can have ([`End::CELL_ENDS`]).
    pub fn is_cell_end(self) -> bool {
        self != End::HeelStrike
    }

    /// The end of a fall of `kind` (the kind a terminal guard carries): each kind its own
    /// class, [`FallKind::Other`] the catch-all `fall`.
    pub fn of_fall(kind: FallKind) -> End {
        match kind {
            FallKind::Forward => End::FallForward,
            FallKind::Backward => End::FallBackward,
            FallKind::KneeBent => End::FallKneeBent,
            FallKind::KneeBuckled => End::FallKneeBuckled,
            FallKind::RollsBack => End::FallRollsBack,
            FallKind::Other => End::Fall,
        }
    }
}

/// `(code, name)` of every end, by code: the one table ([`End::ALL`]).
pub fn table() -> Vec<(u8, &'static str)> {
    End::ALL.iter().map(|o| (o.code(), o.name())).collect()
}
