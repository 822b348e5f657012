//! Memory, estimated before work starts: every command estimates its peak memory from its
//! request (grid cells, walkers, chain states) and refuses, through [`check_memory`], one that
//! cannot fit, instead of aborting on an allocation failure midway (after hours of walkers,
//! say) or being killed by the kernel.

use crate::input::InputError;

/// The share of the available memory a run may plan to use (the rest is head room for the
/// estimate's error and for everything else on the machine).
pub const SHARE_NUM: u64 = 4;
/// See [`SHARE_NUM`]: 4/5 = 80 %.
pub const SHARE_DEN: u64 = 5;

/// `1.5 GiB` style.
pub fn gib(b: u64) -> String {
    format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64)
}

/// Refuses a run whose estimated peak memory `need` (bytes) exceeds 80 % of the memory
/// available to this process ([`pdw_limit::resources::memory_available`]: `MemAvailable` and
/// the room under the cgroup's limit, whichever is smaller). The message starts with `what`
/// (the option and value that decide the size, e.g. `--grid 20000x20000`), names the estimate
/// and the limit, and ends with `advice` (what to change).
pub fn check_memory(need: u64, what: &str, advice: &str) -> Result<(), InputError> {
    check_memory_within(need, pdw_limit::resources::memory_available(), what, advice)
}

/// [`check_memory`] against `have` bytes available.
pub fn check_memory_within(
    need: u64,
    have: u64,
    what: &str,
    advice: &str,
) -> Result<(), InputError> {
    let limit = (u128::from(have) * u128::from(SHARE_NUM) / u128::from(SHARE_DEN)) as u64;
    if need > limit {
        return Err(InputError(format!(
            "{what}: needs about {} of memory, more than the {} available (80 % of {}); {advice}",
            gib(need),
            gib(limit),
            gib(have)
        )));
    }
    Ok(())
}

/// `a · b` in bytes, saturating (an estimate past `u64::MAX` is refused all the same).
pub fn bytes(count: u64, each: u64) -> u64 {
    count.saturating_mul(each)
}
