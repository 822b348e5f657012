//! Physical validity along a gait: constraint forces (stance-foot ground reaction, knee-lock
//! torques) and the flags a gait raises when a passive walker could not realise it, the impulses
//! of an impact, and the scales that make margins relative.

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
    /// From the stance foot's planar spatial ground force `f = (moment, tangential, normal)`
    /// and the knee-lock torques; the friction coefficient required is
    /// |tangential / normal| (∞ without a pushing normal force).
    pub fn from_ground(f: [f64; 3], knee_torque: [Option<f64>; 2]) -> Self {
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

/// Natural scales of a walker, for margins on a scale (issue: "margins relative to m·g·l"):
/// forces relative to `m g`, torques to `m g l`, clearance to `l`, linear impulses to
/// `m √(g l)`, angular impulses to `m l √(g l)` (`m` the total mass, `l` the leg length, `g`
/// gravity, all in the model's units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scales {
    /// Total mass `m`.
    pub mass: f64,
    /// Leg length `l`.
    pub length: f64,
    /// Gravitational acceleration `g`.
    pub gravity: f64,
}

impl Scales {
    /// `m g` (force).
    pub fn force(&self) -> f64 {
        self.mass * self.gravity
    }
    /// `m g l` (torque).
    pub fn torque(&self) -> f64 {
        self.mass * self.gravity * self.length
    }
    /// `m √(g l)` (linear impulse).
    pub fn impulse(&self) -> f64 {
        self.mass * (self.gravity * self.length).sqrt()
    }
    /// `m l √(g l)` (angular impulse).
    pub fn angular_impulse(&self) -> f64 {
        self.mass * self.length * (self.gravity * self.length).sqrt()
    }
    /// `√(g l)` (speed: a contact's separation velocity).
    pub fn speed(&self) -> f64 {
        (self.gravity * self.length).sqrt()
    }
    /// `√(g / l)` (angular rate: a knee's flexion rate).
    pub fn rate(&self) -> f64 {
        (self.gravity / self.length).sqrt()
    }
}

/// What an impulsive constraint of an impact is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImpulseKind {
    /// Normal impulse of a foot contact (N s in SI specs); positive: the ground pushes up.
    ContactNormal,
    /// Tangential impulse of a foot contact along `+y` (downhill); sticking, no sign.
    ContactTangential,
    /// Angular impulse of a knee's hyper-extension stop (N m s); positive: towards flexion
    /// (the only way a stop can push).
    KneeStop,
}

/// One impulsive constraint of an impact (a contact direction or a knee stop).
///
/// `active`, `impulse` and `rate_after` describe the impact map the model applies; `margin`
/// says whether that is physically consistent: a unilateral constraint that holds must push
/// (`impulse ≥ 0`), one that releases must separate (`rate_after ≥ 0`). The model decides which
/// constraints release by the impact's linear complementarity problem (contacts and stops push
/// only); where the model holds a constraint the complementarity problem would release (the
/// trailing knee at heel strike, the trailing foot), the margin is negative and the gait is
/// flagged, never silently accepted.
#[derive(Clone, Debug, PartialEq)]
pub struct ImpulseEntry {
    /// Which contact or stop, e.g. `"new_stance_foot"`, `"trailing_foot"`, `"stance_knee"`,
    /// `"trailing_knee"`, `"striking_knee"` (roles at the impact, before any leg swap).
    pub name: String,
    pub kind: ImpulseKind,
    /// A constraint that may release (a unilateral contact or stop). `false` for those the
    /// event itself closes (the striking foot, the striking knee): they hold by definition and
    /// only the sign of their impulse is checked.
    pub unilateral: bool,
    /// Holds in the model's impact map (rate zero after the impact).
    pub active: bool,
    /// Impulse applied (0 where not active). Sign: positive pushes (module docs of
    /// [`ImpulseKind`]); a tangential impulse has no sign condition.
    pub impulse: f64,
    /// Rate after the impact along the constraint's allowed direction (normal separation
    /// velocity, knee flexion rate); 0 where active.
    pub rate_after: f64,
    /// The pulling impulse the constraint's hardware holds (≥ 0): a latch's `latch_impulse`,
    /// 0 for contacts, stops and ideal latches (reported where they pull).
    pub pull_limit: f64,
}

impl ImpulseEntry {
    /// The consistency margin: the impulse plus the pull the hardware holds
    /// ([`ImpulseEntry::pull_limit`], i.e. limit − pull) where the constraint holds, the
    /// separation rate where it released; `None` for a tangential impulse (see
    /// [`ImpactReport::friction_required`]). Negative: the impact map is not physical.
    pub fn margin(&self) -> Option<f64> {
        match (self.kind, self.active) {
            (ImpulseKind::ContactTangential, _) => None,
            (_, true) if self.pull_limit > 0.0 => Some(self.impulse + self.pull_limit),
            (_, true) => Some(self.impulse),
            (_, false) => Some(self.rate_after),
        }
    }
}

/// The impulses of one impact and what they mean for the gait.
#[derive(Clone, Debug, PartialEq)]
pub struct ImpactReport {
    /// The event, e.g. `"heel_strike"`, `"knee_strike"`.
    pub event: String,
    /// Every constraint of the impact problem.
    pub entries: Vec<ImpulseEntry>,
    /// Friction coefficient the striking (or, at a knee strike, the stance) contact needs,
    /// `|Λ_t / Λ_n|` (`+∞` if `Λ_n ≤ 0`).
    pub friction_required: f64,
    /// Kinetic energy lost in the impact (`≥ 0` up to roundoff).
    pub energy_lost: f64,
}

impl ImpactReport {
    /// The report of a point contact striking the ground while the trailing point leaves it
    /// (the simplest walker's heel strike, the rimless wheel's spoke impact): the new contact's
    /// normal and tangential impulses `ln`, `lt` (bilateral in the impulse problem, both
    /// holding), the trailing contact's release with its normal separation rate `rate` after
    /// the impact, the friction needed `|lt/ln|` (`+∞` if `ln ≤ 0`) and the energy lost.
    pub fn point_contact(event: &str, ln: f64, lt: f64, rate: f64, energy_lost: f64) -> Self {
        let entry = |kind, unilateral, active, impulse, rate_after| ImpulseEntry {
            name: if active {
                "new_stance_foot"
            } else {
                "trailing_foot"
            }
            .into(),
            kind,
            unilateral,
            active,
            impulse,
            rate_after,
            pull_limit: 0.0,
        };
        ImpactReport {
            event: event.into(),
            entries: vec![
                entry(ImpulseKind::ContactNormal, false, true, ln, 0.0),
                entry(ImpulseKind::ContactTangential, false, true, lt, 0.0),
                entry(ImpulseKind::ContactNormal, true, false, 0.0, rate),
            ],
            friction_required: if ln > 0.0 {
                (lt / ln).abs()
            } else {
                f64::INFINITY
            },
            energy_lost,
        }
    }

    /// The smallest impulse among the entries of `kind` that hold (active), or `None`.
    pub fn min_active(&self, kind: ImpulseKind) -> Option<f64> {
        self.entries
            .iter()
            .filter(|e| e.kind == kind && e.active)
            .map(|e| e.impulse)
            .reduce(f64::min)
    }
    /// The entry named `name`.
    pub fn entry(&self, name: &str) -> Option<&ImpulseEntry> {
        self.entries.iter().find(|e| e.name == name)
    }
    /// The smallest consistency margin over the entries ([`ImpulseEntry::margin`]) with the
    /// entry's name, or `None` without entries that have one.
    pub fn min_margin(&self) -> Option<(f64, &str)> {
        self.entries
            .iter()
            .filter_map(|e| e.margin().map(|m| (m, e.name.as_str())))
            .reduce(|a, b| if b.0 < a.0 { b } else { a })
    }
}

/// Where the swing foot must clear the ground.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClearanceRule {
    /// From lift-off to heel strike (walkers with knees: a foot below the slope is a violation).
    WholeSwing,
    /// Only after mid-stance (the swing foot ahead of the stance foot): the point-foot
    /// literature's convention for walkers without knees (Garcia et al. 1998; McGeer 1990), whose
    /// straight swing leg must dip through the slope at mid-stance; the depth of that scuff is
    /// still reported.
    AfterMidStance,
}
