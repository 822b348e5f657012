//! Run-time choice of the vector instruction set for the hot loops, with the same answers on
//! every path.
//!
//! The release binary is built for the baseline x86-64 target (SSE2), so it runs on any x86-64
//! machine: a binary built on an AVX-512 login node does not die with SIGILL on an older compute
//! node. The loops that carry the work (the batched right-hand sides, the batched
//! articulated-body recursion, the integrator's column kernels over lanes) are compiled a
//! second and third time with AVX2+FMA and AVX-512 enabled, and [`dispatch`] runs the best copy
//! the CPU supports (or the one chosen by [`set_path`] / the `PDW_SIMD` environment variable).
//!
//! **One result on every path.** Every path performs the same IEEE-754 operations in the same
//! order: Rust never contracts `a·b + c` into a fused multiply-add (enabling the `fma` feature
//! only lets the compiler *use* wider registers, it does not change rounding), and `wide`'s
//! `mul_add` — used inside its sin/cos polynomials — picks its fused form only when the *crate*
//! is compiled with FMA enabled, which the portable build never does. So no path uses FMA, and
//! results are bit-identical across paths (tested by forcing each available path and comparing
//! a 201×201 basin cell for cell and the kernels' outputs bit for bit). [`NUMERICS`] names this
//! contract; it is recorded in every output file, and shards are merged only when it agrees.
//!
//! On other architectures there is one path, [`SimdPath::Baseline`].

use std::sync::atomic::{AtomicU8, Ordering};

pub mod powr;
pub mod trig;
pub use powr::powr;
pub use trig::{sin_small, sincos, sincos_lanes, sincos_reduced_range, sincos_slice, sincos_small};

/// The numeric contract every path keeps (recorded in output files; `merge` compares it).
pub const NUMERICS: &str = "ieee754-binary64, no fma contraction, sequential lane order";

/// An instruction-set level for the hot loops.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SimdPath {
    /// The build target's own features (x86-64: SSE2).
    Baseline,
    /// x86-64 with AVX2 and FMA (FMA units available, never used for contraction).
    Avx2,
    /// x86-64 with AVX-512 F/DQ/VL (and AVX2+FMA).
    Avx512,
}

impl SimdPath {
    /// Every path, from the most to the least capable.
    pub const ALL: [SimdPath; 3] = [SimdPath::Avx512, SimdPath::Avx2, SimdPath::Baseline];

    /// Name as used by `PDW_SIMD` and in output files.
    pub fn name(self) -> &'static str {
        match self {
            SimdPath::Baseline => "baseline",
            SimdPath::Avx2 => "avx2",
            SimdPath::Avx512 => "avx512",
        }
    }

    /// Parse a name (`baseline`, `avx2`, `avx512`).
    pub fn parse(s: &str) -> Option<SimdPath> {
        match s.trim().to_ascii_lowercase().as_str() {
            "baseline" | "sse2" => Some(SimdPath::Baseline),
            "avx2" => Some(SimdPath::Avx2),
            "avx512" | "avx-512" => Some(SimdPath::Avx512),
            _ => None,
        }
    }

    /// Does this CPU support the path?
    pub fn available(self) -> bool {
        match self {
            SimdPath::Baseline => true,
            #[cfg(target_arch = "x86_64")]
            SimdPath::Avx2 => {
                std::arch::is_x86_feature_detected!("avx2")
                    && std::arch::is_x86_feature_detected!("fma")
            }
            #[cfg(target_arch = "x86_64")]
            SimdPath::Avx512 => {
                SimdPath::Avx2.available()
                    && std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("avx512dq")
                    && std::arch::is_x86_feature_detected!("avx512vl")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    fn code(self) -> u8 {
        match self {
            SimdPath::Baseline => 1,
            SimdPath::Avx2 => 2,
            SimdPath::Avx512 => 3,
        }
    }

    fn from_code(c: u8) -> Option<SimdPath> {
        match c {
            1 => Some(SimdPath::Baseline),
            2 => Some(SimdPath::Avx2),
            3 => Some(SimdPath::Avx512),
            _ => None,
        }
    }
}

impl std::fmt::Display for SimdPath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Why a path cannot be selected.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SimdError {
    /// Not a path name.
    Unknown(String),
    /// The CPU lacks the path's instructions.
    Unavailable(SimdPath),
}

impl std::fmt::Display for SimdError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SimdError::Unknown(s) => write!(
                f,
                "unknown SIMD path {s:?}: allowed are baseline, avx2, avx512"
            ),
            SimdError::Unavailable(p) => write!(
                f,
                "SIMD path {p} is not supported by this CPU (available: {})",
                available_paths()
                    .iter()
                    .map(|p| p.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }
    }
}

impl std::error::Error for SimdError {}

/// 0 = not chosen yet; otherwise [`SimdPath::code`].
static PATH: AtomicU8 = AtomicU8::new(0);

/// The paths this CPU supports, most capable first.
pub fn available_paths() -> Vec<SimdPath> {
    SimdPath::ALL
        .into_iter()
        .filter(|p| p.available())
        .collect()
}

/// The most capable path this CPU supports.
pub fn best_path() -> SimdPath {
    available_paths()[0]
}

/// The path in use: set by [`set_path`], else `PDW_SIMD` if it names an available path, else
/// [`best_path`]. (An unusable `PDW_SIMD` falls back to the best path; front ends that want to
/// report it call [`path_from_env`].)
#[inline]
pub fn path() -> SimdPath {
    match SimdPath::from_code(PATH.load(Ordering::Relaxed)) {
        Some(p) => p,
        None => {
            let p = path_from_env().ok().flatten().unwrap_or_else(best_path);
            PATH.store(p.code(), Ordering::Relaxed);
            p
        }
    }
}

/// The path named by `PDW_SIMD`, `Ok(None)` when it is unset or empty.
pub fn path_from_env() -> Result<Option<SimdPath>, SimdError> {
    match std::env::var("PDW_SIMD") {
        Ok(s) if !s.trim().is_empty() => {
            let p = SimdPath::parse(&s).ok_or(SimdError::Unknown(s))?;
            if p.available() {
                Ok(Some(p))
            } else {
                Err(SimdError::Unavailable(p))
            }
        }
        _ => Ok(None),
    }
}

/// Use `p` from now on, process-wide (tests force each path; every path gives the same bits).
pub fn set_path(p: SimdPath) -> Result<(), SimdError> {
    if !p.available() {
        return Err(SimdError::Unavailable(p));
    }
    PATH.store(p.code(), Ordering::Relaxed);
    Ok(())
}

/// Run `f` compiled for the selected path. Pass a closure marked `#[inline(always)]` whose
/// kernels are `#[inline(always)]` too (`dispatch(#[inline(always)] || kernel(a, b))`): only
/// code inlined into the path's copy is compiled for it; callees that are not inlined run their
/// own (baseline or separately dispatched) code.
#[inline(always)]
pub fn dispatch<R, F: FnOnce() -> R>(f: F) -> R {
    #[cfg(target_arch = "x86_64")]
    {
        match path() {
            // SAFETY: the path is only selectable when the CPU has its features
            // (`SimdPath::available`, checked by `set_path` and `path`).
            SimdPath::Avx512 => unsafe { run_avx512(f) },
            SimdPath::Avx2 => unsafe { run_avx2(f) },
            SimdPath::Baseline => f(),
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        f()
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn run_avx2<R, F: FnOnce() -> R>(f: F) -> R {
    f()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512vl")]
unsafe fn run_avx512<R, F: FnOnce() -> R>(f: F) -> R {
    f()
}
