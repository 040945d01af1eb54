//! What the rules can reach: the checks a decoded snapshot passes before it becomes a state, so that a
//! restored environment is always in a state the game could be in (and its counters can never wrap).
//!
//! Each check follows from `rules.rs`: one bird, tank and alien at most spawn per underlying step, at fixed
//! places (birds and aliens at `x = 768`, tanks at `y = 508`), and each moves a fixed distance per underlying
//! step in the step it appears, so positions come in steps of 5 from the spawn (or sit clamped at the band's
//! edge for their last step) and each list, oldest first, is strictly ordered along its direction of flight.
//! An alien's age fixes its position. Each underlying step is worth +1, or −10 when the chopper is hit, and
//! every hit costs a life.

use crate::action::Action;
use crate::config::{Config, ObsType};
use crate::consts::*;
use crate::geometry::Rect;
use crate::obs_buffer::ObsData;
use crate::world::{Cause, Status, World};

/// Birds (or aliens) on screen at most: one per position of their flight, `768/5 + 1`.
pub(crate) const MAX_BIRDS: usize = ((X_MAX - BIRD_SIZE.0) / BIRD_SPEED + 1) as usize;
/// Fuel tanks on screen at most: one per position of their rise.
pub(crate) const MAX_FUEL_TANKS: usize = ((Y_MAX - FUEL_TANK_SIZE.1 - Y_MIN) / FUEL_TANK_SPEED + 1) as usize;
/// Missiles in flight at most: up to 4 aliens fire in one step (ages 20, 60, 100, 140), and a missile flies
/// at most `800/10 + 1` steps.
pub(crate) const MAX_MISSILES: usize = 4 * (X_MAX / MISSILE_SPEED + 1) as usize;
/// The oldest an alien on screen can be: the age at which it reaches the left edge.
const MAX_ALIEN_AGE: u32 = ((X_MAX - ALIEN_SIZE.0) as u32).div_ceil(BIRD_SPEED as u32);

/// Where a bird or alien of age `age` (underlying steps it has lived through) is.
fn alien_x(age: u32) -> i32 {
    (i64::from(X_MAX - ALIEN_SIZE.0) - i64::from(BIRD_SPEED) * i64::from(age)).max(i64::from(X_MIN)) as i32
}

/// Checks the world (and the last applied action) against what the rules can reach under `config`.
pub(crate) fn check_world(config: &Config, w: &World, prev_action: Action) -> Result<(), String> {
    let fresh = || World {
        chopper: Rect::placed(CHOPPER_SPAWN_X.0, CHOPPER_SPAWN_Y.0, CHOPPER_SIZE),
        fuel_left: config.max_fuel,
        lives: config.lives,
        ..World::default()
    };
    match w.status {
        Status::NotStarted if *w != fresh() || prev_action != Action::Noop => {
            return Err("a never-reset environment holds a state other than the initial one".into());
        }
        Status::NotStarted => return Ok(()),
        _ => {}
    }
    // Lives and the cause of a termination.
    if w.lives > config.lives {
        return Err(format!("lives left {} above the `lives` option {}", w.lives, config.lives));
    }
    if (w.lives == 0) != (w.status == Status::Terminated(Cause::Bird)) {
        return Err(format!("lives left {} with status {:?}: only a bird termination leaves 0", w.lives, w.status));
    }
    if w.fuel_left > config.max_fuel {
        return Err(format!("fuel {} above max_fuel {}", w.fuel_left, config.max_fuel));
    }
    match w.status {
        Status::Terminated(Cause::Fuel) if w.fuel_left != 0 => return Err("out of fuel with fuel left".into()),
        Status::Running | Status::Truncated if w.fuel_left == 0 => {
            return Err("no fuel left in an episode that goes on".into());
        }
        _ => {}
    }
    // Steps.
    match (w.status, config.max_episode_steps) {
        (Status::Running, Some(max)) if w.steps >= max => {
            return Err(format!("steps {} reach max_episode_steps {max} in a running episode", w.steps));
        }
        (Status::Truncated, max) if max != Some(w.steps) => {
            return Err(format!("truncated at step {} but max_episode_steps is {max:?}", w.steps));
        }
        (Status::Terminated(_), Some(max)) if w.steps > max => {
            return Err(format!("steps {} beyond max_episode_steps {max}", w.steps));
        }
        (Status::Terminated(_) | Status::Truncated, _) if w.steps == 0 => {
            return Err("an episode ended before its first step".into());
        }
        _ => {}
    }
    // The return: u underlying steps (steps <= u <= steps * frame_skip), h of them hits (h <= lives lost,
    // and h >= 1 when a life was lost): return = u - 11 h. A saturated step counter bounds nothing above.
    let lost = i128::from(config.lives - w.lives);
    let steps = i128::from(w.steps);
    let lo = steps - 11 * lost;
    let hi = if w.steps == u32::MAX { i128::MAX } else { steps * i128::from(config.frame_skip) - 11 * lost.min(1) };
    if !(lo..=hi).contains(&i128::from(w.episode_return)) {
        return Err(format!(
            "return {} is out of reach after {} steps with {} lives lost (allowed {lo}..={hi})",
            w.episode_return, w.steps, lost
        ));
    }
    // Fuel burns one unit per underlying step from max_fuel, or from a refill.
    if u128::from(w.fuel_left) + u128::from(w.steps) * u128::from(config.frame_skip) < u128::from(config.max_fuel) {
        return Err(format!("fuel {} cannot have burnt in {} steps", w.fuel_left, w.steps));
    }
    if w.steps == 0 && (*w != World { chopper: w.chopper, status: Status::Running, ..fresh() } || !spawn(&w.chopper)) {
        return Err("a just-reset episode holds a state other than a reset one".into());
    }
    if w.steps == 0 && prev_action != Action::Noop {
        return Err("a just-reset episode has a last action other than Do Nothing".into());
    }
    check_entities(w)
}

fn spawn(c: &Rect) -> bool {
    (CHOPPER_SPAWN_X.0..CHOPPER_SPAWN_X.1).contains(&c.x) && (CHOPPER_SPAWN_Y.0..CHOPPER_SPAWN_Y.1).contains(&c.y)
}

/// Entity lists: sizes, positions on their paths, order of appearance, and counts.
fn check_entities(w: &World) -> Result<(), String> {
    let bird_spawn = X_MAX - BIRD_SIZE.0;
    let on_flight = |x: i32| x == X_MIN || (x < bird_spawn && (bird_spawn - x) % BIRD_SPEED == 0);
    if w.birds.len() > MAX_BIRDS {
        return Err(format!("{} birds: at most {MAX_BIRDS} fit on screen", w.birds.len()));
    }
    if let Some(b) = w.birds.iter().find(|b| !on_flight(b.x)) {
        return Err(format!("a bird at x = {} is off every bird's path", b.x));
    }
    if w.birds.windows(2).any(|p| p[0].x >= p[1].x) {
        return Err("birds are not in order of appearance".into());
    }
    let tank_spawn = Y_MAX - FUEL_TANK_SIZE.1;
    if w.fuel_tanks.len() > MAX_FUEL_TANKS {
        return Err(format!("{} fuel tanks: at most {MAX_FUEL_TANKS} fit on screen", w.fuel_tanks.len()));
    }
    let on_rise = |y: i32| y == Y_MIN || (y < tank_spawn && (tank_spawn - y) % FUEL_TANK_SPEED == 0);
    if let Some(t) = w.fuel_tanks.iter().find(|t| !on_rise(t.y)) {
        return Err(format!("a fuel tank at y = {} is off every tank's path", t.y));
    }
    if w.fuel_tanks.windows(2).any(|p| p[0].y >= p[1].y) {
        return Err("fuel tanks are not in order of appearance".into());
    }
    if w.aliens.len() > MAX_BIRDS {
        return Err(format!("{} aliens: at most {MAX_BIRDS} fit on screen", w.aliens.len()));
    }
    if let Some(a) = w.aliens.iter().find(|a| a.age == 0 || a.age > MAX_ALIEN_AGE || a.body.x != alien_x(a.age)) {
        return Err(format!("an alien of age {} at x = {} is not where that age puts it", a.age, a.body.x));
    }
    if w.aliens.windows(2).any(|p| p[0].age <= p[1].age) {
        return Err("aliens are not in order of appearance".into());
    }
    if w.missiles.len() > MAX_MISSILES {
        return Err(format!("{} missiles: at most {MAX_MISSILES} can be in flight", w.missiles.len()));
    }
    // A missile starts at an alien's x (768 - 5a) + MISSILE_OFFSET.0 and moves 10 (two bird steps) at a time.
    let missile_phase = (X_MAX - ALIEN_SIZE.0 + MISSILE_OFFSET.0).rem_euclid(BIRD_SPEED);
    let missile_ys = (Y_MIN + MISSILE_OFFSET.1)..=(Y_MAX - ALIEN_SIZE.1 + MISSILE_OFFSET.1);
    if let Some(m) = w
        .missiles
        .iter()
        .find(|m| !(m.x == X_MIN || m.x.rem_euclid(BIRD_SPEED) == missile_phase) || !missile_ys.contains(&m.y))
    {
        return Err(format!("a missile at ({}, {}) is off every missile's path", m.x, m.y));
    }
    Ok(())
}

/// Checks the frame stack: its type and length (already checked by the decoder), and every value: what the
/// observation space allows, finite, `rgb_float` values exactly a byte over 255, all zero before any reset.
pub(crate) fn check_stacked(config: &Config, status: Status, stacked: &ObsData) -> Result<(), String> {
    let zero = match stacked {
        ObsData::U8(v) => v.iter().all(|&x| x == 0),
        ObsData::F32(v) => v.iter().all(|&x| x.to_bits() == 0),
    };
    if status == Status::NotStarted {
        return if zero { Ok(()) } else { Err("a never-reset environment holds a non-zero frame stack".into()) };
    }
    let ObsData::F32(values) = stacked else { return Ok(()) };
    let bad = match config.obs_type {
        ObsType::RgbFloat => values.iter().position(|&v| {
            let s = v * 255.0;
            !(0.0..=255.0).contains(&s) || (s.round() / 255.0).to_bits() != v.to_bits()
        }),
        _ => {
            let (low, high) = (crate::features::low(), crate::features::high());
            values.iter().enumerate().position(|(i, &v)| {
                let j = i % low.len();
                !(v.is_finite() && low[j] <= v && v <= high[j])
            })
        }
    };
    match bad {
        Some(i) => Err(format!("frame stack value {} at index {i} is not an observation value", values[i])),
        None => Ok(()),
    }
}
