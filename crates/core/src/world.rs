//! The state of one episode: every entity on screen, the fuel, the score, the lives.
//!
//! A [`World`] is plain data. The rules ([`crate::Game`]) change it; the renderer and the features
//! observation only read it.

use crate::consts::{ALIEN_FIRST_SHOT, ALIEN_SHOT_PERIOD};
use crate::geometry::Rect;

/// An alien bird: a box plus its age, which decides when it fires.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Alien {
    /// Where it is.
    pub body: Rect,
    /// Steps since it appeared: 0 in the step it appears. It fires when `age == 20`, `60`, `100`, …
    pub age: u32,
}

impl Alien {
    /// Whether it fires in this step: at age 20, 60, 100, … (`ALIEN_FIRST_SHOT`, then every `ALIEN_SHOT_PERIOD`).
    pub fn fires_now(&self) -> bool {
        self.age >= ALIEN_FIRST_SHOT && (self.age - ALIEN_FIRST_SHOT) % ALIEN_SHOT_PERIOD == 0
    }

    /// Steps from now until it fires next (0 when it fires in this step).
    pub fn steps_to_next_shot(&self) -> u32 {
        if self.age <= ALIEN_FIRST_SHOT {
            ALIEN_FIRST_SHOT - self.age
        } else {
            (ALIEN_SHOT_PERIOD - (self.age - ALIEN_FIRST_SHOT) % ALIEN_SHOT_PERIOD) % ALIEN_SHOT_PERIOD
        }
    }
}

/// Why an episode terminated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Cause {
    /// A bird, an alien or a missile hit the chopper with no life left to lose.
    Bird,
    /// The fuel ran out.
    Fuel,
}

impl Cause {
    /// The name used in infos and JSON: `"bird"` or `"fuel"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Cause::Bird => "bird",
            Cause::Fuel => "fuel",
        }
    }
}

/// Where an episode stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Status {
    /// `reset` has not been called yet.
    #[default]
    NotStarted,
    /// The episode goes on.
    Running,
    /// The episode ended by the rules.
    Terminated(Cause),
    /// The episode was cut off at `max_episode_steps`.
    Truncated,
}

impl Status {
    /// Whether the episode has ended (terminated or truncated).
    pub fn is_over(self) -> bool {
        matches!(self, Status::Terminated(_) | Status::Truncated)
    }
}

/// Everything on screen and on the HUD after a step.
///
/// Lists are in order of appearance, oldest first: that order is part of the rules (SPEC step 5–6).
#[derive(Clone, Debug, PartialEq, Eq, Hash, Default)]
pub struct World {
    /// The chopper.
    pub chopper: Rect,
    /// Birds on screen, oldest first.
    pub birds: Vec<Rect>,
    /// Fuel tanks on screen, oldest first.
    pub fuel_tanks: Vec<Rect>,
    /// Alien birds on screen, oldest first (only with `alien_prob > 0`).
    pub aliens: Vec<Alien>,
    /// Missiles in flight, oldest first.
    pub missiles: Vec<Rect>,
    /// Fuel left, in `[0, max_fuel]`.
    pub fuel_left: u32,
    /// Sum of the rewards of this episode (what the HUD shows as `Rewards`).
    pub episode_return: i64,
    /// Lives left, in `[0, lives]`.
    pub lives: u32,
    /// Agent steps taken in this episode (one `step` call counts once, whatever the frame skip). Saturates at
    /// `u32::MAX` (an episode with no step limit may run longer; it is never truncated for that).
    pub steps: u32,
    /// Where the episode stands.
    pub status: Status,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aliens_fire_at_twenty_then_every_forty_steps() {
        let fires: Vec<u32> = (0..150).filter(|&age| Alien { body: Rect::default(), age }.fires_now()).collect();
        assert_eq!(fires, [20, 60, 100, 140]);
        for age in 0..150 {
            let a = Alien { body: Rect::default(), age };
            let next = Alien { age: age + a.steps_to_next_shot(), ..a };
            assert!(next.fires_now(), "age {age}");
            assert!((age..next.age).all(|g| !Alien { age: g, ..a }.fires_now()), "age {age}");
        }
    }
}
