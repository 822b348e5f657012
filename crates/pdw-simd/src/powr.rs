//! `x^a` for `x ≥ 0` in plain IEEE-754 arithmetic, for the step-size controller.
//!
//! The controller raises the error norm to a fixed power every step (HNW I eq. II.4.13:
//! `err^α`, and `facold^β` for the PI form), and the next step waits for that value: its
//! latency is on the integrator's critical path. glibc's `pow` is correctly rounded but costs
//! about as much as a right-hand side of the simplest walker, and its result is glibc's, not
//! ours. [`powr`] computes `exp(a·ln x)` by the table-driven reductions of Tang (ACM TOMS 15,
//! 1989, for `exp`; 16, 1990, for `ln`) — formulas, not code:
//! - `ln x = e·ln 2 + ln(1/ĉᵢ) + log1p(r)`, `x = m·2^e`, `m ∈ [1, 2)`, `i` the top 7 bits of
//!   m's fraction, `ĉᵢ` the f64 nearest `1/cᵢ` with `cᵢ = 1 + (i + ½)/128`, `r = m·ĉᵢ − 1`
//!   (`|r| < 0.0039`), `log1p r = r − r²/2 + … − r⁶/6` (truncation `< r⁷/7 ≈ 2e−18`), the
//!   table `ln(1/ĉᵢ)` correctly rounded from 60-digit values;
//! - `exp(y) = 2^n·2^(j/64)·exp(r)`, `k = n·64 + j = round(y·64/ln 2)`, `r = y − k·(ln 2/64)`
//!   (`|r| ≤ ln 2/128`; `ln 2/64` split into a high part with a short mantissa and a low part,
//!   Cody–Waite), `exp r` to degree 5 (truncation `< r⁶/720 ≈ 4e−17`), the table `2^(j/64)`
//!   correctly rounded;
//!
//! so there is no division and both polynomials are short: about 70 cycles of latency where the
//! series forms (`atanh` to degree 19, `exp` to degree 13) took about 110. The relative error is
//! at most about `4ε·max(1, |a·ln x|)` (the rounding of `y` carries over into `exp`), tested
//! against `f64::powf` over 1e−300…1e300; for the controller's arguments (`err ∈ [1e−10, 1e10]`,
//! `|a| ≤ 0.2`) that is below 5e−15. It uses `+ − ×`, table look-ups and bit manipulation only:
//! the same bits on every path and every libm.
//!
//! Domain: `x = 0` gives 0 for `a > 0`, `x = +∞` gives +∞ for `a > 0`, NaN or `x < 0` gives NaN;
//! subnormal `x` is scaled into the normal range first. `a` must be finite.

/// ln 2 with its last 21 mantissa bits zero: `e·LN2_HI` is exact for `|e| < 2¹¹`.
// Public, hidden from the docs, for the integration tests (crates/pdw-hybrid/tests/simd.rs).
#[doc(hidden)]
pub const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
/// ln 2 − LN2_HI, rounded.
// Public, hidden from the docs, for the integration tests (crates/pdw-hybrid/tests/simd.rs).
#[doc(hidden)]
pub const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
// Public, hidden from the docs, for the integration tests (crates/pdw-hybrid/tests/simd.rs).
#[doc(hidden)]
pub const LN2: f64 = std::f64::consts::LN_2;
/// ln 2/64 with its last 21 mantissa bits zero: `k·STEP_HI` is exact for `|k| < 2²¹`.
// Public, hidden from the docs, for the integration tests (crates/pdw-hybrid/tests/simd.rs).
#[doc(hidden)]
pub const STEP_HI: f64 = f64::from_bits(0x3f86_2e42_fee0_0000);
/// ln 2/64 − STEP_HI, rounded.
// Public, hidden from the docs, for the integration tests (crates/pdw-hybrid/tests/simd.rs).
#[doc(hidden)]
pub const STEP_LO: f64 = f64::from_bits(0x3d8a_39ef_3579_3c76);
/// 64/ln 2, rounded.
// Public, hidden from the docs, for the integration tests (crates/pdw-hybrid/tests/simd.rs).
#[doc(hidden)]
pub const INV_STEP: f64 = f64::from_bits(0x4057_1547_652b_82fe);
const ROUND: f64 = 6_755_399_441_055_744.0;

// Tables (bit patterns of f64), generated with 60-digit decimal arithmetic:
// `INV_C[i]` = the f64 nearest 1/cᵢ, cᵢ = 1 + (i + ½)/128; `LN_C[i]` = ln(1/INV_C[i]) rounded;
// `EXP2_J[j]` = 2^(j/64) rounded.
// Public, hidden from the docs, for the integration tests (crates/pdw-hybrid/tests/simd.rs).
#[doc(hidden)]
pub const INV_C: [u64; 128] = [
    0x3fefe01fe01fe020,
    0x3fefa11caa01fa12,
    0x3fef6310aca0dbb5,
    0x3fef25f644230ab5,
    0x3feee9c7f8458e02,
    0x3feeae807aba01eb,
    0x3fee741aa59750e4,
    0x3fee3a9179dc1a73,
    0x3fee01e01e01e01e,
    0x3fedca01dca01dca,
    0x3fed92f2231e7f8a,
    0x3fed5cac807572b2,
    0x3fed272ca3fc5b1a,
    0x3fecf26e5c44bfc6,
    0x3fecbe6d9601cbe7,
    0x3fec8b265afb8a42,
    0x3fec5894d10d4986,
    0x3fec26b5392ea01c,
    0x3febf583ee868d8b,
    0x3febc4fd65883e7b,
    0x3feb951e2b18ff23,
    0x3feb65e2e3beee05,
    0x3feb37484ad806ce,
    0x3feb094b31d922a4,
    0x3feadbe87f94905e,
    0x3feaaf1d2f87ebfd,
    0x3fea82e65130e159,
    0x3fea574107688a4a,
    0x3fea2c2a87c51ca0,
    0x3fea01a01a01a01a,
    0x3fe9d79f176b682d,
    0x3fe9ae24ea5510da,
    0x3fe9852f0d8ec0ff,
    0x3fe95cbb0be377ae,
    0x3fe934c67f9b2ce6,
    0x3fe90d4f120190d5,
    0x3fe8e6527af1373f,
    0x3fe8bfce8062ff3a,
    0x3fe899c0f601899c,
    0x3fe87427bcc092b9,
    0x3fe84f00c2780614,
    0x3fe82a4a0182a4a0,
    0x3fe8060180601806,
    0x3fe7e225515a4f1d,
    0x3fe7beb3922e017c,
    0x3fe79baa6bb6398b,
    0x3fe77908119ac60d,
    0x3fe756cac201756d,
    0x3fe734f0c541fe8d,
    0x3fe713786d9c7c09,
    0x3fe6f26016f26017,
    0x3fe6d1a62681c861,
    0x3fe6b1490aa31a3d,
    0x3fe691473a88d0c0,
    0x3fe6719f3601671a,
    0x3fe6524f853b4aa3,
    0x3fe63356b88ac0de,
    0x3fe614b36831ae94,
    0x3fe5f66434292dfc,
    0x3fe5d867c3ece2a5,
    0x3fe5babcc647fa91,
    0x3fe59d61f123ccaa,
    0x3fe5805601580560,
    0x3fe56397ba7c52e2,
    0x3fe54725e6bb82fe,
    0x3fe52aff56a8054b,
    0x3fe50f22e111c4c5,
    0x3fe4f38f62dd4c9b,
    0x3fe4d843bedc2c4c,
    0x3fe4bd3edda68fe1,
    0x3fe4a27fad76014a,
    0x3fe4880522014880,
    0x3fe46dce34596066,
    0x3fe453d9e2c776ca,
    0x3fe43a2730abee4d,
    0x3fe420b5265e5951,
    0x3fe40782d10e6566,
    0x3fe3ee8f42a5af07,
    0x3fe3d5d991aa75c6,
    0x3fe3bd60d9232955,
    0x3fe3a524387ac822,
    0x3fe38d22d366088e,
    0x3fe3755bd1c945ee,
    0x3fe35dce5f9f2af8,
    0x3fe34679ace01346,
    0x3fe32f5ced6a1dfa,
    0x3fe3187758e9ebb6,
    0x3fe301c82ac40260,
    0x3fe2eb4ea1fed14b,
    0x3fe2d50a012d50a0,
    0x3fe2bef98e5a3711,
    0x3fe2a91c92f3c105,
    0x3fe293725bb804a5,
    0x3fe27dfa38a1ce4d,
    0x3fe268b37cd60127,
    0x3fe2539d7e9177b2,
    0x3fe23eb79717605b,
    0x3fe22a0122a0122a,
    0x3fe21579804855e6,
    0x3fe2012012012012,
    0x3fe1ecf43c7fb84c,
    0x3fe1d8f5672e4abd,
    0x3fe1c522fc1ce059,
    0x3fe1b17c67f2bae3,
    0x3fe19e0119e0119e,
    0x3fe18ab083902bdb,
    0x3fe1778a191bd684,
    0x3fe1648d50fc3201,
    0x3fe151b9a3fdd5c9,
    0x3fe13f0e8d344724,
    0x3fe12c8b89edc0ac,
    0x3fe11a3019a74826,
    0x3fe107fbbe011080,
    0x3fe0f5edfab325a2,
    0x3fe0e40655826011,
    0x3fe0d24456359e3a,
    0x3fe0c0a7868b4171,
    0x3fe0af2f722eecb5,
    0x3fe09ddba6af8360,
    0x3fe08cabb37565e2,
    0x3fe07b9f29b8eae2,
    0x3fe06ab59c7912fb,
    0x3fe059eea0727586,
    0x3fe04949cc1664c5,
    0x3fe038c6b78247fc,
    0x3fe02864fc7729e9,
    0x3fe0182436517a37,
    0x3fe0080402010080,
];
// Public, hidden from the docs, for the integration tests (crates/pdw-hybrid/tests/simd.rs).
#[doc(hidden)]
pub const LN_C: [u64; 128] = [
    0x3f6ff00aa2b10ba0,
    0x3f87dc475f810a69,
    0x3f93cea44346a584,
    0x3f9b9fc027af919a,
    0x3fa1b0d98923d97f,
    0x3fa58a5bafc8e4d3,
    0x3fa95c830ec8e3f2,
    0x3fad276b8adb0b56,
    0x3fb075983598e471,
    0x3fb253f62f0a1417,
    0x3fb42edcbea646ee,
    0x3fb60658a93750c4,
    0x3fb7da766d7b12d0,
    0x3fb9ab42462033ae,
    0x3fbb78c82bb0eda0,
    0x3fbd4313d66cb35d,
    0x3fbf0a30c01162a4,
    0x3fc0671512ca596f,
    0x3fc14785846742ac,
    0x3fc2266f190a5acd,
    0x3fc303d718e47fd5,
    0x3fc3dfc2b0ecc62a,
    0x3fc4ba36f39a55e5,
    0x3fc59338d9982085,
    0x3fc66acd4272ad51,
    0x3fc740f8f54037a3,
    0x3fc815c0a14357e9,
    0x3fc8e928de886d41,
    0x3fc9bb362e7dfb85,
    0x3fca8becfc882f19,
    0x3fcb5b519e8fb5a6,
    0x3fcc2968558c18c2,
    0x3fccf6354e09c5dd,
    0x3fcdc1bca0abec7b,
    0x3fce8c0252aa5a60,
    0x3fcf550a564b7b37,
    0x3fd00e6c45ad501d,
    0x3fd071b85fcd590d,
    0x3fd0d46b579ab74b,
    0x3fd136870293a8b0,
    0x3fd1980d2dd4236f,
    0x3fd1f8ff9e48a2f3,
    0x3fd2596010df763a,
    0x3fd2b9303ab89d25,
    0x3fd31871c9544185,
    0x3fd3772662bfd85c,
    0x3fd3d54fa5c1f710,
    0x3fd432ef2a04e813,
    0x3fd49006804009d0,
    0x3fd4ec9732600269,
    0x3fd548a2c3add263,
    0x3fd5a42ab0f4cfe2,
    0x3fd5ff3070a793d4,
    0x3fd659b57303e1f2,
    0x3fd6b3bb2235943d,
    0x3fd70d42e2789236,
    0x3fd7664e1239dbcf,
    0x3fd7bede0a37afbf,
    0x3fd816f41da0d495,
    0x3fd86e919a330ba1,
    0x3fd8c5b7c858b48b,
    0x3fd91c67eb45a83e,
    0x3fd972a341135159,
    0x3fd9c86b02dc0862,
    0x3fda1dc064d5b995,
    0x3fda72a4966bd9e9,
    0x3fdac718c258b0e5,
    0x3fdb1b1e0ebdfc5a,
    0x3fdb6eb59d3cf35c,
    0x3fdbc1e08b0dad0a,
    0x3fdc149ff115f027,
    0x3fdc66f4e3ff6ff9,
    0x3fdcb8e0744d7aca,
    0x3fdd0a63ae721e64,
    0x3fdd5b7f9ae2c684,
    0x3fddac353e2c5955,
    0x3fddfc859906d5b5,
    0x3fde4c71a8687704,
    0x3fde9bfa659861f5,
    0x3fdeeb20c640ddf3,
    0x3fdf39e5bc811e5d,
    0x3fdf884a36fe9ec1,
    0x3fdfd64f20f61571,
    0x3fe011fab125ff8a,
    0x3fe0389eefce633c,
    0x3fe05f14bd26459c,
    0x3fe0855c884b450e,
    0x3fe0ab76bece14d2,
    0x3fe0d163ccb9d6b8,
    0x3fe0f7241c9b497d,
    0x3fe11cb81787ccf8,
    0x3fe1422025243d45,
    0x3fe1675cababa60e,
    0x3fe18c6e0ff5cf07,
    0x3fe1b154b57da29e,
    0x3fe1d610fe677003,
    0x3fe1faa34b87094c,
    0x3fe21f0bfc65beec,
    0x3fe2434b6f483934,
    0x3fe26762013430e0,
    0x3fe28b500df60783,
    0x3fe2af15f02640ac,
    0x3fe2d2b4012edc9d,
    0x3fe2f62a99509546,
    0x3fe3197a0fa7fe6a,
    0x3fe33ca2ba328994,
    0x3fe35fa4edd36ea0,
    0x3fe38280fe58797f,
    0x3fe3a5373e7ebdf9,
    0x3fe3c7c7fff73206,
    0x3fe3ea33936b2f5b,
    0x3fe40c7a4880dcea,
    0x3fe42e9c6ddf80bf,
    0x3fe4509a5133bb0a,
    0x3fe472743f33aaad,
    0x3fe4942a83a2fc07,
    0x3fe4b5bd6956e273,
    0x3fe4d72d3a39fd01,
    0x3fe4f87a3f5026e9,
    0x3fe519a4c0ba3446,
    0x3fe53aad05b99b7c,
    0x3fe55b9354b40bce,
    0x3fe57c57f336f191,
    0x3fe59cfb25fae87f,
    0x3fe5bd7d30e71c73,
    0x3fe5ddde57149923,
    0x3fe5fe1edad18919,
    0x3fe61e3efda46467,
];
// Public, hidden from the docs, for the integration tests (crates/pdw-hybrid/tests/simd.rs).
#[doc(hidden)]
pub const EXP2_J: [u64; 64] = [
    0x3ff0000000000000,
    0x3ff02c9a3e778061,
    0x3ff059b0d3158574,
    0x3ff0874518759bc8,
    0x3ff0b5586cf9890f,
    0x3ff0e3ec32d3d1a2,
    0x3ff11301d0125b51,
    0x3ff1429aaea92de0,
    0x3ff172b83c7d517b,
    0x3ff1a35beb6fcb75,
    0x3ff1d4873168b9aa,
    0x3ff2063b88628cd6,
    0x3ff2387a6e756238,
    0x3ff26b4565e27cdd,
    0x3ff29e9df51fdee1,
    0x3ff2d285a6e4030b,
    0x3ff306fe0a31b715,
    0x3ff33c08b26416ff,
    0x3ff371a7373aa9cb,
    0x3ff3a7db34e59ff7,
    0x3ff3dea64c123422,
    0x3ff4160a21f72e2a,
    0x3ff44e086061892d,
    0x3ff486a2b5c13cd0,
    0x3ff4bfdad5362a27,
    0x3ff4f9b2769d2ca7,
    0x3ff5342b569d4f82,
    0x3ff56f4736b527da,
    0x3ff5ab07dd485429,
    0x3ff5e76f15ad2148,
    0x3ff6247eb03a5585,
    0x3ff6623882552225,
    0x3ff6a09e667f3bcd,
    0x3ff6dfb23c651a2f,
    0x3ff71f75e8ec5f74,
    0x3ff75feb564267c9,
    0x3ff7a11473eb0187,
    0x3ff7e2f336cf4e62,
    0x3ff82589994cce13,
    0x3ff868d99b4492ed,
    0x3ff8ace5422aa0db,
    0x3ff8f1ae99157736,
    0x3ff93737b0cdc5e5,
    0x3ff97d829fde4e50,
    0x3ff9c49182a3f090,
    0x3ffa0c667b5de565,
    0x3ffa5503b23e255d,
    0x3ffa9e6b5579fdbf,
    0x3ffae89f995ad3ad,
    0x3ffb33a2b84f15fb,
    0x3ffb7f76f2fb5e47,
    0x3ffbcc1e904bc1d2,
    0x3ffc199bdd85529c,
    0x3ffc67f12e57d14b,
    0x3ffcb720dcef9069,
    0x3ffd072d4a07897c,
    0x3ffd5818dcfba487,
    0x3ffda9e603db3285,
    0x3ffdfc97337b9b5f,
    0x3ffe502ee78b3ff6,
    0x3ffea4afa2a490da,
    0x3ffefa1bee615a27,
    0x3fff50765b6e4540,
    0x3fffa7c1819e90d8,
];

/// Natural logarithm of a positive normal `x` (see the module docs).
#[inline(always)]
fn ln_normal(x: f64) -> f64 {
    let bits = x.to_bits();
    let e = ((bits >> 52) & 0x7ff) as i64 - 1023;
    let m = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
    let i = ((bits >> 45) & 0x7f) as usize;
    let r = m * f64::from_bits(INV_C[i]) - 1.0;
    // log1p(r) to degree 6, Estrin's scheme (short dependency chains).
    let r2 = r * r;
    let p =
        (r + r2 * (-0.5 + r * (1.0 / 3.0))) + (r2 * r2) * ((-0.25 + r * 0.2) + r2 * (-1.0 / 6.0));
    let ef = e as f64;
    ef * LN2_HI + ((f64::from_bits(LN_C[i]) + p) + ef * LN2_LO)
}

/// `exp(y)` for finite `y` (overflow to +∞, underflow to 0).
#[inline(always)]
fn exp_finite(y: f64) -> f64 {
    if y > 709.8 {
        return f64::INFINITY;
    }
    if y < -745.2 {
        return 0.0;
    }
    // k = round(y·64/ln 2) by adding and subtracting 1.5·2⁵² (|k| < 2¹⁷ here): no libm call
    // on the baseline target, the same result on every path. The low bits of `t` hold
    // 2⁵¹ + k, so j = k mod 64 and n = ⌊k/64⌋ come from integer operations.
    let t = y * INV_STEP + ROUND;
    let kf = t - ROUND;
    let kb = (t.to_bits() & 0x000f_ffff_ffff_ffff) as i64 - (1i64 << 51);
    let j = (kb & 63) as usize;
    let n = kb >> 6;
    let r = (y - kf * STEP_HI) - kf * STEP_LO;
    // exp(r) − 1 to degree 5, Estrin's scheme.
    let r2 = r * r;
    let q = (r + r2 * (0.5 + r * (1.0 / 6.0))) + (r2 * r2) * (1.0 / 24.0 + r * (1.0 / 120.0));
    let tj = f64::from_bits(EXP2_J[j]);
    let p = tj + tj * q;
    // 2^n in two factors so that n down to −1075 and up to 1024 stays representable.
    let (n1, n2) = (n / 2, n - n / 2);
    let pow2 = |k: i64| f64::from_bits(((k + 1023) as u64) << 52);
    p * pow2(n1) * pow2(n2)
}

/// `x^a` for `x ≥ 0` and finite `a` (see the module docs for the method, accuracy and domain).
#[inline(always)]
pub fn powr(x: f64, a: f64) -> f64 {
    if x > 0.0 && x < f64::INFINITY {
        let l = if x < f64::MIN_POSITIVE {
            // Subnormal: scale by 2^64 into the normal range.
            ln_normal(x * 18_446_744_073_709_551_616.0) - 64.0 * LN2
        } else {
            ln_normal(x)
        };
        exp_finite(a * l)
    } else if x == 0.0 {
        if a > 0.0 {
            0.0
        } else if a == 0.0 {
            1.0
        } else {
            f64::INFINITY
        }
    } else if x == f64::INFINITY {
        if a > 0.0 {
            f64::INFINITY
        } else if a == 0.0 {
            1.0
        } else {
            0.0
        }
    } else {
        f64::NAN
    }
}
