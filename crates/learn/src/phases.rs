//! Where an update's time goes, in the phases of Python's `chopperscape.learn.phases` (the same names and the same
//! split), so that the two learners' tables stand side by side.
//!
//! The learner has no clock (the browser's worker has none it can read here): [`Learner::update_laps`] calls
//! [`Laps::lap`] at the end of each stretch of work, naming the phase that stretch belonged to, and the caller's
//! [`Laps`] reads its own clock. [`NoLaps`] (what [`Learner::update`] passes) does nothing.
//!
//! [`Learner::update_laps`]: crate::Learner::update_laps
//! [`Learner::update`]: crate::Learner::update

/// A phase of an update, in loop order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// The vector env's step.
    Env,
    /// Observation normalisation (the statistics' update and the normalised copy).
    ObsNorm,
    /// The rollout's forward passes, action sampling included.
    Forward,
    /// The rest: buffers, episode statistics, reward scaling, minibatch gathering.
    Bookkeeping,
    /// The last value and GAE.
    Gae,
    /// The update's forward passes and losses.
    UpdateForward,
    /// The losses' gradients.
    Backward,
    /// Gradient clipping, Adam's step and setting the parameters.
    Optimizer,
    /// The progress row and the checkpoint (the caller's).
    Logging,
}

/// The phases' names, in [`Phase`]'s order: Python's `chopperscape.learn.phases.PHASES`.
pub const PHASES: [&str; 9] =
    ["env", "obs_norm", "forward", "bookkeeping", "gae", "update_forward", "backward", "optimizer", "logging"];

impl Phase {
    /// The phase's name, as Python's table names it.
    pub fn name(self) -> &'static str {
        PHASES[self as usize]
    }
}

/// Told when each stretch of an update's work ends, and which phase it was.
pub trait Laps {
    /// The work since the previous lap (or since the update began) was `phase`.
    fn lap(&mut self, phase: Phase);
}

/// Laps that measure nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoLaps;

impl Laps for NoLaps {
    fn lap(&mut self, _phase: Phase) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_names_are_pythons_in_order() {
        let all = [
            Phase::Env,
            Phase::ObsNorm,
            Phase::Forward,
            Phase::Bookkeeping,
            Phase::Gae,
            Phase::UpdateForward,
            Phase::Backward,
            Phase::Optimizer,
            Phase::Logging,
        ];
        let names: Vec<_> = all.iter().map(|p| p.name()).collect();
        assert_eq!(names, PHASES);
    }
}
