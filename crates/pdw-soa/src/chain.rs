//! The immutable model: a planar serial chain of revolute and prismatic joints.
//!
//! # Geometry
//! Joint `k` (0-based here, joint k+1 in the seed's numbering) sits at the point `p_k`, the
//! origin of link `k`'s frame. Joint 0 sits at the base point (the world origin). Link `k`
//! carries, in its own frame: `to_next` (the vector from joint `k` to joint `k+1`; for the last
//! link it is the **tip offset**, the vector from the last joint to the tip point), the COM
//! offset `com` (from joint `k` to the link's centre of mass), its mass and its rotational
//! inertia about the COM.
//!
//! A revolute joint rotates link `k` by `q_k` relative to link `k-1` (positive from +y towards
//! +z). A prismatic joint translates link `k` by `q_k · axis` relative to link `k-1`, with the
//! unit `axis` expressed in link `k-1`'s frame (which is also link `k`'s orientation); the joint
//! point then is `p_k = p_{k-1} + R_{k-1} (to_next_{k-1} + q_k axis)`. At `q = 0` every link
//! frame is aligned with the world (slope) frame.
//!
//! # World frame and gravity
//! y runs along the slope, **pointing downhill**; z is normal to the slope, pointing up. Gravity
//! `g` (m/s²) on a slope of angle `γ` has slope-frame components `(g sin γ, −g cos γ)`. It enters
//! as the fictitious base acceleration (seed eq. 3.12) `a_b = [0, −g sin γ, g cos γ]`. (The seed
//! writes `+g sin γ`, i.e. its y axis points uphill.)

use crate::error::SoaError;

/// Kind of a joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JointKind {
    /// Rotation about x (the plane normal); `H = [1, 0, 0]` (seed eq. 3.4).
    Revolute,
    /// Translation along a unit axis `[a_y, a_z]` given in the parent link's frame;
    /// `H = [0, R a]` (seed eq. 3.5 for an arbitrary in-plane axis).
    Prismatic { axis: [f64; 2] },
}

/// Inertial and geometric parameters of one link (all in the link's own frame, SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Link {
    /// Vector from this link's joint to the next joint (m); for the last link: the tip offset.
    pub to_next: [f64; 2],
    /// Vector from this link's joint to its centre of mass (m).
    pub com: [f64; 2],
    /// Mass (kg), > 0.
    pub mass: f64,
    /// Rotational inertia about the COM (kg m²), ≥ 0.
    pub inertia: f64,
}

impl Link {
    /// A uniform slender rod from the joint along `dir` (its length is `|dir|`): COM at the
    /// middle, inertia `m L² / 12` about the COM, next joint (or tip) at its far end.
    pub fn rod(dir: [f64; 2], mass: f64) -> Self {
        let l2 = dir[0] * dir[0] + dir[1] * dir[1];
        Link {
            to_next: dir,
            com: [0.5 * dir[0], 0.5 * dir[1]],
            mass,
            inertia: mass * l2 / 12.0,
        }
    }
}

/// Validating builder of a [`Chain`].
#[derive(Debug, Clone)]
pub struct ChainBuilder {
    kinds: Vec<JointKind>,
    links: Vec<Link>,
    gravity: f64,
    slope: f64,
}

impl Default for ChainBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl ChainBuilder {
    /// An empty chain with `g = 9.81` m/s² and slope `γ = 0`.
    pub fn new() -> Self {
        ChainBuilder {
            kinds: Vec::new(),
            links: Vec::new(),
            gravity: 9.81,
            slope: 0.0,
        }
    }
    /// Gravity magnitude `g` (m/s²; 0 for no gravity).
    pub fn gravity(mut self, g: f64) -> Self {
        self.gravity = g;
        self
    }
    /// Slope angle `γ` (rad; positive: y points downhill).
    pub fn slope(mut self, gamma: f64) -> Self {
        self.slope = gamma;
        self
    }
    /// Append a joint of the given kind and the link it moves.
    pub fn joint(mut self, kind: JointKind, link: Link) -> Self {
        self.kinds.push(kind);
        self.links.push(link);
        self
    }
    /// Append a revolute joint and its link.
    pub fn revolute(self, link: Link) -> Self {
        self.joint(JointKind::Revolute, link)
    }
    /// Append a prismatic joint (axis in the parent frame) and its link.
    pub fn prismatic(self, axis: [f64; 2], link: Link) -> Self {
        self.joint(JointKind::Prismatic { axis }, link)
    }

    /// Validate and build.
    ///
    /// # Errors
    /// [`SoaError::EmptyChain`], [`SoaError::NonPositiveMass`], [`SoaError::NegativeInertia`],
    /// [`SoaError::NonFinite`], [`SoaError::ZeroPrismaticAxis`],
    /// [`SoaError::DegenerateRevoluteInertia`].
    pub fn build(self) -> Result<Chain, SoaError> {
        Chain::new(self.kinds, self.links, self.gravity, self.slope)
    }
}

fn finite(link: Option<usize>, what: &'static str, value: f64) -> Result<(), SoaError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(SoaError::NonFinite { link, what, value })
    }
}

/// Immutable planar chain model. Build it with [`ChainBuilder`] or [`Chain::new`].
#[derive(Debug, Clone)]
pub struct Chain {
    pub(crate) kinds: Vec<JointKind>,
    pub(crate) links: Vec<Link>,
    /// 1.0 for prismatic joints, 0.0 for revolute (used by the shared step functions).
    pub(crate) prismatic: Vec<bool>,
    /// Unit prismatic axes in the parent frame (`[0, 0]` for revolute joints).
    pub(crate) axis: Vec<[f64; 2]>,
    /// Rotational inertia about the joint point, `I_c + m |c|²` (kg m²).
    pub(crate) j_joint: Vec<f64>,
    pub(crate) gravity: f64,
    pub(crate) slope: f64,
    /// Base acceleration `a_b = [0, −g sin γ, g cos γ]` (seed eq. 3.12, y downhill).
    pub(crate) base_acc: [f64; 3],
}

impl Chain {
    /// Validate and build a chain from joint kinds and links (same length), gravity `g` and
    /// slope `γ`. See [`ChainBuilder::build`] for the errors.
    pub fn new(
        kinds: Vec<JointKind>,
        links: Vec<Link>,
        gravity: f64,
        slope: f64,
    ) -> Result<Self, SoaError> {
        if kinds.is_empty() && links.is_empty() {
            return Err(SoaError::EmptyChain);
        }
        if kinds.len() != links.len() {
            return Err(SoaError::DimensionMismatch {
                what: "links (one per joint)",
                expected: kinds.len().to_string(),
                got: links.len().to_string(),
            });
        }
        finite(None, "gravity", gravity)?;
        finite(None, "slope", slope)?;
        let n = kinds.len();
        let mut prismatic = Vec::with_capacity(n);
        let mut axis = Vec::with_capacity(n);
        let mut j_joint = Vec::with_capacity(n);
        for (k, (kind, link)) in kinds.iter().zip(&links).enumerate() {
            let l = Some(k);
            finite(l, "to_next[0]", link.to_next[0])?;
            finite(l, "to_next[1]", link.to_next[1])?;
            finite(l, "com[0]", link.com[0])?;
            finite(l, "com[1]", link.com[1])?;
            finite(l, "mass", link.mass)?;
            finite(l, "inertia", link.inertia)?;
            if link.mass <= 0.0 {
                return Err(SoaError::NonPositiveMass {
                    link: k,
                    mass: link.mass,
                });
            }
            if link.inertia < 0.0 {
                return Err(SoaError::NegativeInertia {
                    link: k,
                    inertia: link.inertia,
                });
            }
            let jj =
                link.inertia + link.mass * (link.com[0] * link.com[0] + link.com[1] * link.com[1]);
            j_joint.push(jj);
            match *kind {
                JointKind::Revolute => {
                    if jj <= 0.0 {
                        return Err(SoaError::DegenerateRevoluteInertia { link: k });
                    }
                    prismatic.push(false);
                    axis.push([0.0, 0.0]);
                }
                JointKind::Prismatic { axis: a } => {
                    finite(l, "axis[0]", a[0])?;
                    finite(l, "axis[1]", a[1])?;
                    let norm = (a[0] * a[0] + a[1] * a[1]).sqrt();
                    if norm == 0.0 {
                        return Err(SoaError::ZeroPrismaticAxis {
                            link: k,
                            ay: a[0],
                            az: a[1],
                        });
                    }
                    prismatic.push(true);
                    axis.push([a[0] / norm, a[1] / norm]);
                }
            }
        }
        let (s, c) = slope.sin_cos();
        Ok(Chain {
            kinds,
            links,
            prismatic,
            axis,
            j_joint,
            gravity,
            slope,
            base_acc: [0.0, -gravity * s, gravity * c],
        })
    }

    /// Number of joints (= degrees of freedom) `n`.
    pub fn dof(&self) -> usize {
        self.kinds.len()
    }
    /// Joint kinds, base to tip.
    pub fn kinds(&self) -> &[JointKind] {
        &self.kinds
    }
    /// Links, base to tip.
    pub fn links(&self) -> &[Link] {
        &self.links
    }
    /// Gravity magnitude `g` (m/s²).
    pub fn gravity(&self) -> f64 {
        self.gravity
    }
    /// Slope angle `γ` (rad).
    pub fn slope(&self) -> f64 {
        self.slope
    }
    /// Base acceleration `[0, −g sin γ, g cos γ]` that represents gravity (seed eq. 3.12).
    pub fn base_acceleration(&self) -> [f64; 3] {
        self.base_acc
    }
    /// Total mass (kg).
    pub fn total_mass(&self) -> f64 {
        self.links.iter().map(|l| l.mass).sum()
    }
    /// A copy of this chain with other gravity and slope.
    pub fn with_gravity(&self, gravity: f64, slope: f64) -> Result<Chain, SoaError> {
        Chain::new(self.kinds.clone(), self.links.clone(), gravity, slope)
    }
}
