//! Exact first derivatives of forward dynamics, of the plastic impact maps and of the tip
//! position, by forward-mode dual numbers ([`crate::dual::Dual`]) through the kernel's own
//! per-link step functions ([`crate::spatial`]), not by finite differences.
//!
//! # Forward dynamics (seed §3.4 for the locked joints)
//! Let `ID(q, q̇, q̈)` be inverse dynamics (RNEA, seed eq. 2.57–2.62, no tip force). Forward
//! dynamics with the joints `l` locked as pseudo joints and the others `f` free is the solution of
//!
//! ```text
//! ID_f(q, q̇, q̈) = τ_f,    q̈_l = 0
//! ```
//! (`𝓜_ff q̈_f = τ_f − C_f`, the Schur-complement form of seed eq. 3.23). RNEA is linear in `q̈`,
//! so `∂ID/∂q̈ = 𝓜`; differentiating the identity along any input `x ∈ {q, q̇}` gives
//! (Carpentier & Mansard 2018, "Analytical derivatives of rigid body dynamics algorithms", RSS:
//! the derivatives of forward dynamics are `−𝓜⁻¹` times those of inverse dynamics evaluated at
//! the forward-dynamics solution)
//!
//! ```text
//! ∂q̈_f/∂x = −𝓜_ff⁻¹ ∂ID_f/∂x |_{q̈ = FD(q, q̇, τ)},    ∂q̈_l/∂x = 0.
//! ```
//! The value `q̈` is the kernel's articulated-body recursion ([`crate::aba`],
//! [`crate::pseudo_joint_dynamics`]) run on the same step functions, so it equals theirs bit for
//! bit. Then **one** RNEA pass in duals of width `3n`, seeded on `(q, q̇, q̈)` at that `q̈`,
//! returns `∂ID/∂q`, `∂ID/∂q̇` and `𝓜 = ∂ID/∂q̈` at once; an `LDLᵀ` factorisation of `𝓜_ff`
//! (on the stack) gives the Jacobians.
//!
//! # Impacts
//! The plastic impact of [`crate::impact`] is `q̇⁺ = q̇⁻ − X Λ` with `X = 𝓜⁻¹Aᵀ`,
//! `S = A X`, `Λ = S⁻¹ A q̇⁻`; `A` holds the linear tip-Jacobian rows (heel strike) and/or
//! `e_kᵀ` for each locked joint `k`. The map is linear in `q̇⁻`, so
//! `∂q̇⁺/∂q̇⁻ = I − X S⁻¹ A`, and `∂q̇⁺/∂q` follows from running the whole computation in duals
//! of width `n` seeded on `q`: kinematics and the tip Jacobian by the generic kinematic steps,
//! `𝓜(q)` by the generic composite-rigid-body steps of [`crate::crba`], the two solves by
//! `LDLᵀ` in duals.
//!
//! The value `q̇⁺` is computed apart, in `f64`, by the kernel's operations in the kernel's order
//! (the same kinematics and CRBA steps, faer's `LLᵀ` on stack storage): it equals
//! [`crate::tip_impact`] / [`crate::joint_lock_impact`] bit for bit, and a configuration is
//! rejected as singular exactly when the kernel rejects it. (Two backward-stable evaluations
//! of `q̇⁺` in a different order differ by `~ε κ`, up to `2e-13` relative on random 8-joint
//! chains; the value does not depend on the order chosen for the derivatives.)
//!
//! # Sizes, layout, memory
//! Chains of `1 ≤ n ≤` [`MAX_DOF`] joints; the dual width is chosen from `n` (`3n` for forward
//! dynamics, `n` otherwise), so a small chain pays for its own size only. Jacobians are written
//! row-major: entry `(i, j)` of an `r × c` Jacobian is `jac[i * c + j]`. Everything lives on the
//! stack; no call allocates (the error values of a failed call aside).

// The generic helpers mirror the kernel's index loops over several per-link arrays.
#![allow(clippy::needless_range_loop)]

use std::mem::MaybeUninit;

use faer::dyn_stack::MemStack;
use faer::linalg::cholesky::llt;
use faer::{Conj, MatMut, Par};

use crate::aba::{aba_recursion, one_lane_back, one_lane_fwd, AbaLanes};
use crate::chain::Chain;
use crate::dual::{Dual, Scalar};
use crate::error::{check_len, SoaError};
use crate::rnea::{one_lane_rnea_back, one_lane_rnea_fwd, rnea_recursion, RneaLanes};
use crate::spatial;
use crate::workspace::{kin_recursion, lanes_tip, one_lane_kin, KinLanes, KinLink};

/// Largest number of joints the derivative routines accept.
pub const MAX_DOF: usize = 8;

pub(crate) type Vec8<T> = [T; MAX_DOF];
pub(crate) type Mat8<T> = [[T; MAX_DOF]; MAX_DOF];

// ---------------------------------------------------------------------------------------------
// Generic kinematics and RNEA over stack arrays (the passes of workspace::kin_pass and
// rnea::rnea_passes, on any Scalar).
// ---------------------------------------------------------------------------------------------

/// Pass-1 quantities of every link (fields as in [`crate::Workspace`]).
#[derive(Clone, Copy)]
pub(crate) struct Kin<T> {
    pub(crate) w: Vec8<T>,
    pub(crate) dy: Vec8<T>,
    pub(crate) dz: Vec8<T>,
    pub(crate) hy: Vec8<T>,
    pub(crate) hz: Vec8<T>,
    pub(crate) cy: Vec8<T>,
    pub(crate) cz: Vec8<T>,
    pub(crate) ay: Vec8<T>,
    pub(crate) az: Vec8<T>,
    pub(crate) by: Vec8<T>,
    pub(crate) bz: Vec8<T>,
    pub(crate) tip_d: [T; 2],
}

/// Link angles, levers, world COM offsets, prismatic axes, rates and bias terms, base to tip:
/// the stack instance of the kernel's kinematic pass ([`kin_recursion`]) on any [`Scalar`].
/// `qd = None` means zero joint rates. `q` (and `qd`) have length `chain.dof() ≤ MAX_DOF`.
pub(crate) fn kin<T: Scalar>(chain: &Chain, q: &[T], qd: Option<&[T]>) -> Kin<T> {
    let zero = T::cst(0.0);
    let mut lanes = StackKin {
        out: Kin {
            w: [zero; MAX_DOF],
            dy: [zero; MAX_DOF],
            dz: [zero; MAX_DOF],
            hy: [zero; MAX_DOF],
            hz: [zero; MAX_DOF],
            cy: [zero; MAX_DOF],
            cz: [zero; MAX_DOF],
            ay: [zero; MAX_DOF],
            az: [zero; MAX_DOF],
            by: [zero; MAX_DOF],
            bz: [zero; MAX_DOF],
            tip_d: [zero; 2],
        },
        q,
        qd,
        prev: [zero, zero, T::cst(1.0), zero],
    };
    kin_recursion(chain, &mut lanes);
    lanes.out
}

/// One lane of the kinematic pass into the stack arrays of [`Kin`], the previous link's
/// `θ, sin, cos, ω` carried in `prev`.
struct StackKin<'a, T> {
    out: Kin<T>,
    q: &'a [T],
    qd: Option<&'a [T]>,
    prev: [T; 4],
}

impl<T: Scalar> KinLanes for StackKin<'_, T> {
    #[inline(always)]
    fn link<const PRI: bool>(&mut self, k: usize, c: &KinLink) {
        let o = &mut self.out;
        let qdk = self.qd.map_or(T::cst(0.0), |v| v[k]);
        let out = [
            &mut o.dy[k],
            &mut o.dz[k],
            &mut o.hy[k],
            &mut o.hz[k],
            &mut o.cy[k],
            &mut o.cz[k],
            &mut o.w[k],
            &mut o.ay[k],
            &mut o.az[k],
            &mut o.by[k],
            &mut o.bz[k],
        ];
        self.prev = one_lane_kin::<T, PRI>(c, self.prev, (self.q[k], qdk), out);
    }

    #[inline(always)]
    fn tip(&mut self, lp: [f64; 2]) {
        let [_, sp, cp, _] = self.prev;
        let [ty, tz] = &mut self.out.tip_d;
        let (one, m1) = (std::slice::from_ref, std::slice::from_mut);
        lanes_tip(lp, one(&sp), one(&cp), m1(ty), m1(tz));
    }
}

/// RNEA acceleration and force passes (no tip force) over `kin`, with base acceleration `a0`:
/// `tau = ID(q, q̇, q̈)`; the stack instance of the kernel's [`rnea_recursion`].
fn rnea_passes<T: Scalar>(chain: &Chain, kin: &Kin<T>, a0: [T; 3], qdd: &[T], tau: &mut [T]) {
    let zero = T::cst(0.0);
    let mut lane = StackRnea {
        kin,
        qdd,
        tau,
        acc: [[zero; 3]; MAX_DOF],
        ap: a0,
        cf: [zero; 3],
    };
    rnea_recursion(chain, &mut lane);
}

/// One lane of RNEA over the stack arrays of [`Kin`].
struct StackRnea<'a, T> {
    kin: &'a Kin<T>,
    qdd: &'a [T],
    tau: &'a mut [T],
    acc: Vec8<[T; 3]>,
    ap: [T; 3],
    cf: [T; 3],
}

impl<T: Scalar> RneaLanes for StackRnea<'_, T> {
    #[inline(always)]
    fn fwd<const PRI: bool>(&mut self, k: usize) {
        let kin = self.kin;
        let link = [
            &self.qdd[k],
            &kin.ay[k],
            &kin.az[k],
            &kin.hy[k],
            &kin.hz[k],
            &kin.dy[k],
            &kin.dz[k],
        ];
        one_lane_rnea_fwd::<T, PRI>(link, &mut self.ap);
        self.acc[k] = self.ap;
    }

    #[inline(always)]
    fn back<const PRI: bool>(&mut self, k: usize, j: f64, m: f64) {
        let kin = self.kin;
        let [a0, a1, a2] = &self.acc[k];
        let link = [
            a0, a1, a2, &kin.cy[k], &kin.cz[k], &kin.by[k], &kin.bz[k], &kin.dy[k], &kin.dz[k],
            &kin.hy[k], &kin.hz[k],
        ];
        (self.tau[k], _) = one_lane_rnea_back::<T, PRI>(j, m, link, &mut self.cf);
    }
}

/// Joint points and the tip point (world) from the levers, as the kernel's positions pass.
pub(crate) fn positions<T: Scalar>(n: usize, kin: &Kin<T>) -> (Vec8<[T; 2]>, [T; 2]) {
    let (mut y, mut z) = (T::cst(0.0), T::cst(0.0));
    let mut p = [[T::cst(0.0); 2]; MAX_DOF];
    for k in 0..n {
        y = y + kin.dy[k];
        z = z + kin.dz[k];
        p[k] = [y, z];
    }
    (p, [y + kin.tip_d[0], z + kin.tip_d[1]])
}

/// The kernel's articulated-body recursion ([`crate::aba::aba_recursion`], no tip force) on
/// `f64` stack arrays: the same loops and step functions, hence the same bits.
fn aba_value(chain: &Chain, kin: &Kin<f64>, tau: &[f64], locked: &[bool], qdd: &mut [f64]) {
    let mut lane = StackLane {
        kin,
        tau,
        qdd,
        g: [[0.0; 3]; MAX_DOF],
        nu: [0.0; MAX_DOF],
        cp: [0.0; 6],
        cz: [0.0; 3],
        ap: chain.base_acc,
    };
    aba_recursion(chain, Some(locked), &mut lane);
}

/// One lane of the articulated-body recursion over the stack arrays of [`Kin`].
struct StackLane<'a> {
    kin: &'a Kin<f64>,
    tau: &'a [f64],
    qdd: &'a mut [f64],
    g: Vec8<[f64; 3]>,
    nu: Vec8<f64>,
    cp: [f64; 6],
    cz: [f64; 3],
    ap: [f64; 3],
}

impl AbaLanes for StackLane<'_> {
    #[inline(always)]
    fn back<const K: u8>(&mut self, k: usize, j: f64, m: f64) {
        let kin = self.kin;
        let link = [
            &kin.cy, &kin.cz, &kin.by, &kin.bz, &kin.ay, &kin.az, &kin.hy, &kin.hz, &kin.dy,
            &kin.dz,
        ]
        .map(|v| &v[k]);
        let gain = (&mut self.g[k], &mut self.nu[k]);
        one_lane_back::<K>(
            j,
            m,
            self.tau[k],
            link,
            gain,
            (&mut self.cp, &mut self.cz),
            |_| {},
        );
    }

    #[inline(always)]
    fn fwd<const K: u8>(&mut self, k: usize) {
        let kin = self.kin;
        let link = [&kin.ay, &kin.az, &kin.hy, &kin.hz, &kin.dy, &kin.dz].map(|v| &v[k]);
        self.qdd[k] = one_lane_fwd::<K>(&self.g[k], self.nu[k], link, &mut self.ap);
    }
}

// ---------------------------------------------------------------------------------------------
// Small dense LDLᵀ on the stack, on any Scalar.
// ---------------------------------------------------------------------------------------------

/// In-place `A = L D Lᵀ` of the leading `n × n` block of the symmetric `a` (lower triangle
/// read): strictly lower part ← `L`, diagonal ← `D`. Returns `(min Dᵢ, max Dᵢ)` of the values;
/// `None` if a pivot is not positive (or NaN).
pub(crate) fn ldl<T: Scalar>(a: &mut Mat8<T>, n: usize) -> Option<(f64, f64)> {
    let (mut dmin, mut dmax) = (f64::INFINITY, 0.0f64);
    for j in 0..n {
        let mut d = a[j][j];
        for k in 0..j {
            d = d - a[j][k] * a[j][k] * a[k][k];
        }
        if d.re().is_nan() || d.re() <= 0.0 {
            return None;
        }
        a[j][j] = d;
        dmin = dmin.min(d.re());
        dmax = dmax.max(d.re());
        for i in j + 1..n {
            let mut s = a[i][j];
            for k in 0..j {
                s = s - a[i][k] * a[j][k] * a[k][k];
            }
            a[i][j] = s / d;
        }
    }
    Some((dmin, dmax))
}

/// Solve `L D Lᵀ x = b` in place (`b` of length `n`) with a factor from [`ldl`].
pub(crate) fn ldl_solve<T: Scalar>(f: &Mat8<T>, n: usize, b: &mut [T]) {
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s = s - f[i][k] * b[k];
        }
        b[i] = s;
    }
    for i in 0..n {
        b[i] = b[i] / f[i][i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s = s - f[k][i] * b[k];
        }
        b[i] = s;
    }
}

// ---------------------------------------------------------------------------------------------
// Argument checks and dispatch on the chain size.
// ---------------------------------------------------------------------------------------------

pub(crate) fn check_dof(n: usize) -> Result<(), SoaError> {
    if n <= MAX_DOF {
        Ok(())
    } else {
        Err(SoaError::DimensionMismatch {
            what: "joints of a chain for derivatives",
            expected: format!("at most {MAX_DOF}"),
            got: n.to_string(),
        })
    }
}

/// Call `$f::<W>(args)` with the dual width `W = $mult · n` for `n = 1..=MAX_DOF`.
macro_rules! by_dof {
    ($n:expr, $mult:literal, $f:ident ( $($arg:expr),* $(,)? )) => {
        match $n {
            1 => $f::<{ $mult }>($($arg),*),
            2 => $f::<{ 2 * $mult }>($($arg),*),
            3 => $f::<{ 3 * $mult }>($($arg),*),
            4 => $f::<{ 4 * $mult }>($($arg),*),
            5 => $f::<{ 5 * $mult }>($($arg),*),
            6 => $f::<{ 6 * $mult }>($($arg),*),
            7 => $f::<{ 7 * $mult }>($($arg),*),
            _ => $f::<{ 8 * $mult }>($($arg),*),
        }
    };
}
pub(crate) use by_dof;

// ---------------------------------------------------------------------------------------------
// Forward dynamics.
// ---------------------------------------------------------------------------------------------

/// Forward dynamics with the joints where `locked[k]` is true held as pseudo joints (`q̈_k = 0`,
/// seed §3.4), and its exact Jacobians (see the module docs for the method).
///
/// - `q`, `qd`: joint positions (rad or m) and rates, length `n`;
/// - `tau`: applied joint torques/forces (N m or N), length `n`;
/// - `locked`: mask of locked joints, length `n` (all `false`: plain [`crate::aba`]);
/// - `qdd`: output accelerations, length `n`; bit-identical to [`crate::aba`] (no joint locked)
///   or [`crate::pseudo_joint_dynamics`] (the same joints locked, no tip force), `0.0` at locked
///   joints;
/// - `dqdd_dq`, `dqdd_dqd`: output `∂q̈/∂q`, `∂q̈/∂q̇`, `n × n` row-major (entry `(i, j)` at
///   `i·n + j`); rows of locked joints are zero.
///
/// # Errors
/// [`SoaError::DimensionMismatch`] for wrong lengths or `n > MAX_DOF`;
/// [`SoaError::MassMatrixNotPositiveDefinite`] if `𝓜_ff` is not numerically positive definite.
#[allow(clippy::too_many_arguments)]
pub fn aba_derivatives(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    locked: &[bool],
    qdd: &mut [f64],
    dqdd_dq: &mut [f64],
    dqdd_dqd: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_dof(n)?;
    check_len("q", n, q.len())?;
    check_len("qd", n, qd.len())?;
    check_len("tau", n, tau.len())?;
    check_len("locked", n, locked.len())?;
    check_len("qdd", n, qdd.len())?;
    check_len("dqdd_dq (n x n)", n * n, dqdd_dq.len())?;
    check_len("dqdd_dqd (n x n)", n * n, dqdd_dqd.len())?;
    by_dof!(
        n,
        3,
        aba_derivatives_w(chain, q, qd, tau, locked, qdd, dqdd_dq, dqdd_dqd)
    )
}

/// [`aba_derivatives`] with duals of width `W = 3n`: directions `0..n` are `q`, `n..2n` are `q̇`,
/// `2n..3n` are `q̈`.
#[allow(clippy::too_many_arguments)]
fn aba_derivatives_w<const W: usize>(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    locked: &[bool],
    qdd: &mut [f64],
    dqdd_dq: &mut [f64],
    dqdd_dqd: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    debug_assert_eq!(W, 3 * n);
    // value: the kernel's articulated-body recursion
    let k64 = kin::<f64>(chain, q, Some(qd));
    aba_value(chain, &k64, tau, locked, qdd);

    // one dual RNEA pass seeded on (q, q̇, q̈) at the solution q̈
    let zero = Dual::<W>::constant(0.0);
    let (mut qx, mut qdx, mut qddx) = ([zero; MAX_DOF], [zero; MAX_DOF], [zero; MAX_DOF]);
    for k in 0..n {
        qx[k] = Dual::variable(q[k], k);
        qdx[k] = Dual::variable(qd[k], n + k);
        qddx[k] = Dual::variable(qdd[k], 2 * n + k);
    }
    let kd = kin(chain, &qx[..n], Some(&qdx[..n]));
    let a0 = chain.base_acc.map(Dual::constant);
    let mut id = [zero; MAX_DOF];
    rnea_passes(chain, &kd, a0, &qddx[..n], &mut id[..n]);

    // free joints f, 𝓜_ff = ∂ID_f/∂q̈_f
    let mut free = [0usize; MAX_DOF];
    let mut nf = 0;
    for k in 0..n {
        if !locked[k] {
            free[nf] = k;
            nf += 1;
        }
    }
    let mut mff = [[0.0; MAX_DOF]; MAX_DOF];
    for a in 0..nf {
        for b in 0..=a {
            mff[a][b] = id[free[a]].d[2 * n + free[b]];
        }
    }
    ldl(&mut mff, nf).ok_or(SoaError::MassMatrixNotPositiveDefinite)?;

    dqdd_dq.fill(0.0);
    dqdd_dqd.fill(0.0);
    let mut rhs = [0.0; MAX_DOF];
    for x in 0..2 * n {
        // ∂q̈_f/∂x = −𝓜_ff⁻¹ ∂ID_f/∂x
        for a in 0..nf {
            rhs[a] = -id[free[a]].d[x];
        }
        ldl_solve(&mff, nf, &mut rhs[..nf]);
        let (out, col) = if x < n {
            (&mut *dqdd_dq, x)
        } else {
            (&mut *dqdd_dqd, x - n)
        };
        for a in 0..nf {
            out[free[a] * n + col] = rhs[a];
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Impacts.
// ---------------------------------------------------------------------------------------------

/// Heel strike / tip impact of [`crate::tip_impact`] (the tip point's velocity and the rates of
/// the joints in `locked` become zero) with its exact Jacobian.
///
/// - `q`, `qd`: configuration and pre-impact rates `q̇⁻`, length `n`;
/// - `locked`: joints stopped in the same instant (distinct indices `< n`; `2 + len ≤ n`);
/// - `qd_post`: output `q̇⁺`, length `n`;
/// - `jac`: output `[∂q̇⁺/∂q | ∂q̇⁺/∂q̇⁻]`, `n × 2n` row-major (entry `(i, j)` at `i·2n + j`).
///
/// # Errors
/// As [`crate::tip_impact`] ([`SoaError::DimensionMismatch`], [`SoaError::InvalidJointIndex`],
/// [`SoaError::SingularConstraint`], [`SoaError::MassMatrixNotPositiveDefinite`]), and
/// [`SoaError::DimensionMismatch`] for `n > MAX_DOF`.
pub fn tip_impact_derivatives(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    locked: &[usize],
    qd_post: &mut [f64],
    jac: &mut [f64],
) -> Result<(), SoaError> {
    impact_derivatives(chain, q, qd, true, [0.0, 0.0], locked, qd_post, jac)
}

/// Knee strike of [`crate::joint_lock_impact`] (the rates of the joints in `locked` become zero)
/// with its exact Jacobian; arguments, layout and errors as [`tip_impact_derivatives`]
/// (`1 ≤ locked.len() ≤ n`).
pub fn joint_lock_impact_derivatives(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    locked: &[usize],
    qd_post: &mut [f64],
    jac: &mut [f64],
) -> Result<(), SoaError> {
    impact_derivatives(chain, q, qd, false, [0.0, 0.0], locked, qd_post, jac)
}

#[allow(clippy::too_many_arguments)]
fn impact_derivatives(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    tip: bool,
    offset: [f64; 2],
    locked: &[usize],
    qd_post: &mut [f64],
    jac: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_dof(n)?;
    let m = locked.len() + if tip { 2 } else { 0 };
    check_len("q", n, q.len())?;
    check_len("qd_minus", n, qd.len())?;
    check_len("qd_plus", n, qd_post.len())?;
    check_len("jac (n x 2n)", 2 * n * n, jac.len())?;
    if m == 0 || m > n {
        return Err(SoaError::DimensionMismatch {
            what: "number of impulsive constraints (1 ≤ rows ≤ n)",
            expected: format!("1..={n}"),
            got: m.to_string(),
        });
    }
    let mut seen = [false; MAX_DOF];
    for &k in locked {
        if k >= n || seen[k] {
            return Err(SoaError::InvalidJointIndex { index: k, n });
        }
        seen[k] = true;
    }
    by_dof!(
        n,
        1,
        impact_derivatives_w(chain, q, qd, tip, offset, locked, qd_post, jac)
    )
}

/// [`impact_derivatives`] with duals of width `W = n` seeded on `q`.
#[allow(clippy::too_many_arguments)]
fn impact_derivatives_w<const W: usize>(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    tip: bool,
    offset: [f64; 2],
    locked: &[usize],
    qd_post: &mut [f64],
    jac: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    debug_assert_eq!(W, n);
    // value: the kernel's computation
    let k64 = kin::<f64>(chain, q, None);
    let mut mass = [[0.0; MAX_DOF]; MAX_DOF];
    mass_matrix(chain, &k64, &mut mass);
    let arows = constraint_rows(chain, &k64, tip, locked, offset);
    let m = locked.len() + if tip { 2 } else { 0 };
    impact_value(n, m, &mass, &arows, qd, qd_post)?;

    // derivatives: the same map in duals seeded on q (q̇ = 0: no bias terms)
    let zero = Dual::<W>::constant(0.0);
    let mut qx = [zero; MAX_DOF];
    for k in 0..n {
        qx[k] = Dual::variable(q[k], k);
    }
    let kd = kin(chain, &qx[..n], None);
    let mut mm = [[zero; MAX_DOF]; MAX_DOF];
    mass_matrix(chain, &kd, &mut mm);
    ldl(&mut mm, n).ok_or(SoaError::MassMatrixNotPositiveDefinite)?;
    let arows = constraint_rows(chain, &kd, tip, locked, offset);
    let (mut v, mut lam) = ([0.0; MAX_DOF], [0.0; MAX_DOF]);
    impact_in_duals(n, m, &mm, &arows, qd, &mut v, &mut lam, jac)?;
    Ok(())
}

/// The plastic impact with constraint rows `a` (the leading `m` of them) in duals of width `W`
/// seeded on `q`, with `mm` the `LDLᵀ` factor of `𝓜(q)` ([`ldl`]): `X = 𝓜⁻¹Aᵀ`, `S = A X`,
/// `Λ = S⁻¹ A q̇⁻`, `q̇⁺ = q̇⁻ − X Λ` (module docs). Writes the values of `q̇⁺` and `Λ`, and the
/// Jacobian `[∂q̇⁺/∂q | ∂q̇⁺/∂q̇⁻]` (`n × 2n` row-major; `∂q̇⁺/∂q̇⁻ = I − X S⁻¹ A`). Returns the
/// smallest and largest pivot of `S`'s factorisation (a caller rejects near-singular sets).
#[allow(clippy::too_many_arguments)]
pub(crate) fn impact_in_duals<const W: usize>(
    n: usize,
    m: usize,
    mm: &Mat8<Dual<W>>,
    arows: &Mat8<Dual<W>>,
    qd: &[f64],
    qd_post: &mut [f64],
    lam_out: &mut [f64],
    jac: &mut [f64],
) -> Result<(f64, f64), SoaError> {
    let zero = Dual::<W>::constant(0.0);
    // X = 𝓜⁻¹ Aᵀ (column i of X in xt[i])
    let mut xt = *arows;
    for i in 0..m {
        ldl_solve(mm, n, &mut xt[i][..n]);
    }
    // S = A X (m × m, lower triangle), y = A q̇⁻
    let mut s = [[zero; MAX_DOF]; MAX_DOF];
    let mut lam = [zero; MAX_DOF];
    for i in 0..m {
        for j in 0..=i {
            let mut acc = zero;
            for k in 0..n {
                acc = acc + arows[i][k] * xt[j][k];
            }
            s[i][j] = acc;
        }
        let mut y = zero;
        for k in 0..n {
            y = y + arows[i][k] * Dual::constant(qd[k]);
        }
        lam[i] = y;
    }
    let pivots = ldl(&mut s, m).ok_or(SoaError::SingularConstraint {
        what: "A 𝓜⁻¹ Aᵀ (impact)",
    })?;
    // Λ = S⁻¹ y, q̇⁺ = q̇⁻ − X Λ
    ldl_solve(&s, m, &mut lam[..m]);
    for i in 0..m {
        lam_out[i] = lam[i].v;
    }
    let w2 = 2 * n;
    for k in 0..n {
        let mut v = Dual::constant(qd[k]);
        for i in 0..m {
            v = v - xt[i][k] * lam[i];
        }
        qd_post[k] = v.v;
        jac[k * w2..k * w2 + n].copy_from_slice(&v.d[..n]);
    }

    // ∂q̇⁺/∂q̇⁻ = I − X S⁻¹ A on the values
    let mut sv = [[0.0; MAX_DOF]; MAX_DOF];
    for i in 0..m {
        for j in 0..=i {
            sv[i][j] = s[i][j].v;
        }
    }
    let mut z = [0.0; MAX_DOF];
    for c in 0..n {
        for i in 0..m {
            z[i] = arows[i][c].v;
        }
        ldl_solve(&sv, m, &mut z[..m]);
        for k in 0..n {
            let mut v = if k == c { 1.0 } else { 0.0 };
            for i in 0..m {
                v -= xt[i][k].v * z[i];
            }
            jac[k * w2 + n + c] = v;
        }
    }
    Ok(pivots)
}

/// Mass matrix 𝓜 (both triangles) by the composite-rigid-body steps of the kernel
/// (crate::crba), in the same order: for `f64` it is the kernel's 𝓜 bit for bit.
pub(crate) fn mass_matrix<T: Scalar>(chain: &Chain, kin: &Kin<T>, mass: &mut Mat8<T>) {
    let n = chain.dof();
    let zero = T::cst(0.0);
    let mut comp = [[zero; 6]; MAX_DOF];
    let mut carry = [zero; 6];
    for k in (0..n).rev() {
        let m = T::cst(chain.links[k].mass);
        let kk = [
            T::cst(chain.j_joint[k]) + carry[0],
            carry[1] - m * kin.cz[k],
            carry[2] + m * kin.cy[k],
            m + carry[3],
            carry[4],
            m + carry[5],
        ];
        comp[k] = kk;
        carry = spatial::congruence(&kk, kin.dy[k], kin.dz[k]);
    }
    let h_dot = |k: usize, f: &[T; 3]| {
        if chain.prismatic[k] {
            kin.hy[k] * f[1] + kin.hz[k] * f[2]
        } else {
            f[0]
        }
    };
    for k in 0..n {
        let x = &comp[k];
        let (hy, hz) = (kin.hy[k], kin.hz[k]);
        let mut f = if chain.prismatic[k] {
            [
                x[1] * hy + x[2] * hz,
                x[3] * hy + x[4] * hz,
                x[4] * hy + x[5] * hz,
            ]
        } else {
            [x[0], x[1], x[2]]
        };
        mass[k][k] = h_dot(k, &f);
        for j in (0..k).rev() {
            f = spatial::force_transport(&f, kin.dy[j + 1], kin.dz[j + 1]);
            let v = h_dot(j, &f);
            mass[j][k] = v;
            mass[k][j] = v;
        }
    }
}

/// Impulsive constraint rows `A` (`m × n` in the leading rows): the linear Jacobian of the
/// contact point (the tip moved by the world `offset`)
/// (`[−(t − p_k)_z, (t − p_k)_y]` for a revolute joint, `h_k` for a prismatic one; seed
/// eq. 2.24) if `tip`, then `e_kᵀ` for each locked `k`.
fn constraint_rows<T: Scalar>(
    chain: &Chain,
    kin: &Kin<T>,
    tip: bool,
    locked: &[usize],
    offset: [f64; 2],
) -> Mat8<T> {
    let n = chain.dof();
    let mut a = [[T::cst(0.0); MAX_DOF]; MAX_DOF];
    let mut row = 0;
    if tip {
        let (p, t) = positions(n, kin);
        // the contact point: the tip, or the tip moved by a world offset (a round foot's
        // lowest point below its arc centre); no arithmetic at all for a zero offset
        let t = if offset == [0.0, 0.0] {
            t
        } else {
            [t[0] + T::cst(offset[0]), t[1] + T::cst(offset[1])]
        };
        for k in 0..n {
            if chain.prismatic[k] {
                a[0][k] = kin.hy[k];
                a[1][k] = kin.hz[k];
            } else {
                a[0][k] = -(t[1] - p[k][1]);
                a[1][k] = t[0] - p[k][0];
            }
        }
        row = 2;
    }
    for (i, &k) in locked.iter().enumerate() {
        a[row + i][k] = T::cst(1.0);
    }
    a
}

/// Scratch bytes for faer's small Cholesky factorisations and solves (n ≤ MAX_DOF).
const FAER_SCRATCH: usize = 1024;

/// `q̇⁺ = q̇⁻ − 𝓜⁻¹Aᵀ(A𝓜⁻¹Aᵀ)⁻¹A q̇⁻` by the kernel's operations in the kernel's order (faer
/// `LLᵀ` of 𝓜 and of `A𝓜⁻¹Aᵀ`, crate::impact), on stack storage: the same bits as
/// [`crate::tip_impact`] / [`crate::joint_lock_impact`] and the same singularity test.
fn impact_value(
    n: usize,
    m: usize,
    mass: &Mat8<f64>,
    arows: &Mat8<f64>,
    qd: &[f64],
    qd_post: &mut [f64],
) -> Result<(), SoaError> {
    let mut buf = [MaybeUninit::<u8>::uninit(); FAER_SCRATCH];
    let stack = MemStack::new(&mut buf);
    // 𝓜 = L Lᵀ (column-major n × n)
    let mut chol = [0.0; MAX_DOF * MAX_DOF];
    for j in 0..n {
        for i in 0..n {
            chol[i + j * n] = mass[i][j];
        }
    }
    let mut lm = MatMut::from_column_major_slice_mut(&mut chol[..n * n], n, n);
    llt::factor::cholesky_in_place(
        lm.as_mut(),
        Default::default(),
        Par::Seq,
        stack,
        Default::default(),
    )
    .map_err(|_| SoaError::MassMatrixNotPositiveDefinite)?;
    // X = 𝓜⁻¹ Aᵀ (column-major n × m)
    let mut x = [0.0; MAX_DOF * MAX_DOF];
    for i in 0..m {
        for k in 0..n {
            x[k + i * n] = arows[i][k];
        }
    }
    llt::solve::solve_in_place_with_conj(
        lm.as_ref(),
        Conj::No,
        MatMut::from_column_major_slice_mut(&mut x[..n * m], n, m),
        Par::Seq,
        stack,
    );
    // S = A X (column-major m × m), y = A q̇⁻
    let mut sm = [0.0; MAX_DOF * MAX_DOF];
    let mut y = [0.0; MAX_DOF];
    for i in 0..m {
        for j in 0..m {
            let mut s = 0.0;
            for k in 0..n {
                s += arows[i][k] * x[k + j * n];
            }
            sm[i + j * m] = s;
        }
        let mut v = 0.0;
        for k in 0..n {
            v += arows[i][k] * qd[k];
        }
        y[i] = v;
    }
    let singular = || SoaError::SingularConstraint {
        what: "A 𝓜⁻¹ Aᵀ (impact)",
    };
    let mut ls = MatMut::from_column_major_slice_mut(&mut sm[..m * m], m, m);
    llt::factor::cholesky_in_place(
        ls.as_mut(),
        Default::default(),
        Par::Seq,
        stack,
        Default::default(),
    )
    .map_err(|_| singular())?;
    // the kernel's rejection of numerically rank-deficient constraint sets
    let (mut dmin, mut dmax) = (f64::INFINITY, 0.0f64);
    for i in 0..m {
        let d = ls[(i, i)].abs();
        dmin = dmin.min(d);
        dmax = dmax.max(d);
    }
    if dmin.is_nan() || dmin <= 1e-7 * dmax {
        return Err(singular());
    }
    llt::solve::solve_in_place_with_conj(
        ls.as_ref(),
        Conj::No,
        MatMut::from_column_major_slice_mut(&mut y[..m], m, 1),
        Par::Seq,
        stack,
    );
    for k in 0..n {
        let mut s = 0.0;
        for (i, l) in y[..m].iter().enumerate() {
            s += x[k + i * n] * l;
        }
        qd_post[k] = qd[k] - s;
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Round feet: a base rolling without slip, and the impact at an offset contact point.
// ---------------------------------------------------------------------------------------------

/// Checks a floating chain (joint 0 prismatic along the base `y`, joint 1 along `z`, then `n ≥ 1`
/// joints) for the rolling routines; returns `n`.
pub(crate) fn check_floating(chain: &Chain) -> Result<usize, SoaError> {
    let nf = chain.dof();
    check_dof(nf)?;
    let ok = nf >= 3
        && chain.prismatic[0]
        && chain.prismatic[1]
        && chain.axis[0] == [1.0, 0.0]
        && chain.axis[1] == [0.0, 1.0]
        && chain.links[0].to_next == [0.0, 0.0]
        && chain.links[1].to_next == [0.0, 0.0];
    if ok {
        Ok(nf - 2)
    } else {
        Err(SoaError::DimensionMismatch {
            what: "floating chain for a rolling base",
            expected: "prismatic [1, 0], prismatic [0, 1] (zero-length base links), then ≥ 1 joint"
                .into(),
            got: format!("{} joints", nf),
        })
    }
}

/// Forward dynamics of a chain whose base point rolls without slip on the slope: the base point
/// is the centre of a circular arc of radius `radius` rigidly fixed to the first link, touching
/// the slope at the point straight below it (McGeer 1990, "Passive dynamic walking", IJRR 9(2):
/// the arc-foot walker). With `θ₀ = q₀` the first link's absolute angle, the arc centre moves
/// along the slope by `y = −r q₀` (rolling, no slip) at constant height: a holonomic constraint
/// with a **constant** Jacobian on the floating chain `q_F = (y, z, q) = J q`,
/// `J = [−r e₀ᵀ; 0; I]`, so that `J̇ = 0` and the reduced equations are
///
/// ```text
/// Jᵀ ID_F(J q, J q̇, J q̈) = τ        (Jᵀ𝓜_F J q̈ = τ − Jᵀ C_F)
/// ```
/// with the joints where `locked[k]` is true held (`q̈_k = 0`, seed §3.4) and the others passive
/// (`τ = 0`). `chain` is the floating chain (see [`check_floating`]: prismatic `y`, prismatic
/// `z`, then the `n` joints of the walker rooted at the arc centre); `radius = 0` is a pinned
/// base (the values agree with [`crate::pseudo_joint_dynamics`] to roundoff).
///
/// - `q`, `qd`: the `n` joint positions and rates;
/// - `qdd`: output accelerations (length `n`, `0.0` at locked joints);
/// - `tau_f`: output `ID_F(J q, J q̇, J q̈)` (length `n + 2`): the ground's force on the foot
///   `[f_y, f_z]` (entries 0, 1), the torque `r f_y` the rolling contact applies about the arc
///   centre (entry 2, as `q₀`'s generalized force) and the locking torques (entries `2 + k`).
///
/// # Errors
/// [`SoaError::DimensionMismatch`] for a chain of the wrong shape or wrong lengths;
/// [`SoaError::MassMatrixNotPositiveDefinite`] if `(Jᵀ𝓜_F J)_ff` is not positive definite.
#[allow(clippy::too_many_arguments)]
pub fn rolling_base_dynamics(
    chain: &Chain,
    radius: f64,
    q: &[f64],
    qd: &[f64],
    locked: &[bool],
    qdd: &mut [f64],
    tau_f: &mut [f64],
) -> Result<(), SoaError> {
    let n = check_floating(chain)?;
    check_len("q", n, q.len())?;
    check_len("qd", n, qd.len())?;
    check_len("locked", n, locked.len())?;
    check_len("qdd", n, qdd.len())?;
    check_len("tau_f", n + 2, tau_f.len())?;
    rolling_value(chain, n, radius, q, qd, locked, qdd, tau_f)
}

/// [`rolling_base_dynamics`] and its exact Jacobians `∂q̈/∂q`, `∂q̈/∂q̇` (`n × n` row-major,
/// rows of locked joints zero): one RNEA pass in duals of width `3n` seeded on `(q, q̇, q̈)`
/// through `J`, `∂q̈_f/∂x = −(Jᵀ𝓜_F J)_ff⁻¹ ∂(Jᵀ ID_F)_f/∂x` (Carpentier & Mansard 2018, as
/// [`aba_derivatives`]). Errors as [`rolling_base_dynamics`].
#[allow(clippy::too_many_arguments)]
pub fn rolling_base_derivatives(
    chain: &Chain,
    radius: f64,
    q: &[f64],
    qd: &[f64],
    locked: &[bool],
    qdd: &mut [f64],
    dqdd_dq: &mut [f64],
    dqdd_dqd: &mut [f64],
) -> Result<(), SoaError> {
    let n = check_floating(chain)?;
    check_len("q", n, q.len())?;
    check_len("qd", n, qd.len())?;
    check_len("locked", n, locked.len())?;
    check_len("qdd", n, qdd.len())?;
    check_len("dqdd_dq (n x n)", n * n, dqdd_dq.len())?;
    check_len("dqdd_dqd (n x n)", n * n, dqdd_dqd.len())?;
    by_dof!(
        n,
        3,
        rolling_derivatives_w(chain, radius, q, qd, locked, qdd, dqdd_dq, dqdd_dqd)
    )
}

/// Indices of the free joints.
fn free_joints(locked: &[bool]) -> (Vec8<usize>, usize) {
    let mut free = [0usize; MAX_DOF];
    let mut nf = 0;
    for (k, l) in locked.iter().enumerate() {
        if !l {
            free[nf] = k;
            nf += 1;
        }
    }
    (free, nf)
}

#[allow(clippy::too_many_arguments)]
fn rolling_value(
    chain: &Chain,
    n: usize,
    r: f64,
    q: &[f64],
    qd: &[f64],
    locked: &[bool],
    qdd: &mut [f64],
    tau_f: &mut [f64],
) -> Result<(), SoaError> {
    let nf = n + 2;
    let (mut qf, mut qdf, mut qddf) = ([0.0; MAX_DOF], [0.0; MAX_DOF], [0.0; MAX_DOF]);
    qf[0] = -r * q[0];
    qdf[0] = -r * qd[0];
    qf[2..nf].copy_from_slice(q);
    qdf[2..nf].copy_from_slice(qd);
    let k64 = kin::<f64>(chain, &qf[..nf], Some(&qdf[..nf]));
    // C_F = ID_F(q_F, q̇_F, 0), 𝓜_F
    let mut c = [0.0; MAX_DOF];
    rnea_passes(chain, &k64, chain.base_acc, &qddf[..nf], &mut c[..nf]);
    let mut mf = [[0.0; MAX_DOF]; MAX_DOF];
    mass_matrix(chain, &k64, &mut mf);
    // Jᵀ𝓜_F J and Jᵀ C_F: column a of J is e_{a+2} − r δ_{a0} e_0
    let red = |a: usize, b: usize| {
        let mut v = mf[a + 2][b + 2];
        if a == 0 {
            v -= r * mf[0][b + 2];
        }
        if b == 0 {
            v -= r * mf[a + 2][0];
        }
        if a == 0 && b == 0 {
            v += r * r * mf[0][0];
        }
        v
    };
    let (free, nfree) = free_joints(locked);
    let mut mff = [[0.0; MAX_DOF]; MAX_DOF];
    let mut rhs = [0.0; MAX_DOF];
    for a in 0..nfree {
        for b in 0..=a {
            mff[a][b] = red(free[a], free[b]);
        }
        let k = free[a];
        rhs[a] = -(c[k + 2] - if k == 0 { r * c[0] } else { 0.0 });
    }
    ldl(&mut mff, nfree).ok_or(SoaError::MassMatrixNotPositiveDefinite)?;
    ldl_solve(&mff, nfree, &mut rhs[..nfree]);
    qdd.fill(0.0);
    for a in 0..nfree {
        qdd[free[a]] = rhs[a];
    }
    qddf[0] = -r * qdd[0];
    qddf[2..nf].copy_from_slice(qdd);
    rnea_passes(chain, &k64, chain.base_acc, &qddf[..nf], tau_f);
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn rolling_derivatives_w<const W: usize>(
    chain: &Chain,
    r: f64,
    q: &[f64],
    qd: &[f64],
    locked: &[bool],
    qdd: &mut [f64],
    dqdd_dq: &mut [f64],
    dqdd_dqd: &mut [f64],
) -> Result<(), SoaError> {
    let nf = chain.dof();
    let n = nf - 2;
    debug_assert_eq!(W, 3 * n);
    let mut tau_f = [0.0; MAX_DOF];
    rolling_value(chain, n, r, q, qd, locked, qdd, &mut tau_f[..nf])?;

    let zero = Dual::<W>::constant(0.0);
    let mr = Dual::<W>::constant(-r);
    let (mut qx, mut qdx, mut qddx) = ([zero; MAX_DOF], [zero; MAX_DOF], [zero; MAX_DOF]);
    for k in 0..n {
        qx[k + 2] = Dual::variable(q[k], k);
        qdx[k + 2] = Dual::variable(qd[k], n + k);
        qddx[k + 2] = Dual::variable(qdd[k], 2 * n + k);
    }
    qx[0] = mr * qx[2];
    qdx[0] = mr * qdx[2];
    qddx[0] = mr * qddx[2];
    let kd = kin(chain, &qx[..nf], Some(&qdx[..nf]));
    let a0 = chain.base_acc.map(Dual::constant);
    let mut id = [zero; MAX_DOF];
    rnea_passes(chain, &kd, a0, &qddx[..nf], &mut id[..nf]);
    // Jᵀ ID_F
    let mut idr = [zero; MAX_DOF];
    idr[..n].copy_from_slice(&id[2..n + 2]);
    idr[0] = idr[0] + mr * id[0];

    let (free, nfree) = free_joints(locked);
    let mut mff = [[0.0; MAX_DOF]; MAX_DOF];
    for a in 0..nfree {
        for b in 0..=a {
            mff[a][b] = idr[free[a]].d[2 * n + free[b]];
        }
    }
    ldl(&mut mff, nfree).ok_or(SoaError::MassMatrixNotPositiveDefinite)?;
    dqdd_dq.fill(0.0);
    dqdd_dqd.fill(0.0);
    let mut rhs = [0.0; MAX_DOF];
    for x in 0..2 * n {
        for a in 0..nfree {
            rhs[a] = -idr[free[a]].d[x];
        }
        ldl_solve(&mff, nfree, &mut rhs[..nfree]);
        let (out, col) = if x < n {
            (&mut *dqdd_dq, x)
        } else {
            (&mut *dqdd_dqd, x - n)
        };
        for a in 0..nfree {
            out[free[a] * n + col] = rhs[a];
        }
    }
    Ok(())
}

/// Plastic impact at a contact point offset from the tip by a fixed **world** vector `offset`
/// (a round foot of radius `r` touching the slope at `offset = [0, −r]` below its arc centre,
/// the tip): the contact point's velocity (as a point of the last link) and the rates of the
/// joints in `locked` become zero, `q̇⁺ = q̇⁻ − 𝓜⁻¹Aᵀ(A𝓜⁻¹Aᵀ)⁻¹A q̇⁻` with `A` the contact
/// point's linear Jacobian and `e_kᵀ` rows (the map of [`crate::tip_impact`], equal to it bit for
/// bit at `offset = [0, 0]`). Also returns the impulse on the chain along the first two
/// joints `[(𝓜Δq̇)₀, (𝓜Δq̇)₁]` — with a floating base (prismatic `y`, `z` first), the
/// ground's impulse on the contact. Arguments, layout and errors as [`tip_impact_derivatives`];
/// `jac = None` skips the Jacobian.
pub fn contact_impact(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    offset: [f64; 2],
    locked: &[usize],
    qd_post: &mut [f64],
    jac: Option<&mut [f64]>,
) -> Result<[f64; 2], SoaError> {
    let n = chain.dof();
    check_dof(n)?;
    // the value comes with the Jacobian (one dual pass of width n; small next to a stride)
    let mut scratch = [0.0; 2 * MAX_DOF * MAX_DOF];
    let j = match jac {
        Some(j) => j,
        None => &mut scratch[..2 * n * n],
    };
    impact_derivatives(chain, q, qd, true, offset, locked, qd_post, j)?;
    let k64 = kin::<f64>(chain, q, None);
    let mut mass = [[0.0; MAX_DOF]; MAX_DOF];
    mass_matrix(chain, &k64, &mut mass);
    let mut imp = [0.0; 2];
    for (i, v) in imp.iter_mut().enumerate().take(n.min(2)) {
        for k in 0..n {
            *v += mass[i][k] * (qd_post[k] - qd[k]);
        }
    }
    Ok(imp)
}

// ---------------------------------------------------------------------------------------------
// Tip position.
// ---------------------------------------------------------------------------------------------

/// Tip position `[y, z]` (m, bit-identical to [`crate::tip_position`]) and its exact
/// Jacobian `∂tip/∂q` (`2 × n` row-major, entry `(i, j)` at `i·n + j`), for guard gradients.
///
/// # Errors
/// [`SoaError::DimensionMismatch`] for wrong lengths or `n > MAX_DOF`.
pub fn tip_position_derivatives(
    chain: &Chain,
    q: &[f64],
    pos: &mut [f64; 2],
    jac: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_dof(n)?;
    check_len("q", n, q.len())?;
    check_len("jac (2 x n)", 2 * n, jac.len())?;
    by_dof!(n, 1, tip_position_w(chain, q, pos, jac));
    Ok(())
}

fn tip_position_w<const W: usize>(chain: &Chain, q: &[f64], pos: &mut [f64; 2], jac: &mut [f64]) {
    let n = chain.dof();
    let mut qx = [Dual::<W>::constant(0.0); MAX_DOF];
    for k in 0..n {
        qx[k] = Dual::variable(q[k], k);
    }
    let kd = kin(chain, &qx[..n], None);
    let (_, t) = positions(n, &kd);
    *pos = [t[0].v, t[1].v];
    jac[..n].copy_from_slice(&t[0].d[..n]);
    jac[n..2 * n].copy_from_slice(&t[1].d[..n]);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faer_scratch_fits_on_the_stack_buffer() {
        for n in 1..=MAX_DOF {
            let req =
                llt::factor::cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default())
                    .or(llt::solve::solve_in_place_scratch::<f64>(n, n, Par::Seq));
            assert!(
                req.size_bytes() + req.align_bytes() <= FAER_SCRATCH,
                "n = {n}"
            );
        }
    }
}
