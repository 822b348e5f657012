//! Building a chain walker from its spec: the kernel chains (rooted at the stance foot, and
//! floating for impacts and round feet), the knees' modes and holds, the state's names, and the
//! walker on a tilted landing line (chain walker docs, "Chain, frame, coordinates and signs",
//! "Modes", "Landing on a tilted line").

use super::{ChainWalker, FLOATING_BASE_MASS, MAX_SEGMENTS};
use crate::error::WalkerError;
use crate::spec::{Resolved, WalkerSpec};
use pdw_soa::{Chain, ChainBuilder, Link};

impl ChainWalker {
    /// Builds the walker from a spec at its default parameter values.
    pub fn from_spec(spec: WalkerSpec) -> Result<Self, WalkerError> {
        let values = spec.param_table().values;
        Self::new(spec, &values)
    }

    /// Builds the walker from a spec at parameter values `values` (in
    /// [`WalkerSpec::param_table`] order).
    pub fn new(spec: WalkerSpec, values: &[f64]) -> Result<Self, WalkerError> {
        let r = spec.resolve(values)?;
        let m = r.segments.len();
        check_segment_count(&spec, m)?;
        let n = 2 * m;
        check_step_down(&spec, &r)?;
        let mut table = spec.param_table();
        table.values = values.to_vec();
        let radius = r.foot_radius;
        let links = chain_links(&r);
        let (chain, floating) = build_chains(&spec, &r, &links)?;
        let len: Vec<f64> = links.iter().map(|l| l.to_next[1]).collect();
        let leg_length = r.segments.iter().map(|s| s[0]).sum();
        let knees = KneeLayout::of(&r);
        Ok(Self {
            spec,
            table,
            r,
            m,
            n,
            chain,
            floating,
            len,
            leg_length,
            radius,
            free_knee: knees.free_knee,
            masks: knees.masks,
            locked: knees.locked,
            floating_knees: knees.floating_knees,
            latched: knees.latched,
            trailing_free: knees.trailing_free,
            latch_torque: knees.latch_torque,
            latch_impulse: knees.latch_impulse,
            state_names: state_names(m),
            tilt: 0.0,
            tilt_sc: (0.0, 1.0),
        })
    }

    /// The same walker landing on a line through the stance foot's contact point inclined `Δ`
    /// (`delta`, rad, downhill positive) against the line the stance foot stands on (module
    /// docs, "Landing on a tilted line"): one step of random slopes for round feet. The state
    /// stays in the stance line's frame (gravity at the spec's `slope`); the swing-foot guards,
    /// the heel strike's admissibility and contact point see the landing line. Refused with
    /// `step_down ≠ 0` (one ground change per step) and for `|Δ| ≥ π/4`.
    pub fn with_tilt(&self, delta: f64) -> Result<Self, WalkerError> {
        if !(delta.is_finite() && delta.abs() < std::f64::consts::FRAC_PI_4) {
            return Err(WalkerError::InvalidSpec {
                source_name: self.spec.name.clone(),
                field: "tilt".into(),
                value: delta.to_string(),
                rule: "a landing line inclined less than pi/4 rad against the stance line".into(),
            });
        }
        if self.r.step_down != 0.0 && delta != 0.0 {
            return Err(WalkerError::InvalidSpec {
                source_name: self.spec.name.clone(),
                field: "parameters.step_down".into(),
                value: self.r.step_down.to_string(),
                rule: "a tilted landing line starts at the stance foot: step_down must be 0".into(),
            });
        }
        let mut w = self.clone();
        w.tilt = delta;
        w.tilt_sc = if delta == 0.0 {
            (0.0, 1.0)
        } else {
            delta.sin_cos()
        };
        Ok(w)
    }
}

/// Refuses a step down the walker cannot take: a height of the hip's reach or more — a leg
/// length for point feet, the length from the hip to the foot's arc centre (`L − r`) for round
/// feet (chain walker docs, "Step down": the swing foot never reaches a foothold that far below,
/// nor the trailing foot one that far above).
fn check_step_down(spec: &WalkerSpec, r: &Resolved) -> Result<(), WalkerError> {
    let h = r.step_down;
    if h == 0.0 {
        return Ok(());
    }
    let leg: f64 = r.segments.iter().map(|s| s[0]).sum::<f64>() - r.foot_radius;
    let rule = if h.abs() >= leg && r.foot_radius > 0.0 {
        format!(
            "a height within (-{leg}, {leg}), less than the length from the hip to the foot's \
             arc centre (leg length − foot_radius)"
        )
    } else if h.abs() >= leg {
        format!("a height within (-{leg}, {leg}), less than one leg length")
    } else {
        return Ok(());
    };
    Err(WalkerError::InvalidSpec {
        source_name: spec.name.clone(),
        field: "parameters.step_down".into(),
        value: h.to_string(),
        rule,
    })
}

/// A link with a point mass `mp` added at `p` (link frame): composite mass, COM and inertia
/// about the new COM (parallel-axis theorem).
fn add_point_mass(l: Link, mp: f64, p: [f64; 2]) -> Link {
    let mass = l.mass + mp;
    let com = [
        (l.mass * l.com[0] + mp * p[0]) / mass,
        (l.mass * l.com[1] + mp * p[1]) / mass,
    ];
    let d2 = |a: [f64; 2]| (a[0] - com[0]).powi(2) + (a[1] - com[1]).powi(2);
    Link {
        to_next: l.to_next,
        com,
        mass,
        inertia: l.inertia + l.mass * d2(l.com) + mp * d2(p),
    }
}

/// Refuses a leg of more than [`MAX_SEGMENTS`] segments (the kernel's exact derivatives take
/// chains of at most `pdw_soa::derivatives::MAX_DOF` joints).
fn check_segment_count(spec: &WalkerSpec, m: usize) -> Result<(), WalkerError> {
    if m > MAX_SEGMENTS {
        return Err(WalkerError::InvalidSpec {
            source_name: spec.name.clone(),
            field: "segments".into(),
            value: format!("{m} segments"),
            rule: format!("at most {MAX_SEGMENTS} segments per leg"),
        });
    }
    Ok(())
}

/// The kernel chain's links (chain walker docs, "Chain, frame, coordinates and signs"): the stance
/// segments from the foot up, the top one carrying the hip mass at its upper end, then the swing
/// segments from the hip down.
fn chain_links(r: &Resolved) -> Vec<Link> {
    let m = r.segments.len();
    let n = 2 * m;
    let mut links = Vec::with_capacity(n);
    // with round feet the chain is rooted at the stance foot's arc centre, `r` above the
    // foot's lower end on the lowest segment; the swing chain ends at the swing arc centre
    let radius = r.foot_radius;
    let cut = |k: usize| if k == 0 { radius } else { 0.0 };
    for (k, s) in r.segments.iter().enumerate() {
        let [l, mass, c, cn, inertia] = *s;
        let l = l - cut(k);
        let c = c - cut(k);
        let mut link = Link {
            to_next: [0.0, l],
            com: [cn, c],
            mass,
            inertia,
        };
        if k + 1 == m && r.hip_mass > 0.0 {
            link = add_point_mass(link, r.hip_mass, [0.0, l]);
        }
        links.push(link);
    }
    for (k, s) in r.segments.iter().enumerate().rev() {
        let [l, mass, c, cn, inertia] = *s;
        links.push(Link {
            to_next: [0.0, -(l - cut(k))],
            com: [cn, -(l - c)],
            mass,
            inertia,
        });
    }
    links
}

/// The kernel chains of `links`: rooted at the stance foot (or its arc centre), and floating —
/// the same links after two prismatic base links `y`, `z` of [`FLOATING_BASE_MASS`] (module
/// docs, "Resets"). A chain the kernel rejects is an invalid spec.
fn build_chains(
    spec: &WalkerSpec,
    r: &Resolved,
    links: &[Link],
) -> Result<(Chain, Chain), WalkerError> {
    let kernel_error = |e: pdw_soa::SoaError| WalkerError::InvalidSpec {
        source_name: spec.name.clone(),
        field: "segments".into(),
        value: "the chain".into(),
        rule: format!("the kernel rejects the chain: {e}"),
    };
    let mut b = ChainBuilder::new().gravity(r.gravity).slope(r.slope);
    for l in links {
        b = b.revolute(*l);
    }
    let chain = b.build().map_err(kernel_error)?;
    let base = Link {
        to_next: [0.0, 0.0],
        com: [0.0, 0.0],
        mass: FLOATING_BASE_MASS,
        inertia: 0.0,
    };
    let mut fb = ChainBuilder::new()
        .gravity(r.gravity)
        .slope(r.slope)
        .prismatic([1.0, 0.0], base)
        .prismatic([0.0, 1.0], base);
    for l in links {
        fb = fb.revolute(*l);
    }
    let floating = fb.build().map_err(kernel_error)?;
    Ok((chain, floating))
}

/// The knees of a resolved spec as the walker's joints (chain walker docs, "Modes", "Latches with
/// holding limits"): knee `i` (foot side first) is stance joint `i + 1` and swing joint
/// `2m − 1 − i`.
struct KneeLayout {
    free_knee: Option<usize>,
    /// locked-joint mask per mode
    masks: Vec<Vec<bool>>,
    /// locked joints per mode
    locked: Vec<Vec<usize>>,
    /// knee joints of the floating chain (offset by the two base joints)
    floating_knees: Vec<usize>,
    /// per joint: a knee held by a latch
    latched: Vec<bool>,
    /// the stance joint of the trailing knee that becomes the free swing knee at heel strike,
    /// when it may release there
    trailing_free: Option<usize>,
    latch_torque: Option<f64>,
    latch_impulse: Option<f64>,
}

impl KneeLayout {
    fn of(r: &Resolved) -> Self {
        let m = r.segments.len();
        let n = 2 * m;
        let knees: Vec<usize> = (1..m).chain(m + 1..n).collect();
        let free_knee = r.free_swing.iter().position(|f| *f).map(|i| 2 * m - 1 - i);
        // knee i (foot side first) is stance joint i + 1 and swing joint 2m − 1 − i
        let mut latched = vec![false; n];
        for (i, l) in r.latched.iter().enumerate() {
            latched[i + 1] = *l;
            latched[2 * m - 1 - i] = *l;
        }
        let locked_mode = |free: Option<usize>| -> Vec<usize> {
            knees.iter().copied().filter(|k| Some(*k) != free).collect()
        };
        let locked: Vec<Vec<usize>> = match free_knee {
            Some(f) => vec![locked_mode(Some(f)), locked_mode(None)],
            None => vec![locked_mode(None)],
        };
        let masks = locked
            .iter()
            .map(|l| (0..n).map(|k| l.contains(&k)).collect())
            .collect();
        let floating_knees = knees.iter().map(|k| k + 2).collect();
        // old stance joint i + 1 becomes new swing joint 2m − 1 − i at the leg swap
        let latch_torque = r.latch_torque.iter().flatten().copied().next();
        let latch_impulse = r.latch_impulse.iter().flatten().copied().next();
        let trailing_free = free_knee
            .map(|fk| 2 * m - fk)
            .filter(|j| !latched[*j] || latch_impulse.is_some());
        Self {
            free_knee,
            masks,
            locked,
            floating_knees,
            latched,
            trailing_free,
            latch_torque,
            latch_impulse,
        }
    }
}

/// The state's names: the joint angles (`stance`, the stance knees foot side first, `hip`, the
/// swing knees hip side first; knees numbered on three-segment legs), then their `_rate`s.
fn state_names(m: usize) -> Vec<String> {
    let mut names = vec!["stance".to_string()];
    let knee_name = |side: &str, i: usize| {
        if m == 2 {
            format!("{side}_knee")
        } else {
            format!("{side}_knee{}", i + 1)
        }
    };
    names.extend((0..m - 1).map(|i| knee_name("stance", i)));
    names.push("hip".into());
    names.extend((0..m - 1).rev().map(|i| knee_name("swing", i)));
    let rates: Vec<String> = names.iter().map(|s| format!("{s}_rate")).collect();
    names.extend(rates);
    names
}
