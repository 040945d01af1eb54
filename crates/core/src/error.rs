//! Typed errors. Every message names the bad value and what is allowed.
//!
//! The bottom of the crate: it uses no other module, so the option table (`config.rs`), the memory budgets
//! (`limits.rs`) and the modes (`modes.rs`) all build on it and none of them on each other in a circle.

use thiserror::Error;

/// `n` bytes for people: `"12.0 GiB (12884901888 bytes)"` (what the memory errors say).
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

/// An option of [`crate::Config`] outside its allowed range, or an unknown option.
#[derive(Clone, Debug, PartialEq, Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// A known option with a value outside its range.
    #[error("invalid value {value} for option `{option}`: allowed {allowed}")]
    OutOfRange {
        /// The option's name as in SPEC.md (`lives`, `alien_prob`, …).
        option: &'static str,
        /// The rejected value, as given.
        value: String,
        /// The allowed range or set, in words.
        allowed: &'static str,
    },
    /// Options whose buffers would take more memory than the budget (the budgets are in `limits.rs`).
    #[error(
        "{what} would take {} of memory, over the budget of {}: {hint}",
        format_bytes(*needed),
        format_bytes(*budget)
    )]
    TooLarge {
        /// What would be allocated, with the options that size it.
        what: String,
        /// Bytes it would take.
        needed: u64,
        /// Bytes allowed.
        budget: u64,
        /// What to change.
        hint: &'static str,
    },
    /// The system refused memory for a buffer within the budget (for example under `ulimit -v`).
    #[error(
        "could not allocate {} for {what}: the system refused the memory (is a memory limit such as ulimit -v set?)",
        format_bytes(*needed)
    )]
    OutOfMemory {
        /// What was being allocated.
        what: String,
        /// Bytes asked for.
        needed: u64,
    },
    /// An option name that does not exist.
    #[error("unknown option `{name}`: allowed options are {}", allowed.join(", "))]
    Unknown {
        /// The name given.
        name: String,
        /// Every option name there is ([`crate::OPTION_NAMES`]).
        allowed: &'static [&'static str],
    },
    /// Options given beside a difficulty mode that contradict the rules it fixes ([`crate::configure`]).
    #[error(
        "options contradict mode \"{mode}\", whose rules options are fixed ({fixed}): {}; drop them, or give no mode",
        options.join(", ")
    )]
    ModeContradiction {
        /// The mode's name (`"full-v0"`).
        mode: &'static str,
        /// What the mode fixes, in words (`"frame_skip=4, sticky_prob=0.25, the others at their defaults"`).
        fixed: String,
        /// Each contradicting option as `name value != fixed` (`"lives 2 != 3"`).
        options: Vec<String>,
    },
}

/// Why a snapshot could not be decoded or restored.
#[derive(Clone, Debug, PartialEq, Error)]
#[non_exhaustive]
pub enum SnapshotError {
    /// The bytes do not start with the ChopperScape snapshot magic.
    #[error("not a ChopperScape snapshot (the bytes do not start with \"CSNP\")")]
    NotASnapshot,
    /// A snapshot written by another format version.
    #[error("snapshot format version {found} is not supported: this build reads versions 1 to {supported}")]
    Version {
        /// Version in the bytes.
        found: u16,
        /// Newest version this build reads, the one it writes.
        supported: u16,
    },
    /// The bytes end before the snapshot does.
    #[error("snapshot is truncated: it ends before its {0}")]
    Truncated(&'static str),
    /// A field holds a value no valid state can have.
    #[error("snapshot is corrupted: {0}")]
    Corrupted(String),
    /// The snapshot was taken from an environment with other options.
    #[error("snapshot was taken with other options than this environment's: {0}")]
    ConfigMismatch(String),
    /// A valid snapshot that does not fit where it is restored (a batch slot's pending reset or step count).
    #[error("state does not fit: {0}")]
    Inconsistent(String),
}

/// Everything the environment can refuse.
#[derive(Clone, Debug, PartialEq, Error)]
#[non_exhaustive]
pub enum Error {
    /// An action outside `Discrete(5)`.
    #[error("invalid action {0}: allowed actions are 0..=4 (0 Right, 1 Left, 2 Down, 3 Up, 4 Do Nothing)")]
    InvalidAction(i64),
    /// `step` before any `reset`.
    #[error("step called before reset: call reset() first")]
    NotReset,
    /// `step` after the episode terminated or was truncated.
    #[error("step called after the episode ended ({0}): call reset() to start a new episode")]
    EpisodeOver(&'static str),
    /// A caller-owned buffer of the wrong length or element type.
    #[error(
        "observation buffer has {got} elements of {got_dtype}: this environment writes {expected} elements of {expected_dtype}"
    )]
    BufferSize {
        /// Elements the observation needs.
        expected: usize,
        /// Element type the observation needs.
        expected_dtype: &'static str,
        /// Elements given.
        got: usize,
        /// Element type given.
        got_dtype: &'static str,
    },
    /// An invalid option.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// A snapshot that cannot be read or restored.
    #[error(transparent)]
    Snapshot(#[from] SnapshotError),
}
