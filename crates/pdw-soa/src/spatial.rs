//! Planar spatial vectors and the per-link arithmetic shared by the scalar and batched kernels.
//!
//! # Planar spatial algebra (seed §3.3)
//! Every spatial quantity is expressed in the world (slope) frame and referred to a point:
//! - motion vector `V = [ω, v_y, v_z]` (seed eq. 3.3): angular rate about x and the linear
//!   velocity of the reference point;
//! - force vector `F = [τ, f_y, f_z]`: moment about the reference point and the force;
//! - rigid-body transform from point `a` to point `b = a + l` (seed eq. 3.10):
//!   `Φ_{b,a} = [[1, 0, 0], [−l_z, 1, 0], [l_y, 0, 1]]`, so `V_b = Φ V_a` and
//!   `F_a = Φᵀ F_b` (seed Table 2.1);
//! - joint map `H = [1, 0, 0]` (revolute) or `[0, u_y, u_z]` (prismatic) (seed eq. 3.4–3.5);
//! - spatial inertia of a link about its joint point with world COM offset `c` (seed eq. 3.16
//!   with a rotational inertia `I_c` about the COM added):
//!   `M = [[I_c + m|c|², −m c_z, m c_y], [−m c_z, m, 0], [m c_y, 0, m]]`.
//!
//! Accelerations are classical (the linear part is the acceleration of the reference point), so
//! the bias terms are those of seed eq. 3.13–3.14: `a_k = [0, −ω_{k−1}² l_{k−1,k}]` (plus the
//! Coriolis term `2 ω × u q̇` for a prismatic joint) and `b_k = [0, −m ω_k² c]`.
//!
//! # Bit-for-bit equality of scalar and batched kernels
//! Each function below is the whole arithmetic of one link in one pass. The scalar kernels call
//! them once per link; the batched kernels call them once per link and lane, inside the lane
//! loop. Rust never contracts `a*b + c` into a fused multiply-add on its own, so the vectorised
//! lane loop performs the identical IEEE operations and both give the same bits. sin/cos come
//! from one routine ([`sincos`], `pdw_simd::trig`) in both paths.
//!
//! # Generic scalars
//! The kinematics and RNEA steps are generic over [`Scalar`]: `f64` for the kernels, and the
//! forward-mode [`crate::dual::Dual`] for exact derivatives ([`crate::derivatives`]) through the
//! same arithmetic. Constants are written `T::cst(c)` in the place the literal had, so the `f64`
//! instantiation performs the same IEEE operations in the same order as before (the kernels'
//! results are unchanged bit for bit).

// The per-link step functions take every input as a separate scalar so that the scalar
// kernels and the batched lane loops call the very same arithmetic.
#![allow(clippy::too_many_arguments)]

use crate::dual::Scalar;

/// Symmetric 3×3 stored as `[x00, x01, x02, x11, x12, x22]`.
pub(crate) type Sym3 = [f64; 6];

/// `(sin x, cos x)` by the vectorisable routine of [`pdw_simd::trig`] (≤ 2 ulp of libm), which
/// the batched kernels evaluate on many lanes at a time with the same bits per lane.
#[inline(always)]
pub fn sincos(x: f64) -> (f64, f64) {
    pdw_simd::sincos(x)
}

/// `sin`/`cos` of every element of `x` into `s` and `c` (same length), with the routine of
/// [`sincos`].
#[inline(always)]
pub(crate) fn sincos_slice(x: &[f64], s: &mut [f64], c: &mut [f64]) {
    pdw_simd::sincos_slice(x, s, c);
}

/// `Φ_{b,a}` for the lever `l = p_b − p_a` (seed eq. 3.10) as a dense 3×3.
pub fn phi(l: [f64; 2]) -> [[f64; 3]; 3] {
    [[1.0, 0.0, 0.0], [-l[1], 1.0, 0.0], [l[0], 0.0, 1.0]]
}

/// Spatial inertia about a point for mass `m`, rotational inertia `ic` about the COM and world
/// COM offset `c` from the point (seed eq. 3.16 plus `ic`).
pub fn spatial_inertia(m: f64, ic: f64, c: [f64; 2]) -> [[f64; 3]; 3] {
    let j = ic + m * (c[0] * c[0] + c[1] * c[1]);
    [
        [j, -m * c[1], m * c[0]],
        [-m * c[1], m, 0.0],
        [m * c[0], 0.0, m],
    ]
}

// ---------------------------------------------------------------------------------------------
// Pass 1: kinematics and velocity-dependent bias terms (base to tip).
// ---------------------------------------------------------------------------------------------

/// Geometry of link `k` for a revolute joint: lever `d = R_{k−1} l_{k−1}` from the previous
/// joint (world), and world COM offset `c = R_k com`.
/// Inputs: previous link rotation `(sp, cp)`, previous `to_next` `(lyp, lzp)` (local), own
/// rotation `(s, c)`, local COM `(comy, comz)`. Returns `(dy, dz, cy, cz)`.
#[inline(always)]
pub(crate) fn geom_rev<T: Scalar>(
    sp: T,
    cp: T,
    lyp: T,
    lzp: T,
    s: T,
    c: T,
    comy: T,
    comz: T,
) -> (T, T, T, T) {
    let dy = cp * lyp - sp * lzp;
    let dz = sp * lyp + cp * lzp;
    let cy = c * comy - s * comz;
    let cz = s * comy + c * comz;
    (dy, dz, cy, cz)
}

/// Geometry of link `k` for a prismatic joint (orientation unchanged, `(s, c) = (sp, cp)`):
/// lever `d = R (l_{k−1} + q u)`, world axis `h = R u`, world COM offset.
/// Returns `(dy, dz, hy, hz, cy, cz)`.
#[inline(always)]
pub(crate) fn geom_pri<T: Scalar>(
    sp: T,
    cp: T,
    lyp: T,
    lzp: T,
    uy: T,
    uz: T,
    q: T,
    comy: T,
    comz: T,
) -> (T, T, T, T, T, T) {
    let ly = lyp + q * uy;
    let lz = lzp + q * uz;
    let dy = cp * ly - sp * lz;
    let dz = sp * ly + cp * lz;
    let hy = cp * uy - sp * uz;
    let hz = sp * uy + cp * uz;
    let cy = cp * comy - sp * comz;
    let cz = sp * comy + cp * comz;
    (dy, dz, hy, hz, cy, cz)
}

/// Angular rate and acceleration bias across a revolute joint (seed eq. 3.13):
/// `ω = ω_p + q̇`, `a = [0, −ω_p² d]`. Returns `(ω, a_y, a_z)`.
#[inline(always)]
pub(crate) fn vel_rev<T: Scalar>(wp: T, qd: T, dy: T, dz: T) -> (T, T, T) {
    let w = wp + qd;
    let w2 = wp * wp;
    (w, -(w2 * dy), -(w2 * dz))
}

/// Angular rate and acceleration bias across a prismatic joint: `ω = ω_p`,
/// `a = [0, −ω_p² d + 2 ω_p × (h q̇)]`. Returns `(ω, a_y, a_z)`.
#[inline(always)]
pub(crate) fn vel_pri<T: Scalar>(wp: T, qd: T, dy: T, dz: T, hy: T, hz: T) -> (T, T, T) {
    let w2 = wp * wp;
    let t = T::cst(2.0) * wp * qd;
    (wp, -(w2 * dy) - t * hz, -(w2 * dz) + t * hy)
}

/// Force bias of a link (seed eq. 3.14): `b = [0, −m ω² c]`. Returns `(b_y, b_z)`.
#[inline(always)]
pub(crate) fn force_bias<T: Scalar>(m: T, w: T, cy: T, cz: T) -> (T, T) {
    let mw2 = m * (w * w);
    (-(mw2 * cy), -(mw2 * cz))
}

// ---------------------------------------------------------------------------------------------
// Articulated-body (SOA innovations) backward pass, tip to base.
// ---------------------------------------------------------------------------------------------

/// Output of one backward articulated-body step.
#[derive(Clone, Copy)]
pub(crate) struct AbaBack {
    /// Kalman gain `G = P H / D` (seed/Jain's innovations factorisation).
    pub g: [f64; 3],
    /// `ν = ε / D`, the joint acceleration with zero inboard acceleration.
    pub nu: f64,
    /// Articulated inertia of links k..n at joint k before the joint-k innovation.
    pub p: Sym3,
    /// Articulated bias force at joint k before the joint-k innovation.
    pub z: [f64; 3],
    /// `Φ_{k,k−1}ᵀ P⁺ Φ_{k,k−1}`: carried to the parent.
    pub cp: Sym3,
    /// `Φ_{k,k−1}ᵀ z⁺`: carried to the parent.
    pub cz: [f64; 3],
}

/// Link inertia plus the carried articulated inertia: `P = M + Φᵀ P⁺_{k+1} Φ`, `z = b + Φᵀ z⁺`.
#[inline(always)]
fn add_link(
    cp: &Sym3,
    cz: &[f64; 3],
    j: f64,
    m: f64,
    cy: f64,
    cz_: f64,
    by: f64,
    bz: f64,
) -> (Sym3, [f64; 3]) {
    let mcy = m * cy;
    let mcz = m * cz_;
    (
        [
            j + cp[0],
            cp[1] - mcz,
            cp[2] + mcy,
            m + cp[3],
            cp[4],
            m + cp[5],
        ],
        [cz[0], cz[1] + by, cz[2] + bz],
    )
}

/// `Φᵀ X Φ` for symmetric `X` and the lever `d` (`r = (−d_z, d_y)`).
#[inline(always)]
pub(crate) fn congruence<T: Scalar>(x: &[T; 6], dy: T, dz: T) -> [T; 6] {
    let r0 = -dz;
    let r1 = dy;
    let y0 = x[0] + r0 * x[1] + r1 * x[2];
    let y1 = x[1] + r0 * x[3] + r1 * x[4];
    let y2 = x[2] + r0 * x[4] + r1 * x[5];
    [y0 + r0 * y1 + r1 * y2, y1, y2, x[3], x[4], x[5]]
}

/// `Φᵀ f` for the lever `d`: moment transport `τ + d × f`.
#[inline(always)]
pub(crate) fn force_transport<T: Scalar>(f: &[T; 3], dy: T, dz: T) -> [T; 3] {
    [f[0] + (-dz) * f[1] + dy * f[2], f[1], f[2]]
}

/// `Φ A` for the lever `d`.
#[inline(always)]
pub(crate) fn motion_transport<T: Scalar>(a: &[T; 3], dy: T, dz: T) -> [T; 3] {
    [a[0], a[1] + (-dz) * a[0], a[2] + dy * a[0]]
}

/// One backward step of the articulated-body recursion across a **revolute** joint.
/// `(cp, cz)` carried from the child, link constants, biases, applied torque `tau` and the lever
/// `d` of this joint (for the carry to the parent).
#[inline(always)]
pub(crate) fn aba_back_rev(
    cp: &Sym3,
    czc: &[f64; 3],
    j: f64,
    m: f64,
    cy: f64,
    cz: f64,
    by: f64,
    bz: f64,
    ay: f64,
    az: f64,
    tau: f64,
    dy: f64,
    dz: f64,
) -> AbaBack {
    let (p, z) = add_link(cp, czc, j, m, cy, cz, by, bz);
    // z + P a with a = [0, a_y, a_z]
    let zz0 = z[0] + (p[1] * ay + p[2] * az);
    let zz1 = z[1] + (p[3] * ay + p[4] * az);
    let zz2 = z[2] + (p[4] * ay + p[5] * az);
    let eps = tau - zz0;
    let dinv = 1.0 / p[0];
    let g1 = p[1] * dinv;
    let g2 = p[2] * dinv;
    let nu = eps * dinv;
    // P⁺ = P − P H Hᵀ P / D: row/column 0 vanish.
    let x11 = p[3] - p[1] * g1;
    let x12 = p[4] - p[1] * g2;
    let x22 = p[5] - p[2] * g2;
    let zp1 = zz1 + g1 * eps;
    let zp2 = zz2 + g2 * eps;
    let r0 = -dz;
    let r1 = dy;
    let y1 = r0 * x11 + r1 * x12;
    let y2 = r0 * x12 + r1 * x22;
    AbaBack {
        g: [1.0, g1, g2],
        nu,
        p,
        z,
        cp: [r0 * y1 + r1 * y2, y1, y2, x11, x12, x22],
        cz: [tau + r0 * zp1 + r1 * zp2, zp1, zp2],
    }
}

/// One backward step across a **prismatic** joint with world axis `h = [0, hy, hz]`.
#[inline(always)]
pub(crate) fn aba_back_pri(
    cp: &Sym3,
    czc: &[f64; 3],
    j: f64,
    m: f64,
    cy: f64,
    cz: f64,
    by: f64,
    bz: f64,
    ay: f64,
    az: f64,
    hy: f64,
    hz: f64,
    tau: f64,
    dy: f64,
    dz: f64,
) -> AbaBack {
    let (p, z) = add_link(cp, czc, j, m, cy, cz, by, bz);
    let zz0 = z[0] + (p[1] * ay + p[2] * az);
    let zz1 = z[1] + (p[3] * ay + p[4] * az);
    let zz2 = z[2] + (p[4] * ay + p[5] * az);
    let ph0 = p[1] * hy + p[2] * hz;
    let ph1 = p[3] * hy + p[4] * hz;
    let ph2 = p[4] * hy + p[5] * hz;
    let dinv = 1.0 / (hy * ph1 + hz * ph2);
    let g = [ph0 * dinv, ph1 * dinv, ph2 * dinv];
    let eps = tau - (hy * zz1 + hz * zz2);
    let nu = eps * dinv;
    let x = [
        p[0] - ph0 * g[0],
        p[1] - ph0 * g[1],
        p[2] - ph0 * g[2],
        p[3] - ph1 * g[1],
        p[4] - ph1 * g[2],
        p[5] - ph2 * g[2],
    ];
    let zp = [zz0 + g[0] * eps, zz1 + g[1] * eps, zz2 + g[2] * eps];
    AbaBack {
        g,
        nu,
        p,
        z,
        cp: congruence(&x, dy, dz),
        cz: force_transport(&zp, dy, dz),
    }
}

/// Backward step across a **locked** joint (pseudo joint, seed §3.4): no innovation, the whole
/// articulated inertia passes to the parent: `P⁺ = P`, `z⁺ = z + P a`.
#[inline(always)]
pub(crate) fn aba_back_locked(
    cp: &Sym3,
    czc: &[f64; 3],
    j: f64,
    m: f64,
    cy: f64,
    cz: f64,
    by: f64,
    bz: f64,
    ay: f64,
    az: f64,
    dy: f64,
    dz: f64,
) -> AbaBack {
    let (p, z) = add_link(cp, czc, j, m, cy, cz, by, bz);
    let zz = [
        z[0] + (p[1] * ay + p[2] * az),
        z[1] + (p[3] * ay + p[4] * az),
        z[2] + (p[4] * ay + p[5] * az),
    ];
    AbaBack {
        g: [0.0, 0.0, 0.0],
        nu: 0.0,
        p,
        z,
        cp: congruence(&p, dy, dz),
        cz: force_transport(&zz, dy, dz),
    }
}

/// Forward step across a revolute joint: `Ā = Φ A_p`, `q̈ = ν − Gᵀ Ā`, `A = Ā + H q̈ + a`.
/// Returns `(q̈, A)`.
#[inline(always)]
pub(crate) fn aba_fwd_rev(
    ap: &[f64; 3],
    g1: f64,
    g2: f64,
    nu: f64,
    ay: f64,
    az: f64,
    dy: f64,
    dz: f64,
) -> (f64, [f64; 3]) {
    let ab = motion_transport(ap, dy, dz);
    let qdd = nu - (ab[0] + g1 * ab[1] + g2 * ab[2]);
    (qdd, [ab[0] + qdd, ab[1] + ay, ab[2] + az])
}

/// Forward step across a prismatic joint with world axis `h`.
#[inline(always)]
pub(crate) fn aba_fwd_pri(
    ap: &[f64; 3],
    g: &[f64; 3],
    nu: f64,
    ay: f64,
    az: f64,
    hy: f64,
    hz: f64,
    dy: f64,
    dz: f64,
) -> (f64, [f64; 3]) {
    let ab = motion_transport(ap, dy, dz);
    let qdd = nu - (g[0] * ab[0] + g[1] * ab[1] + g[2] * ab[2]);
    (
        qdd,
        [ab[0], ab[1] + (hy * qdd + ay), ab[2] + (hz * qdd + az)],
    )
}

// ---------------------------------------------------------------------------------------------
// RNEA (seed eq. 2.50, 2.57, 2.61).
// ---------------------------------------------------------------------------------------------

/// Forward acceleration step of RNEA: `A = Φ A_p + H q̈ + a` (revolute).
#[inline(always)]
pub(crate) fn rnea_fwd_rev<T: Scalar>(ap: &[T; 3], qdd: T, ay: T, az: T, dy: T, dz: T) -> [T; 3] {
    let ab = motion_transport(ap, dy, dz);
    [ab[0] + qdd, ab[1] + ay, ab[2] + az]
}

/// Forward acceleration step of RNEA (prismatic).
#[inline(always)]
pub(crate) fn rnea_fwd_pri<T: Scalar>(
    ap: &[T; 3],
    qdd: T,
    ay: T,
    az: T,
    hy: T,
    hz: T,
    dy: T,
    dz: T,
) -> [T; 3] {
    let ab = motion_transport(ap, dy, dz);
    [ab[0], ab[1] + (hy * qdd + ay), ab[2] + (hz * qdd + az)]
}

/// Backward force step of RNEA (seed eq. 2.57): `F = Φᵀ_{k+1,k} F_{k+1} + M A + b`, where
/// `cf = Φᵀ F_{k+1}` is carried from the child. Returns `F`.
#[inline(always)]
pub(crate) fn rnea_back<T: Scalar>(
    cf: &[T; 3],
    a: &[T; 3],
    j: T,
    m: T,
    cy: T,
    cz: T,
    by: T,
    bz: T,
) -> [T; 3] {
    let mcy = m * cy;
    let mcz = m * cz;
    let ma0 = j * a[0] + (mcy * a[2] - mcz * a[1]);
    let ma1 = m * a[1] - mcz * a[0];
    let ma2 = m * a[2] + mcy * a[0];
    [cf[0] + ma0, cf[1] + (ma1 + by), cf[2] + (ma2 + bz)]
}
