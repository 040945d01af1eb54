//! Memory limits. Every buffer whose size comes from the user (observation size, frame stack, and in
//! `chopperscape-vector` the number of environments) is sized and checked against a budget before anything is
//! allocated, and allocated with `try_reserve`, so options that ask for too much are a typed error
//! ([`ConfigError::TooLarge`], [`ConfigError::OutOfMemory`]) and never an abort, even under `ulimit -v`.

use crate::config::{Config, ObsType};
use crate::error::ConfigError;
use crate::features::FEATURES_LEN;

/// The most memory one environment's observation buffers may take: 4 GiB. (The largest observation within
/// the options' ranges, `rgb_float` 4096 × 4096 stacked 64 deep, would take 24 GiB.)
pub const MAX_ENV_BYTES: u64 = 4 << 30;

/// Bytes of one observation (frame stack included): what a caller's buffer for it takes.
pub fn observation_bytes(config: &Config) -> u64 {
    let (single, elem) = single(config);
    single * u64::from(config.frame_stack) * elem
}

/// Elements of one unstacked observation and bytes per element.
fn single(config: &Config) -> (u64, u64) {
    let (h, w) = (u64::from(config.obs_size.0), u64::from(config.obs_size.1));
    match config.obs_type {
        ObsType::Rgb => (h * w * 3, 1),
        ObsType::RgbFloat => (h * w * 3, 4),
        ObsType::Grayscale => (h * w, 1),
        ObsType::Features => (FEATURES_LEN as u64, 4),
    }
}

/// Bytes one environment's observation buffers take: the canvas it draws into, the frame stack and its
/// scratch frame (`frame_stack > 1`), and one observation in the caller's buffer. Exact up to the renderer's
/// sprites and HUD (a few hundred kilobytes at most). Cannot overflow within the options' ranges.
pub fn env_bytes(config: &Config) -> u64 {
    let (single, elem) = single(config);
    // The canvas holds one byte per element of an unstacked observation (RGB or gray); features draw nothing.
    let canvas = if config.obs_type.is_pixels() { single } else { 0 };
    let observation = observation_bytes(config);
    let stack = if config.frame_stack > 1 { observation + single * elem } else { 0 };
    canvas + stack + observation
}

/// `n` bytes for people: `"12.0 GiB (12884901888 bytes)"`.
pub fn format_bytes(n: u64) -> String {
    const UNITS: [&str; 5] = ["bytes", "KiB", "MiB", "GiB", "TiB"];
    let mut v = n as f64;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    if unit == 0 { format!("{n} bytes") } else { format!("{v:.1} {} ({n} bytes)", UNITS[unit]) }
}

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
    fn the_default_env_takes_two_rgb_frames() {
        assert_eq!(env_bytes(&Config::default()), 2 * 600 * 800 * 3);
        assert_eq!(env_bytes(&Config::features()), FEATURES_LEN as u64 * 4);
    }

    #[test]
    fn the_largest_options_are_over_the_budget_and_say_by_how_much() {
        let c = Config { obs_size: (4096, 4096), frame_stack: 64, obs_type: ObsType::RgbFloat, ..Config::default() };
        assert_eq!(env_bytes(&c), 4096 * 4096 * 3 * (2 * 64 * 4 + 4 + 1));
        assert!(env_bytes(&c) > MAX_ENV_BYTES);
        assert_eq!(format_bytes(12 << 30), "12.0 GiB (12884901888 bytes)");
        assert_eq!(format_bytes(100), "100 bytes");
    }

    #[test]
    fn refused_memory_is_an_error_not_an_abort() {
        let err = probe(u64::MAX, "a test").unwrap_err().to_string();
        assert!(err.contains("could not allocate") && err.contains("a test"), "{err}");
        let err = try_filled(usize::MAX / 2, 0u32, "a huge vector").unwrap_err().to_string();
        assert!(err.contains("a huge vector"), "{err}");
    }
}
