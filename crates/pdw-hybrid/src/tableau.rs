//! Butcher tableaux of the three methods, as used by the stage kernels.
//!
//! Stage numbering is zero-based: `k₀ = f(x₀)` (kept from the previous step: first same as last),
//! `k_q = f(x₀ + h Σ_{p<q} a_{qp} k_p)`. The *last* stage of every method is evaluated at the new
//! state `x₁ = x₀ + h Σ b_p k_p`, so that `k_last = f(x₁)` becomes the next step's `k₀` and the
//! right end of the Hermite interpolant. This costs nothing for DOPRI5 (its 7th stage is `f(x₁)`)
//! and is the FSAL evaluation of DOP853 and RK4.
//!
//! Sources: classical RK4 (Hairer–Nørsett–Wanner I, Table II.1.2); DOPRI5 = Dormand & Prince
//! 1980, RK5(4)7M, with the dense output of Shampine 1986 (HNW I, Table II.5.2 and eq. II.6.12);
//! DOP853 = Dormand & Prince 8(5,3) with the 7th-order dense output of HNW I, §II.10 (coefficients
//! as tabulated for the code DOP853 of Hairer & Wanner).
//!
//! Coefficients carry the published 30 digits; the compiler rounds them to the nearest f64.
#![allow(clippy::excessive_precision, clippy::unreadable_literal)]

/// Method-specific constants: stage rows, error weights, dense-output weights, controller.
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub struct Tableau {
    /// Number of stage blocks evaluated per attempt, including `k₀` and the final `f(x₁)`.
    pub n_stages: usize,
    /// `a[q]` = row q of the stage matrix (length q), for q = 1..n_stages; `a[0]` is empty.
    /// The last row holds the weights b.
    pub a: &'static [&'static [f64]],
    /// Order p used in the initial-step heuristic exponent 1/p (HNW II.4, code convention).
    pub hinit_order: f64,
    /// Step-size controller (HNW II.4 eq. 4.13 with the PI stabilisation of §IV.2):
    /// exponent α of `err^α`, PI weight β, clamps of h_new/h, safety factor.
    pub alpha: f64,
    pub beta: f64,
    pub fac_min: f64,
    pub fac_max: f64,
    pub safety: f64,
}

// Stage rows as constants (the one-lane kernels use them directly so that the compiler can
// unroll the sums); the tableaux below reference them.

pub(crate) const RK4_A1: [f64; 1] = [0.5];
pub(crate) const RK4_A2: [f64; 2] = [0.0, 0.5];
pub(crate) const RK4_A3: [f64; 3] = [0.0, 0.0, 1.0];
pub(crate) const RK4_A4: [f64; 4] = [1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0];

/// Classical fourth-order Runge–Kutta (c = 0, ½, ½, 1; b = ⅙, ⅓, ⅓, ⅙).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub static RK4: Tableau = Tableau {
    n_stages: 5,
    a: &[&[], &RK4_A1, &RK4_A2, &RK4_A3, &RK4_A4],
    hinit_order: 4.0,
    alpha: 0.0,
    beta: 0.0,
    fac_min: 1.0,
    fac_max: 1.0,
    safety: 1.0,
};

pub(crate) const DP5_A1: [f64; 1] = [1.0 / 5.0];
pub(crate) const DP5_A2: [f64; 2] = [3.0 / 40.0, 9.0 / 40.0];
pub(crate) const DP5_A3: [f64; 3] = [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0];
pub(crate) const DP5_A4: [f64; 4] = [
    19372.0 / 6561.0,
    -25360.0 / 2187.0,
    64448.0 / 6561.0,
    -212.0 / 729.0,
];
pub(crate) const DP5_A5: [f64; 5] = [
    9017.0 / 3168.0,
    -355.0 / 33.0,
    46732.0 / 5247.0,
    49.0 / 176.0,
    -5103.0 / 18656.0,
];
pub(crate) const DP5_A6: [f64; 6] = [
    35.0 / 384.0,
    0.0,
    500.0 / 1113.0,
    125.0 / 192.0,
    -2187.0 / 6784.0,
    11.0 / 84.0,
];

/// Dormand–Prince 5(4) (HNW I, Table II.5.2). The 7th row equals b (FSAL).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub static DOPRI5: Tableau = Tableau {
    n_stages: 7,
    a: &[&[], &DP5_A1, &DP5_A2, &DP5_A3, &DP5_A4, &DP5_A5, &DP5_A6],
    hinit_order: 5.0,
    // HNW's dopri5 defaults: β = 0.04, α = 1/5 − 0.75 β, h_new/h ∈ [0.2, 10], safety 0.9.
    alpha: 0.2 - 0.75 * 0.04,
    beta: 0.04,
    fac_min: 0.2,
    fac_max: 10.0,
    safety: 0.9,
};

/// DOPRI5 with the elementary controller ([`crate::Controller::Elementary`]): β = 0,
/// α = 1/5 (HNW I eq. II.4.13 without the PI term; the code dopri5 with `WORK(5) = BETA = 0`);
/// everything else as [`DOPRI5`].
pub(crate) static DOPRI5_ELEMENTARY: Tableau = Tableau {
    n_stages: 7,
    a: &[&[], &DP5_A1, &DP5_A2, &DP5_A3, &DP5_A4, &DP5_A5, &DP5_A6],
    hinit_order: 5.0,
    alpha: 0.2,
    beta: 0.0,
    fac_min: 0.2,
    fac_max: 10.0,
    safety: 0.9,
};

/// DOPRI5 error weights e = b − b̂ over k₀..k₆ (HNW I, Table II.5.2).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub const DOPRI5_E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

/// Shampine's 4th-order dense output for DOPRI5 (HNW I, eq. II.6.12, as in the code DOPRI5):
/// fifth interpolation coefficient `h Σ d_q k_q` over k₀..k₆.
pub(crate) const DOPRI5_D: [f64; 7] = [
    -12715105075.0 / 11282082432.0,
    0.0,
    87487479700.0 / 32700410799.0,
    -10690763975.0 / 1880347072.0,
    701980252875.0 / 199316789632.0,
    -1453857185.0 / 822651844.0,
    69997945.0 / 29380423.0,
];

const A21: f64 = 5.26001519587677318785587544488e-2;
const A31: f64 = 1.97250569845378994544595329183e-2;
const A32: f64 = 5.91751709536136983633785987549e-2;
const A41: f64 = 2.95875854768068491816892993775e-2;
const A43: f64 = 8.87627564304205475450678981324e-2;
const A51: f64 = 2.41365134159266685502369798665e-1;
const A53: f64 = -8.84549479328286085344864962717e-1;
const A54: f64 = 9.24834003261792003115737966543e-1;
const A61: f64 = 3.7037037037037037037037037037e-2;
const A64: f64 = 1.70828608729473871279604482173e-1;
const A65: f64 = 1.25467687566822425016691814123e-1;
const A71: f64 = 3.7109375e-2;
const A74: f64 = 1.70252211019544039314978060272e-1;
const A75: f64 = 6.02165389804559606850219397283e-2;
const A76: f64 = -1.7578125e-2;
const A81: f64 = 3.70920001185047927108779319836e-2;
const A84: f64 = 1.70383925712239993810214054705e-1;
const A85: f64 = 1.07262030446373284651809199168e-1;
const A86: f64 = -1.53194377486244017527936158236e-2;
const A87: f64 = 8.27378916381402288758473766002e-3;
const A91: f64 = 6.24110958716075717114429577812e-1;
const A94: f64 = -3.36089262944694129406857109825e0;
const A95: f64 = -8.68219346841726006818189891453e-1;
const A96: f64 = 2.75920996994467083049415600797e1;
const A97: f64 = 2.01540675504778934086186788979e1;
const A98: f64 = -4.34898841810699588477366255144e1;
const A101: f64 = 4.77662536438264365890433908527e-1;
const A104: f64 = -2.48811461997166764192642586468e0;
const A105: f64 = -5.90290826836842996371446475743e-1;
const A106: f64 = 2.12300514481811942347288949897e1;
const A107: f64 = 1.52792336328824235832596922938e1;
const A108: f64 = -3.32882109689848629194453265587e1;
const A109: f64 = -2.03312017085086261358222928593e-2;
const A111: f64 = -9.3714243008598732571704021658e-1;
const A114: f64 = 5.18637242884406370830023853209e0;
const A115: f64 = 1.09143734899672957818500254654e0;
const A116: f64 = -8.14978701074692612513997267357e0;
const A117: f64 = -1.85200656599969598641566180701e1;
const A118: f64 = 2.27394870993505042818970056734e1;
const A119: f64 = 2.49360555267965238987089396762e0;
const A1110: f64 = -3.0467644718982195003823669022e0;
const A121: f64 = 2.27331014751653820792359768449e0;
const A124: f64 = -1.05344954667372501984066689879e1;
const A125: f64 = -2.00087205822486249909675718444e0;
const A126: f64 = -1.79589318631187989172765950534e1;
const A127: f64 = 2.79488845294199600508499808837e1;
const A128: f64 = -2.85899827713502369474065508674e0;
const A129: f64 = -8.87285693353062954433549289258e0;
const A1210: f64 = 1.23605671757943030647266201528e1;
const A1211: f64 = 6.43392746015763530355970484046e-1;
const B1: f64 = 5.42937341165687622380535766363e-2;
const B6: f64 = 4.45031289275240888144113950566e0;
const B7: f64 = 1.89151789931450038304281599044e0;
const B8: f64 = -5.8012039600105847814672114227e0;
const B9: f64 = 3.1116436695781989440891606237e-1;
const B10: f64 = -1.52160949662516078556178806805e-1;
const B11: f64 = 2.01365400804030348374776537501e-1;
const B12: f64 = 4.47106157277725905176885569043e-2;

pub(crate) const DOP_A1: [f64; 1] = [A21];
pub(crate) const DOP_A2: [f64; 2] = [A31, A32];
pub(crate) const DOP_A3: [f64; 3] = [A41, 0.0, A43];
pub(crate) const DOP_A4: [f64; 4] = [A51, 0.0, A53, A54];
pub(crate) const DOP_A5: [f64; 5] = [A61, 0.0, 0.0, A64, A65];
pub(crate) const DOP_A6: [f64; 6] = [A71, 0.0, 0.0, A74, A75, A76];
pub(crate) const DOP_A7: [f64; 7] = [A81, 0.0, 0.0, A84, A85, A86, A87];
pub(crate) const DOP_A8: [f64; 8] = [A91, 0.0, 0.0, A94, A95, A96, A97, A98];
pub(crate) const DOP_A9: [f64; 9] = [A101, 0.0, 0.0, A104, A105, A106, A107, A108, A109];
pub(crate) const DOP_A10: [f64; 10] = [A111, 0.0, 0.0, A114, A115, A116, A117, A118, A119, A1110];
pub(crate) const DOP_A11: [f64; 11] = [
    A121, 0.0, 0.0, A124, A125, A126, A127, A128, A129, A1210, A1211,
];
/// The weights b (last stage row).
pub(crate) const DOP_A12: [f64; 12] = [B1, 0.0, 0.0, 0.0, 0.0, B6, B7, B8, B9, B10, B11, B12];

/// Dormand–Prince 8(5,3): 12 stages plus `f(x₁)` (the 13th block, FSAL).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub static DOP853: Tableau = Tableau {
    n_stages: 13,
    a: &[
        &[],
        &DOP_A1,
        &DOP_A2,
        &DOP_A3,
        &DOP_A4,
        &DOP_A5,
        &DOP_A6,
        &DOP_A7,
        &DOP_A8,
        &DOP_A9,
        &DOP_A10,
        &DOP_A11,
        &DOP_A12,
    ],
    hinit_order: 8.0,
    // HNW's dop853 defaults: β = 0, α = 1/8, h_new/h ∈ [0.333, 6], safety 0.9.
    alpha: 1.0 / 8.0,
    beta: 0.0,
    fac_min: 0.333,
    fac_max: 6.0,
    safety: 0.9,
};

/// DOP853 weights b over k₀..k₁₁ (the last stage row).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub const DOP853_B: [f64; 12] = DOP_A12;

/// DOP853 fifth-order error weights over k₀..k₁₁.
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub const DOP853_ER: [f64; 12] = [
    0.1312004499419488073250102996e-01,
    0.0,
    0.0,
    0.0,
    0.0,
    -0.1225156446376204440720569753e+01,
    -0.4957589496572501915214079952e+00,
    0.1664377182454986536961530415e+01,
    -0.3503288487499736816886487290e+00,
    0.3341791187130174790297318841e+00,
    0.8192320648511571246570742613e-01,
    -0.2235530786388629525884427845e-01,
];

/// DOP853 third-order embedded weights on k₀, k₈, k₁₁ (the `bhh` of the code).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub const DOP853_BHH: [f64; 3] = [
    0.244094488188976377952755905512e+00,
    0.733846688281611857341361741547e+00,
    0.220588235294117647058823529412e-01,
];

/// Rows of the three extra dense-output stages k₁₃, k₁₄, k₁₅ (c = 0.1, 0.2, 7/9) over k₀..k₁₄
/// (HNW I, §II.10), one constant per row: the dense-output build sums them with
/// compile-time weights.
pub(crate) const DOP853_DENSE_A13: [f64; 13] = [
    5.61675022830479523392909219681e-2,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    2.53500210216624811088794765333e-1,
    -2.46239037470802489917441475441e-1,
    -1.24191423263816360469010140626e-1,
    1.5329179827876569731206322685e-1,
    8.20105229563468988491666602057e-3,
    7.56789766054569976138603589584e-3,
    -8.298e-3,
];
pub(crate) const DOP853_DENSE_A14: [f64; 14] = [
    3.18346481635021405060768473261e-2,
    0.0,
    0.0,
    0.0,
    0.0,
    2.83009096723667755288322961402e-2,
    5.35419883074385676223797384372e-2,
    -5.49237485713909884646569340306e-2,
    0.0,
    0.0,
    -1.08347328697249322858509316994e-4,
    3.82571090835658412954920192323e-4,
    -3.40465008687404560802977114492e-4,
    1.41312443674632500278074618366e-1,
];
pub(crate) const DOP853_DENSE_A15: [f64; 15] = [
    -4.28896301583791923408573538692e-1,
    0.0,
    0.0,
    0.0,
    0.0,
    -4.69762141536116384314449447206e0,
    7.68342119606259904184240953878e0,
    4.06898981839711007970213554331e0,
    3.56727187455281109270669543021e-1,
    0.0,
    0.0,
    0.0,
    -1.39902416515901462129418009734e-3,
    2.9475147891527723389556272149e0,
    -9.15095847217987001081870187138e0,
];

/// The three rows above as slices (row r computes stage 13 + r).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub const DOP853_DENSE_A: [&[f64]; 3] = [&DOP853_DENSE_A13, &DOP853_DENSE_A14, &DOP853_DENSE_A15];

/// Weights of the four higher dense-output coefficients over k₀..k₁₅ (the `d` of HNW §II.10).
pub(crate) const DOP853_D: [[f64; 16]; 4] = [
    [
        -0.84289382761090128651353491142e+01,
        0.0,
        0.0,
        0.0,
        0.0,
        0.56671495351937776962531783590e+00,
        -0.30689499459498916912797304727e+01,
        0.23846676565120698287728149680e+01,
        0.21170345824450282767155149946e+01,
        -0.87139158377797299206789907490e+00,
        0.22404374302607882758541771650e+01,
        0.63157877876946881815570249290e+00,
        -0.88990336451333310820698117400e-01,
        0.18148505520854727256656404962e+02,
        -0.91946323924783554000451984436e+01,
        -0.44360363875948939664310572000e+01,
    ],
    [
        0.10427508642579134603413151009e+02,
        0.0,
        0.0,
        0.0,
        0.0,
        0.24228349177525818288430175319e+03,
        0.16520045171727028198505394887e+03,
        -0.37454675472269020279518312152e+03,
        -0.22113666853125306036270938578e+02,
        0.77334326684722638389603898808e+01,
        -0.30674084731089398182061213626e+02,
        -0.93321305264302278729567221706e+01,
        0.15697238121770843886131091075e+02,
        -0.31139403219565177677282850411e+02,
        -0.93529243588444783865713862664e+01,
        0.35816841486394083752465898540e+02,
    ],
    [
        0.19985053242002433820987653617e+02,
        0.0,
        0.0,
        0.0,
        0.0,
        -0.38703730874935176555105901742e+03,
        -0.18917813819516756882830838328e+03,
        0.52780815920542364900561016686e+03,
        -0.11573902539959630126141871134e+02,
        0.68812326946963000169666922661e+01,
        -0.10006050966910838403183860980e+01,
        0.77771377980534432092869265740e+00,
        -0.27782057523535084065932004339e+01,
        -0.60196695231264120758267380846e+02,
        0.84320405506677161018159903784e+02,
        0.11992291136182789328035130030e+02,
    ],
    [
        -0.25693933462703749003312586129e+02,
        0.0,
        0.0,
        0.0,
        0.0,
        -0.15418974869023643374053993627e+03,
        -0.23152937917604549567536039109e+03,
        0.35763911791061412378285349910e+03,
        0.93405324183624310003907691704e+02,
        -0.37458323136451633156875139351e+02,
        0.10409964950896230045147246184e+03,
        0.29840293426660503123344363579e+02,
        -0.43533456590011143754432175058e+02,
        0.96324553959188282948394950600e+02,
        -0.39177261675615439165231486172e+02,
        -0.14972683625798562581422125276e+03,
    ],
];
