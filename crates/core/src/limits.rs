//! Memory limits. Every buffer whose size comes from the user (observation size, frame stack, and in
//! `chopperscape-vector` the number of environments) is sized (an env's by [`crate::Config::env_bytes`]) and
//! checked against a budget before anything is allocated, and allocated with `try_reserve`, so options that ask
//! for too much are a typed error ([`ConfigError::TooLarge`], [`ConfigError::OutOfMemory`]) and never an abort,
//! even under `ulimit -v`. Below the option table: the budgets and the checks, knowing nothing of options.

use crate::error::ConfigError;
pub use crate::error::format_bytes;

/// The most memory one environment's observation buffers may take: 4 GiB. (The largest observation within
/// the options' ranges, `rgb_float` 4096 × 4096 stacked 64 deep, would take 24 GiB.)
pub const MAX_ENV_BYTES: u64 = 4 << 30;

/// Checks that `needed` bytes for `what` fit in `budget`.
///
/// # Errors
/// [`ConfigError::TooLarge`] naming `what`, both sizes and `hint`.
pub fn check_budget(what: String, needed: u64, budget: u64, hint: &'static str) -> Result<(), ConfigError> {
    if needed > budget { Err(ConfigError::TooLarge { what, needed, budget, hint }) } else { Ok(()) }
}

/// Asks the system for `bytes` of address space and gives it back at once: a cheap check (nothing is
/// touched) that a set of buffers of that total size can be allocated, so building them cannot abort.
///
/// # Errors
/// [`ConfigError::OutOfMemory`] when the system refuses (for example under `ulimit -v`).
pub fn probe(bytes: u64, what: &str) -> Result<(), ConfigError> {
    let refused = || ConfigError::OutOfMemory { what: what.to_string(), needed: bytes };
    let n = usize::try_from(bytes).map_err(|_| refused())?;
    let mut v: Vec<u8> = Vec::new();
    v.try_reserve_exact(n).map_err(|_| refused())
}

/// A vector of `n` copies of `value`, or an error instead of an abort when the memory is refused.
///
/// # Errors
/// [`ConfigError::OutOfMemory`] naming `what`.
pub fn try_filled<T: Clone>(n: usize, value: T, what: &str) -> Result<Vec<T>, ConfigError> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| ConfigError::OutOfMemory {
        what: what.to_string(),
        needed: (n as u64).saturating_mul(std::mem::size_of::<T>() as u64),
    })?;
    v.resize(n, value);
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_said_in_units_and_bytes() {
        assert_eq!(format_bytes(12 << 30), "12.0 GiB (12884901888 bytes)");
        assert_eq!(format_bytes(100), "100 bytes");
        let err = check_budget("a thing".into(), 5 << 30, MAX_ENV_BYTES, "make it smaller").unwrap_err().to_string();
        assert_eq!(
            err,
            "a thing would take 5.0 GiB (5368709120 bytes) of memory, over the budget of 4.0 GiB \
                         (4294967296 bytes): make it smaller"
        );
        assert!(check_budget("a thing".into(), MAX_ENV_BYTES, MAX_ENV_BYTES, "").is_ok());
    }

    #[test]
    fn refused_memory_is_an_error_not_an_abort() {
        let err = probe(u64::MAX, "a test").unwrap_err().to_string();
        assert!(err.contains("could not allocate") && err.contains("a test"), "{err}");
        let err = try_filled(usize::MAX / 2, 0u32, "a huge vector").unwrap_err().to_string();
        assert!(err.contains("a huge vector"), "{err}");
    }
}
