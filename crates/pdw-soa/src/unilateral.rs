//! Plastic impacts with unilateral contacts and joint stops, solved as a linear complementarity
//! problem, with the exact Jacobian of the resulting map.
//!
//! # The impact problem
//! A chain (in practice a *floating* chain: prismatic `y`, `z` at the base, then the walker's
//! joints, see [`crate::rolling_base_dynamics`]) meets, in one instant, a set of velocity
//! constraints — *items*, each one or two rows of `A`:
//!
//! - [`ImpactRow::BaseContact`]: the foot at the base, an arc of radius `r` centred on the base
//!   point and fixed to the first revolute link (joint 2), touching the slope `r` below its
//!   centre. Its contact point moves at `(ẏ + r θ̇₂, ż)` (tangential, normal): two rows.
//!   `r = 0` is a point foot at the base.
//! - [`ImpactRow::TipContact`]: the point at a fixed world offset from the tip (a round foot's
//!   lowest point below its arc centre, the tip): its linear Jacobian, two rows (seed eq. 2.24).
//! - [`ImpactRow::Stop`]: a joint stop, one row `s e_kᵀ`; the stop allows `s q̇_k ≥ 0` (a knee's
//!   hyper-extension stop allows flexion only).
//!
//! The impulse `λ` of the active rows acts on the chain as `Aᵀλ` (for a contact: the ground's
//! impulse on the foot, `[tangential, normal]`; for a stop: the stop's angular impulse towards
//! its allowed direction). Plastic impact (Glocker & Pfeiffer 1992; Brogliato, *Nonsmooth
//! Mechanics*, ch. 5; Hurmuzlu & Marghitu 1994 for walkers):
//!
//! ```text
//! 𝓜 (q̇⁺ − q̇⁻) = A_aᵀ λ_a,    A_a q̇⁺ = 0,
//! λ_a = −(A_a 𝓜⁻¹ A_aᵀ)⁻¹ A_a q̇⁻,    q̇⁺ = q̇⁻ + 𝓜⁻¹ A_aᵀ λ_a
//! ```
//! for the active set `a`. A *unilateral* item pushes only and may release (complementarity,
//! on its normal row for a contact, with its tangential row going along):
//!
//! ```text
//! λ_n ≥ 0,   v_n⁺ ≥ 0,   λ_n v_n⁺ = 0
//! ```
//! Items the event itself closes (the striking foot, the striking knee) are *bilateral*: always
//! active, their sign only reported. For stops (one row each) and linearly independent rows,
//! `A 𝓜⁻¹ Aᵀ` is positive definite, the problem is a P-matrix LCP and its solution is unique
//! (Cottle, Pang & Stone, *The Linear Complementarity Problem*, thm. 3.3.7). A sticking contact
//! whose tangential row holds and releases with its normal one is not of that form, and an
//! impact can then have no consistent active set (the solver says so:
//! [`ImpactSolution::complementary`] is false and the least-violating set is used). With at
//! most a handful of unilateral items the problem is solved exactly by enumerating active sets
//! (all active first). The kinetic energy lost is
//! `½ Δq̇ᵀ 𝓜 Δq̇ ≥ 0` (the active rows vanish after the impact, so no cross term).
//! The tangential rows assume sticking; the friction the contact needs, `|λ_t / λ_n|`, is the
//! caller's to check against a friction coefficient.
//!
//! # Derivatives
//! For a fixed active set the map is the equality-constrained impact of [`crate::impact`] with
//! these rows, linear in `q̇⁻`: `∂q̇⁺/∂q̇⁻ = I − X S⁻¹ A`, and `∂q̇⁺/∂q` by running the whole
//! computation in dual numbers seeded on `q` (kinematics, `𝓜` by the composite-rigid-body
//! steps, the rows, two `LDLᵀ` solves). The active set is locally constant away from the
//! switching surfaces (a `λ` or a `v⁺` exactly zero), where the map is continuous but not
//! differentiable.

#![allow(clippy::needless_range_loop)]

use crate::chain::Chain;
use crate::derivatives::{
    by_dof, check_dof, check_floating, impact_in_duals, kin, ldl, ldl_solve, mass_matrix,
    positions, Kin, Mat8, MAX_DOF,
};
use crate::dual::{Dual, Scalar};
use crate::error::{check_len, SoaError};

/// Largest number of items of one impact problem.
pub const MAX_ITEMS: usize = 6;

/// One constraint of an impact (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ImpactRow {
    /// The round (radius `radius`, 0: point) foot at the base of a floating chain: rows
    /// `[1, 0, r, 0…]` (tangential) and `[0, 1, 0…]` (normal).
    BaseContact { radius: f64 },
    /// The point at world `offset` from the tip: the linear Jacobian's two rows.
    TipContact { offset: [f64; 2] },
    /// A stop on joint `joint` allowing `sign · q̇_joint ≥ 0` (`sign` is ±1).
    Stop { joint: usize, sign: f64 },
}

impl ImpactRow {
    fn rows(&self) -> usize {
        match self {
            ImpactRow::Stop { .. } => 1,
            _ => 2,
        }
    }
}

/// An item of the impact problem: a constraint and whether it may release.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpactItem {
    pub row: ImpactRow,
    /// Pushes only and may release (complementarity); `false`: always active.
    pub unilateral: bool,
}

/// The solution for one item.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ItemResult {
    /// Holds after the impact.
    pub active: bool,
    /// Impulse: `[tangential, normal]` for a contact (the ground's impulse on the foot), `[λ, 0]`
    /// for a stop (towards its allowed direction); zeros where not active.
    pub impulse: [f64; 2],
    /// Velocity after the impact: `[tangential, normal]` of the contact point, `[s q̇_k⁺, 0]` for
    /// a stop (zero where active, up to roundoff).
    pub rate: [f64; 2],
}

/// The solution of an impact problem.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpactSolution {
    /// Per item, in the order given.
    pub items: [ItemResult; MAX_ITEMS],
    /// Number of items.
    pub n_items: usize,
    /// Kinetic energy lost, `½ Δq̇ᵀ 𝓜 Δq̇` (≥ 0).
    pub energy_lost: f64,
    /// The active set satisfies every sign condition (always true when the active set was
    /// solved for by complementarity and a solution exists; with `hold` given, whether the
    /// imposed set is consistent).
    pub complementary: bool,
}

/// Solves the impact problem of `items` for the chain at `q` with pre-impact rates `qd`
/// (length `n`), writing `q̇⁺` into `qd_post` and, if given, the Jacobian
/// `[∂q̇⁺/∂q | ∂q̇⁺/∂q̇⁻]` (`n × 2n` row-major) into `jac`. Without `jac` no derivative is
/// computed (the same value arithmetic in duals of width 0: the same bits, several times
/// cheaper). No call allocates.
///
/// `hold = None` solves for the active set by complementarity (module docs); `hold = Some(mask)`
/// imposes the active set `mask` (one flag per item; bilateral items must be `true`) — the map a
/// model applies when it holds a constraint by assumption; [`ImpactSolution::complementary`]
/// then says whether that is consistent.
///
/// # Errors
/// [`SoaError::DimensionMismatch`] for wrong lengths, more than [`MAX_ITEMS`] items, more rows
/// than joints, a base contact on a chain that is not floating, or `n > MAX_DOF`;
/// [`SoaError::InvalidJointIndex`] for a stop beyond the chain;
/// [`SoaError::SingularConstraint`] if the imposed active set (or, solving by complementarity,
/// every candidate) has dependent rows; [`SoaError::MassMatrixNotPositiveDefinite`].
pub fn unilateral_impact(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    items: &[ImpactItem],
    hold: Option<&[bool]>,
    qd_post: &mut [f64],
    jac: Option<&mut [f64]>,
) -> Result<ImpactSolution, SoaError> {
    let n = chain.dof();
    check_arguments(chain, q, qd, items, hold, qd_post, jac.as_deref())?;
    let k64 = kin::<f64>(chain, q, None);
    let mut mass = [[0.0; MAX_DOF]; MAX_DOF];
    mass_matrix(chain, &k64, &mut mass);
    let all_rows = item_rows(chain, &k64, items);
    let mut mfac = mass;
    ldl(&mut mfac, n).ok_or(SoaError::MassMatrixNotPositiveDefinite)?;
    let set = ActiveSet {
        n,
        items,
        all: &all_rows,
        mass: &mass,
        mfac: &mfac,
        qd,
    };
    // the chosen set's violation: known from the search, computed for an imposed set
    let (chosen_at, violated) = match hold {
        Some(h) => set.imposed(h)?,
        None => set.search()?,
    };
    let chosen = &chosen_at[..items.len()];
    let complementary = violated.ok_or(SoaError::SingularConstraint {
        what: "A 𝓜⁻¹ Aᵀ (impact)",
    })? == 0.0;
    // the map, and its Jacobian if asked for, for the chosen set (without it, duals of width
    // 0: the value arithmetic of every width, hence the same bits, without the derivatives)
    let mut lam = [0.0; MAX_DOF];
    match jac {
        Some(j) => by_dof!(
            n,
            1,
            solve_w(chain, q, qd, items, chosen, qd_post, &mut lam, Some(j))
        )?,
        None => solve_w::<0>(chain, q, qd, items, chosen, qd_post, &mut lam, None)?,
    }
    let mut sol = set.results(chosen, &lam, qd_post);
    sol.complementary = complementary;
    Ok(sol)
}

/// The argument checks of [`unilateral_impact`], in the order its errors are reported (lengths,
/// the item count, each item's joint, sign and radius, the hold mask's and the Jacobian's
/// lengths).
fn check_arguments(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    items: &[ImpactItem],
    hold: Option<&[bool]>,
    qd_post: &[f64],
    jac: Option<&[f64]>,
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_dof(n)?;
    check_len("q", n, q.len())?;
    check_len("qd_minus", n, qd.len())?;
    check_len("qd_plus", n, qd_post.len())?;
    if items.is_empty() || items.len() > MAX_ITEMS {
        return Err(SoaError::DimensionMismatch {
            what: "impact items",
            expected: format!("1..={MAX_ITEMS}"),
            got: items.len().to_string(),
        });
    }
    for it in items {
        match it.row {
            ImpactRow::Stop { joint, sign } => {
                if joint >= n {
                    return Err(SoaError::InvalidJointIndex { index: joint, n });
                }
                if sign.abs() != 1.0 {
                    return Err(SoaError::DimensionMismatch {
                        what: "stop sign",
                        expected: "+1 or -1".into(),
                        got: sign.to_string(),
                    });
                }
            }
            ImpactRow::BaseContact { radius } => {
                check_floating(chain)?;
                if !(radius.is_finite() && radius >= 0.0) {
                    return Err(SoaError::DimensionMismatch {
                        what: "foot radius",
                        expected: "finite and >= 0".into(),
                        got: radius.to_string(),
                    });
                }
            }
            ImpactRow::TipContact { .. } => {}
        }
    }
    if let Some(h) = hold {
        check_len("hold", items.len(), h.len())?;
    }
    if let Some(j) = jac {
        check_len("jac (n x 2n)", 2 * n * n, j.len())?;
    }
    Ok(())
}

/// An impact problem on the values: the items, every item's rows, the mass matrix 𝓜 and its
/// LDLᵀ factors, the pre-impact rates.
struct ActiveSet<'a> {
    n: usize,
    items: &'a [ImpactItem],
    /// Every item's rows ([`item_rows`]).
    all: &'a Mat8<f64>,
    mass: &'a Mat8<f64>,
    mfac: &'a Mat8<f64>,
    qd: &'a [f64],
}

impl ActiveSet<'_> {
    /// The imposed active set `h` and its violation (`None`: dependent rows); bilateral items
    /// must be held.
    fn imposed(&self, h: &[bool]) -> Result<([bool; MAX_ITEMS], Option<f64>), SoaError> {
        let items = self.items;
        for (i, it) in items.iter().enumerate() {
            if !it.unilateral && !h[i] {
                return Err(SoaError::DimensionMismatch {
                    what: "hold mask (bilateral items must be held)",
                    expected: "true".into(),
                    got: format!("false at item {i}"),
                });
            }
        }
        let mut chosen_at = [false; MAX_ITEMS];
        chosen_at[..items.len()].copy_from_slice(h);
        let v = violation(self.n, items, self.all, self.mass, self.mfac, h, self.qd);
        Ok((chosen_at, v))
    }

    /// The active set by complementarity: every subset of the unilateral items (their indices
    /// on the stack: no call allocates), all of them active first, then fewer; the first
    /// without violation, else the least violated. Errors when every candidate has dependent
    /// rows.
    fn search(&self) -> Result<([bool; MAX_ITEMS], Option<f64>), SoaError> {
        let items = self.items;
        let (mut uni_at, mut n_uni) = ([0usize; MAX_ITEMS], 0);
        for (i, it) in items.iter().enumerate() {
            if it.unilateral {
                uni_at[n_uni] = i;
                n_uni += 1;
            }
        }
        let uni = &uni_at[..n_uni];
        let mut best: Option<(f64, [bool; MAX_ITEMS])> = None;
        for code in (0..1usize << uni.len()).rev() {
            let mut act = [true; MAX_ITEMS];
            for (b, &i) in uni.iter().enumerate() {
                act[i] = code >> b & 1 == 1;
            }
            let act_items = &act[..items.len()];
            let Some(v) = violation(
                self.n, items, self.all, self.mass, self.mfac, act_items, self.qd,
            ) else {
                continue;
            };
            if v == 0.0 {
                best = Some((0.0, act));
                break;
            }
            if best.as_ref().is_none_or(|b| v < b.0) {
                best = Some((v, act));
            }
        }
        match best {
            Some((v, a)) => Ok((a, Some(v))),
            None => Err(SoaError::SingularConstraint {
                what: "A 𝓜⁻¹ Aᵀ (every active set of the impact)",
            }),
        }
    }

    /// Per-item results on the values (activity, impulse from the chosen set's multipliers
    /// `lam`, post-impact rates of the item's rows) and the kinetic energy lost,
    /// `½ Δq̇ᵀ 𝓜 Δq̇`; `complementary` is left false for the caller.
    fn results(&self, chosen: &[bool], lam: &[f64], qd_post: &[f64]) -> ImpactSolution {
        let (n, items, qd) = (self.n, self.items, self.qd);
        let mut sol = ImpactSolution {
            items: [ItemResult::default(); MAX_ITEMS],
            n_items: items.len(),
            energy_lost: 0.0,
            complementary: false,
        };
        let (mut r, mut a) = (0, 0);
        for (i, it) in items.iter().enumerate() {
            let nr = it.row.rows();
            let res = &mut sol.items[i];
            res.active = chosen[i];
            for k in 0..nr {
                res.rate[k] = dot(&self.all[r + k][..n], qd_post);
                if chosen[i] {
                    res.impulse[k] = lam[a + k];
                }
            }
            if chosen[i] {
                a += nr;
            }
            r += nr;
        }
        let mut e = 0.0;
        for i in 0..n {
            for k in 0..n {
                e += (qd_post[i] - qd[i]) * self.mass[i][k] * (qd_post[k] - qd[k]);
            }
        }
        sol.energy_lost = 0.5 * e;
        sol
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Every item's rows (all items, in order; a contact's tangential row first).
fn item_rows<T: Scalar>(chain: &Chain, kin: &Kin<T>, items: &[ImpactItem]) -> Mat8<T> {
    let n = chain.dof();
    let zero = T::cst(0.0);
    let mut a = [[zero; MAX_DOF]; MAX_DOF];
    let mut r = 0;
    for it in items {
        match it.row {
            ImpactRow::BaseContact { radius } => {
                a[r][0] = T::cst(1.0);
                a[r][2] = T::cst(radius);
                a[r + 1][1] = T::cst(1.0);
            }
            ImpactRow::TipContact { offset } => {
                let (p, t) = positions(n, kin);
                let t = [t[0] + T::cst(offset[0]), t[1] + T::cst(offset[1])];
                for k in 0..n {
                    if chain.prismatic[k] {
                        a[r][k] = kin.hy[k];
                        a[r + 1][k] = kin.hz[k];
                    } else {
                        a[r][k] = -(t[1] - p[k][1]);
                        a[r + 1][k] = t[0] - p[k][0];
                    }
                }
            }
            ImpactRow::Stop { joint, sign } => a[r][joint] = T::cst(sign),
        }
        r += it.row.rows();
        if r > MAX_DOF {
            break;
        }
    }
    a
}

/// The active rows of `act` packed into the leading rows; returns their count (`None` if more
/// rows than joints).
fn active_rows(
    n: usize,
    items: &[ImpactItem],
    all: &Mat8<f64>,
    act: &[bool],
) -> Option<(Mat8<f64>, usize)> {
    let mut a = [[0.0; MAX_DOF]; MAX_DOF];
    let (mut r, mut m) = (0, 0);
    for (i, it) in items.iter().enumerate() {
        let nr = it.row.rows();
        if act[i] {
            if m + nr > n {
                return None;
            }
            a[m..m + nr].copy_from_slice(&all[r..r + nr]);
            m += nr;
        }
        r += nr;
    }
    Some((a, m))
}

/// Total sign violation of the unilateral items under the active set `act` (0 when
/// complementary), relative to the scales of the impulses and of the pre-impact rates; `None`
/// for dependent rows.
#[allow(clippy::too_many_arguments)]
fn violation(
    n: usize,
    items: &[ImpactItem],
    all: &Mat8<f64>,
    mass: &Mat8<f64>,
    mfac: &Mat8<f64>,
    act: &[bool],
    qd: &[f64],
) -> Option<f64> {
    let (a, m) = active_rows(n, items, all, act)?;
    let mut lam = [0.0; MAX_DOF];
    let mut xt = [[0.0; MAX_DOF]; MAX_DOF];
    if m > 0 {
        for i in 0..m {
            xt[i] = a[i];
            ldl_solve(mfac, n, &mut xt[i][..n]);
        }
        let mut s = [[0.0; MAX_DOF]; MAX_DOF];
        for i in 0..m {
            for j in 0..=i {
                s[i][j] = dot(&a[i][..n], &xt[j][..n]);
            }
            lam[i] = -dot(&a[i][..n], qd);
        }
        let (dmin, dmax) = ldl(&mut s, m)?;
        if dmin <= 1e-10 * dmax {
            return None;
        }
        ldl_solve(&s, m, &mut lam[..m]);
    }
    let mut v = [0.0; MAX_DOF];
    for k in 0..n {
        v[k] = qd[k];
        for i in 0..m {
            v[k] += xt[i][k] * lam[i];
        }
    }
    // scales: impulses by the largest |λ| (or, without any, by |𝓜 q̇⁻|), rates by |A q̇⁻|
    let mut vscale = 0.0f64;
    let total_rows: usize = items.iter().map(|it| it.row.rows()).sum();
    for r in 0..total_rows.min(MAX_DOF) {
        vscale = vscale.max(dot(&all[r][..n], qd).abs());
    }
    let mut lscale = lam[..m].iter().fold(0.0f64, |s, l| s.max(l.abs()));
    if lscale == 0.0 {
        for i in 0..n {
            lscale = lscale.max(dot(&mass[i][..n], qd).abs());
        }
    }
    let (tl, tv) = (1e-12 * lscale, 1e-12 * vscale);
    let mut viol = 0.0;
    let (mut r, mut ai) = (0, 0);
    for (i, it) in items.iter().enumerate() {
        let nr = it.row.rows();
        // the sign row: a contact's normal (second) row, a stop's only row
        let sr = nr - 1;
        if act[i] {
            // bilateral items hold by definition: only their sign is reported, by the caller
            let l = if it.unilateral { lam[ai + sr] } else { 0.0 };
            if l < -tl {
                viol += -l / lscale.max(f64::MIN_POSITIVE);
            }
            ai += nr;
        } else {
            let rate = dot(&all[r + sr][..n], &v[..n]);
            if rate < -tv {
                viol += -rate / vscale.max(f64::MIN_POSITIVE);
            }
        }
        r += nr;
    }
    Some(viol)
}

/// The impact map for the active set `act` in duals of width `W = n` seeded on `q`: `q̇⁺`, the
/// active impulses `λ` (packed) and the Jacobian (module docs).
#[allow(clippy::too_many_arguments)]
fn solve_w<const W: usize>(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    items: &[ImpactItem],
    act: &[bool],
    qd_post: &mut [f64],
    lam_out: &mut [f64],
    jac: Option<&mut [f64]>,
) -> Result<(), SoaError> {
    let n = chain.dof();
    let zero = Dual::<W>::constant(0.0);
    let mut qx = [zero; MAX_DOF];
    for k in 0..n {
        // seeded on q when the Jacobian is asked for (W = n), constants for the values (W = 0)
        qx[k] = if k < W {
            Dual::variable(q[k], k)
        } else {
            Dual::constant(q[k])
        };
    }
    let kd = kin(chain, &qx[..n], None);
    let mut mm = [[zero; MAX_DOF]; MAX_DOF];
    mass_matrix(chain, &kd, &mut mm);
    ldl(&mut mm, n).ok_or(SoaError::MassMatrixNotPositiveDefinite)?;
    let all = item_rows(chain, &kd, items);
    // pack the active rows
    let mut a = [[zero; MAX_DOF]; MAX_DOF];
    let (mut r, mut m) = (0, 0);
    for (i, it) in items.iter().enumerate() {
        let nr = it.row.rows();
        if act[i] {
            if m + nr > n {
                return Err(SoaError::DimensionMismatch {
                    what: "active impact rows (at most n)",
                    expected: format!("<= {n}"),
                    got: (m + nr).to_string(),
                });
            }
            a[m..m + nr].copy_from_slice(&all[r..r + nr]);
            m += nr;
        }
        r += nr;
    }
    let w2 = 2 * n;
    if m == 0 {
        qd_post[..n].copy_from_slice(&qd[..n]);
        if let Some(jac) = jac {
            jac[..n * w2].fill(0.0);
            for k in 0..n {
                jac[k * w2 + n + k] = 1.0;
            }
        }
        return Ok(());
    }
    // Λ = (A 𝓜⁻¹ Aᵀ)⁻¹ A q̇⁻, q̇⁺ = q̇⁻ − 𝓜⁻¹AᵀΛ: the impulse on the chain is λ = −Λ
    let (dmin, dmax) = impact_in_duals(n, m, &mm, &a, qd, qd_post, lam_out, jac)?;
    if dmin <= 1e-10 * dmax {
        return Err(SoaError::SingularConstraint {
            what: "A 𝓜⁻¹ Aᵀ (impact)",
        });
    }
    for l in lam_out[..m].iter_mut() {
        *l = -*l;
    }
    Ok(())
}
