//! The rules: how a [`World`] changes in one step. Pure and allocation-free after warm-up.
//!
//! # Order of random draws
//! The generator is drawn from in this order, and in no other place:
//! - `reset`: chopper `x` in `[40, 80)`, then chopper `y` in `[90, 120)`.
//! - each underlying step (frame): the sticky draw (`unit`, only when `sticky_prob > 0`); the bird draw
//!   (`unit`, always), then its `y` if it appears; the fuel draw (`unit`, always), then its `x` if it appears;
//!   the alien draw (`unit`, only when `alien_prob > 0`), then its `y` if it appears.
//!
//! # Order within a step (SPEC "One step", with the options placed)
//! 1. fuel −1, reward +1; 2. the chopper moves; 3–4. spawns (bird, tank, alien); 5. birds, oldest first;
//!    then aliens (move, collide, then fire when due: a fired missile moves in the same step), then missiles;
//! 6. fuel tanks; then, with `bird_fuel_collision = "destroy"`, each tank (oldest first) and the oldest bird,
//!    else the oldest alien, it touches are removed; 7. fuel check; 8. the return grows by the reward.
//!
//! A hit (bird, alien or missile) with more than one life left costs a life, removes what hit and sets the
//! reward to −10; with one life left it sets the reward to −10, leaves what hit on screen (the last frame shows
//! the crash), takes the last life and terminates. Hits after a termination in the same step change nothing.

use crate::action::Action;
use crate::config::{BirdFuelCollision, Config};
use crate::consts::*;
use crate::error::{ConfigError, Error};
use crate::geometry::Rect;
use crate::rng::Rng;
use crate::world::{Alien, Cause, Status, World};

/// What one agent step produced (the observation aside).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    /// Sum of the rewards of the underlying steps (+1 or −10 each).
    pub reward: f32,
    /// The episode ended by the rules.
    pub terminated: bool,
    /// The episode was cut off at `max_episode_steps`.
    pub truncated: bool,
}

/// One game: the options, the world and the generator. Knows nothing of pixels, threads or callers.
#[derive(Clone, Debug, PartialEq)]
pub struct Game {
    pub(crate) config: Config,
    pub(crate) world: World,
    pub(crate) rng: Rng,
    /// The action applied in the last underlying step (for sticky actions); `Noop` after reset.
    pub(crate) prev_action: Action,
    /// The options' probabilities in integer form, derived from `config` once.
    odds: Odds,
}

/// Probabilities as [`Rng::threshold`]s, so each draw is an integer compare.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Odds {
    sticky: u64,
    bird: u64,
    fuel: u64,
    alien: u64,
}

impl Odds {
    fn of(c: &Config) -> Odds {
        let t = Rng::threshold;
        Odds { sticky: t(c.sticky_prob), bird: t(c.bird_prob), fuel: t(c.fuel_prob), alien: t(c.alien_prob) }
    }
}

impl Game {
    /// A game with these options, not yet reset. Its generator is seeded with 0 until `reset(Some(seed))`.
    ///
    /// # Errors
    /// The first option out of range.
    pub fn new(config: Config) -> Result<Game, ConfigError> {
        config.validate()?;
        // Before the first reset the world is a valid one (chopper in the band, full tank), so it can be drawn,
        // snapshotted and restored like any other.
        let world = World {
            chopper: Rect::placed(CHOPPER_SPAWN_X.0, CHOPPER_SPAWN_Y.0, CHOPPER_SIZE),
            fuel_left: config.max_fuel,
            lives: config.lives,
            ..World::default()
        };
        Ok(Game::from_parts(config, world, Rng::seed_from_u64(0), Action::Noop))
    }

    /// A game from its parts (for snapshots); `config` must be valid.
    pub(crate) fn from_parts(config: Config, world: World, rng: Rng, prev_action: Action) -> Game {
        let odds = Odds::of(&config);
        Game { config, world, rng, prev_action, odds }
    }

    /// The options.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The current state.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The generator (read-only: for snapshots and tests).
    pub fn rng(&self) -> &Rng {
        &self.rng
    }

    /// Starts a new episode. `Some(seed)` reseeds the generator; `None` continues its stream.
    pub fn reset(&mut self, seed: Option<u64>) {
        if let Some(seed) = seed {
            self.rng = Rng::seed_from_u64(seed);
        }
        let w = &mut self.world;
        w.birds.clear();
        w.fuel_tanks.clear();
        w.aliens.clear();
        w.missiles.clear();
        let x = self.rng.range(CHOPPER_SPAWN_X.0, CHOPPER_SPAWN_X.1);
        let y = self.rng.range(CHOPPER_SPAWN_Y.0, CHOPPER_SPAWN_Y.1);
        w.chopper = Rect::placed(x, y, CHOPPER_SIZE);
        w.fuel_left = self.config.max_fuel;
        w.episode_return = 0;
        w.lives = self.config.lives;
        w.steps = 0;
        w.status = Status::Running;
        self.prev_action = Action::Noop;
    }

    /// One agent step: the action for `frame_skip` underlying steps (fewer if the episode ends).
    ///
    /// # Errors
    /// [`Error::NotReset`] before the first reset; [`Error::EpisodeOver`] after the episode ended.
    pub fn step(&mut self, action: Action) -> Result<Outcome, Error> {
        match self.world.status {
            Status::Running => {}
            Status::NotStarted => return Err(Error::NotReset),
            Status::Terminated(Cause::Bird) => return Err(Error::EpisodeOver("terminated: hit by a bird")),
            Status::Terminated(Cause::Fuel) => return Err(Error::EpisodeOver("terminated: out of fuel")),
            Status::Truncated => return Err(Error::EpisodeOver("truncated at max_episode_steps")),
        }
        let mut reward = 0;
        for _ in 0..self.config.frame_skip {
            reward += self.tick(action);
            if self.world.status != Status::Running {
                break;
            }
        }
        let w = &mut self.world;
        // Saturates: with no step limit an episode may outlast the counter, which then stays at u32::MAX.
        w.steps = w.steps.saturating_add(1);
        if w.status == Status::Running && self.config.max_episode_steps == Some(w.steps) {
            w.status = Status::Truncated;
        }
        Ok(Outcome {
            reward: reward as f32,
            terminated: matches!(w.status, Status::Terminated(_)),
            truncated: w.status == Status::Truncated,
        })
    }

    /// One underlying step of the rules; returns its reward.
    fn tick(&mut self, action: Action) -> i32 {
        let cfg = &self.config;
        let rng = &mut self.rng;
        let odds = self.odds;
        let applied = if cfg.sticky_prob > 0.0 && rng.chance_below(odds.sticky) { self.prev_action } else { action };
        self.prev_action = applied;

        let World { chopper, birds, fuel_tanks, aliens, missiles, fuel_left, episode_return, lives, status, .. } =
            &mut self.world;

        // 1–2.
        *fuel_left = fuel_left.saturating_sub(1);
        let mut reward = STEP_REWARD;
        let (dx, dy) = applied.delta();
        chopper.shift(dx, dy);

        // 3–4 and the alien draw.
        if rng.chance_below(odds.bird) {
            birds.push(Rect::placed(X_MAX, rng.range(Y_MIN, Y_MAX), BIRD_SIZE));
        }
        if rng.chance_below(odds.fuel) {
            fuel_tanks.push(Rect::placed(rng.range(X_MIN, X_MAX), Y_MAX, FUEL_TANK_SIZE));
        }
        if cfg.alien_prob > 0.0 && rng.chance_below(odds.alien) {
            aliens.push(Alien { body: Rect::placed(X_MAX, rng.range(Y_MIN, Y_MAX), ALIEN_SIZE), age: 0 });
        }

        let chopper = *chopper;

        // 5. Birds, then aliens (which may fire), then missiles.
        fly_left(birds, BIRD_SPEED, &chopper, lives, status, &mut reward);
        aliens.retain_mut(|a| {
            if a.body.x <= X_MIN {
                return false;
            }
            a.body.shift_left(BIRD_SPEED);
            if a.body.collides(&chopper) && hit(lives, status, &mut reward) {
                return false;
            }
            if a.fires_now() {
                let (ox, oy) = MISSILE_OFFSET;
                missiles.push(Rect::placed(a.body.x + ox, a.body.y + oy, MISSILE_SIZE));
            }
            a.age += 1;
            true
        });
        fly_left(missiles, MISSILE_SPEED, &chopper, lives, status, &mut reward);

        // 6. Fuel tanks.
        fuel_tanks.retain_mut(|t| {
            if t.y <= Y_MIN {
                return false;
            }
            t.shift_up(FUEL_TANK_SPEED);
            if t.collides(&chopper) {
                *fuel_left = cfg.max_fuel;
                return false;
            }
            true
        });
        if cfg.bird_fuel_collision == BirdFuelCollision::Destroy {
            destroy_colliding(fuel_tanks, birds, aliens);
        }

        // 7–8.
        if *fuel_left == 0 && *status == Status::Running {
            *status = Status::Terminated(Cause::Fuel);
        }
        *episode_return = episode_return.saturating_add(i64::from(reward));
        reward
    }
}

/// Birds and missiles, oldest first: one past the left edge leaves without a collision test; the others move
/// `speed` left and hit the chopper if they then touch it.
#[inline(always)]
fn fly_left(list: &mut Vec<Rect>, speed: i32, chopper: &Rect, lives: &mut u32, status: &mut Status, reward: &mut i32) {
    // Usually empty or nearly so: skip the retain machinery then (measurably cheaper per step).
    if list.is_empty() {
        return;
    }
    list.retain_mut(|r| {
        if r.x <= X_MIN {
            return false;
        }
        r.shift_left(speed);
        !(r.collides(chopper) && hit(lives, status, reward))
    });
}

/// A hit on the chopper; returns whether what hit is removed (only when a life was lost and lives remain).
fn hit(lives: &mut u32, status: &mut Status, reward: &mut i32) -> bool {
    if *status != Status::Running {
        return false;
    }
    *reward = HIT_REWARD;
    if *lives > 1 {
        *lives -= 1;
        true
    } else {
        *lives = 0;
        *status = Status::Terminated(Cause::Bird);
        false
    }
}

/// Removes each fuel tank (oldest first) together with the oldest bird, or else the oldest alien, it touches.
fn destroy_colliding(tanks: &mut Vec<Rect>, birds: &mut Vec<Rect>, aliens: &mut Vec<Alien>) {
    let mut i = 0;
    while i < tanks.len() {
        let t = tanks[i];
        if let Some(j) = birds.iter().position(|b| b.collides(&t)) {
            birds.remove(j);
        } else if let Some(j) = aliens.iter().position(|a| a.body.collides(&t)) {
            aliens.remove(j);
        } else {
            i += 1;
            continue;
        }
        tanks.remove(i);
    }
}

#[cfg(test)]
#[path = "rules_tests.rs"]
mod tests;
