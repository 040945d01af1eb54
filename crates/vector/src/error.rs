//! What a batch can refuse. Every message names the bad value and what is allowed.

use thiserror::Error;

/// Why a batch call was refused. A refused call changes no environment.
#[derive(Clone, Debug, PartialEq, Error)]
#[non_exhaustive]
pub enum BatchError {
    /// The action array does not hold one action per environment.
    #[error("expected {expected} actions (one per environment), got {got}")]
    ActionCount {
        /// Environments in the batch.
        expected: usize,
        /// Actions given.
        got: usize,
    },
    /// An action outside `Discrete(5)`.
    #[error(
        "invalid action {action} at index {index}: allowed actions are 0..=4 (0 Right, 1 Left, 2 Down, 3 Up, 4 Do Nothing)"
    )]
    InvalidAction {
        /// Position of the first bad action in the array.
        index: usize,
        /// The bad action.
        action: i64,
    },
    /// A per-environment seed list of the wrong length.
    #[error("expected {expected} seeds (one per environment), got {got}")]
    SeedCount {
        /// Environments in the batch.
        expected: usize,
        /// Seeds given.
        got: usize,
    },
    /// `step` before any `reset`.
    #[error("step called before reset: call reset() first")]
    NotReset,
    /// An environment that can neither step nor reset (only reachable through a restored state).
    #[error("environment {index} cannot step: its episode is {status} and no reset is pending")]
    EnvState {
        /// The first such environment.
        index: usize,
        /// Where its episode stands.
        status: String,
    },
    /// An output buffer of the wrong length or element type.
    #[error(
        "output buffer `{buffer}` has {got} elements of {got_dtype}: this batch writes {expected} elements of {expected_dtype}"
    )]
    BufferSize {
        /// Which buffer (`observations`, `rewards`, `final_observations`, …).
        buffer: &'static str,
        /// Elements needed.
        expected: usize,
        /// Element type needed.
        expected_dtype: &'static str,
        /// Elements given.
        got: usize,
        /// Element type given.
        got_dtype: &'static str,
    },
    /// `SAME_STEP` autoreset needs a buffer for the final observations.
    #[error("autoreset mode SAME_STEP needs a final_observations buffer")]
    MissingFinalObservations,
    /// The worker threads could not be started.
    #[error("could not start {threads} worker threads: {reason}")]
    ThreadPool {
        /// Threads asked for.
        threads: usize,
        /// What the system said.
        reason: String,
    },
}
