//! Built-in policies for demos, tests and baselines. A policy picks an action from the world it sees; the
//! trained ones (exported to ONNX) run in the `chopperscape-policy` crate.
//!
//! - `random`: a uniform action from the policy's own seeded generator (independent of the env's).
//! - `right`, `left`, `down`, `up`, `noop`: one fixed action.
//! - `heuristic`: a scripted policy that plans in agent steps. An action it picks is held for `frame_skip`
//!   underlying steps (ticks), so for each first action it tries every plan "this action for one agent step, then
//!   hold one action" over the next `frame_skip + LOOKAHEAD − 1` ticks against the hazards' known motion (birds
//!   and aliens 5 px left per tick, missiles 10, an alien's next missiles from when it fires), and scores the
//!   first action by the longest time its best plan stays clear of every hazard (with a safety margin, wider
//!   around aliens and missiles). Under sticky actions (`sticky_prob > 0`) a plan is scored by its worse case of
//!   each change of action happening on time or one tick late, with a wider margin. Among equally safe actions it flies toward the nearest
//!   reachable fuel tank when fuel is below half, else home (left quarter, mid height). Ties go to the lower
//!   action index, so it is deterministic. Under the v0 rules (`frame_skip` 1, no sticky actions, no
//!   aliens) it picks exactly the actions of the earlier frame-by-frame planner.

use crate::action::Action;
use crate::config::Config;
use crate::consts::{
    ALIEN_SHOT_PERIOD, BIRD_SPEED, CHOPPER_SPEED, FUEL_TANK_SPEED, MISSILE_OFFSET, MISSILE_SIZE, MISSILE_SPEED, X_MIN,
    Y_MAX, Y_MIN,
};
use crate::geometry::Rect;
use crate::rng::Rng;
use crate::world::World;

/// Every built-in policy name, as `by_name` accepts it.
pub const NAMES: &[&str] = &["random", "heuristic", "right", "left", "down", "up", "noop"];

/// Ticks (underlying steps) the heuristic policy looks ahead beyond its first agent step.
pub const LOOKAHEAD: i32 = 32;

/// A policy: picks an action from the world it sees.
pub trait Policy {
    /// The action for this state.
    fn act(&mut self, world: &World) -> Action;
}

/// Builds a built-in policy by name for an env with `config`'s options (the heuristic plans with its
/// `frame_skip` and `sticky_prob`); `seed` seeds `random`'s own generator (the others ignore it).
///
/// # Errors
/// An unknown name; the message lists the known ones.
pub fn by_name(name: &str, seed: u64, config: &Config) -> Result<Box<dyn Policy + Send + Sync>, String> {
    Ok(match name {
        "random" => Box::new(RandomPolicy::new(seed)),
        "heuristic" => Box::new(Heuristic::for_config(config)),
        "right" => Box::new(Fixed(Action::Right)),
        "left" => Box::new(Fixed(Action::Left)),
        "down" => Box::new(Fixed(Action::Down)),
        "up" => Box::new(Fixed(Action::Up)),
        "noop" => Box::new(Fixed(Action::Noop)),
        _ => return Err(format!("unknown policy `{name}`: allowed policies are {}", NAMES.join(", "))),
    })
}

/// Uniformly random actions from its own generator.
#[derive(Clone, Debug)]
pub struct RandomPolicy {
    rng: Rng,
}

impl RandomPolicy {
    /// A random policy whose generator is seeded with `seed`.
    pub fn new(seed: u64) -> RandomPolicy {
        RandomPolicy { rng: Rng::seed_from_u64(seed) }
    }
}

impl Policy for RandomPolicy {
    fn act(&mut self, _world: &World) -> Action {
        Action::ALL[self.rng.below(Action::ALL.len() as u32) as usize]
    }
}

/// Always the same action.
#[derive(Clone, Copy, Debug)]
pub struct Fixed(pub Action);

impl Policy for Fixed {
    fn act(&mut self, _world: &World) -> Action {
        self.0
    }
}

/// The scripted policy (see the module docs).
#[derive(Clone, Copy, Debug)]
pub struct Heuristic {
    /// Ticks an action is held for (the env's `frame_skip`).
    hold: i32,
    /// Ticks the previous action may still be applied for at each change of action (1 under sticky actions):
    /// a plan is scored by its worse case, started on time or late.
    late: i32,
    /// Pixels of clearance kept around the chopper.
    margin: i32,
    /// The action it picked last in this episode (`Noop` at its start, as the rules' previous action).
    last: Action,
}

impl Default for Heuristic {
    /// The heuristic for the v0 rules (`frame_skip` 1, no sticky actions).
    fn default() -> Heuristic {
        Heuristic::for_config(&Config::default())
    }
}

impl Heuristic {
    /// The heuristic for an env with these options.
    pub fn for_config(config: &Config) -> Heuristic {
        let hold = i32::try_from(config.frame_skip).unwrap_or(i32::MAX).max(1);
        let sticky = config.sticky_prob > 0.0;
        Heuristic {
            hold,
            late: i32::from(sticky),
            margin: if sticky { MARGIN + STICKY_MARGIN / hold } else { MARGIN },
            last: Action::Noop,
        }
    }
}

impl Policy for Heuristic {
    fn act(&mut self, world: &World) -> Action {
        if world.steps == 0 {
            self.last = Action::Noop;
        }
        let hazards = Hazards::of(world, self.hold.saturating_add(LOOKAHEAD - 1), self.margin);
        let mut best = (i32::MIN, f32::INFINITY, Action::Noop);
        for first in Action::ALL {
            let plan = |then: Action| {
                let on_time = hazards.clear_steps(world.chopper, self.last, 0, first, self.hold, then);
                (1..=self.late).fold(on_time, |worst, d| {
                    worst.min(hazards.clear_steps(world.chopper, self.last, d, first, self.hold, then))
                })
            };
            let clear = Action::ALL.iter().map(|&then| plan(then)).max().unwrap_or(0);
            let mut at = world.chopper;
            let (dx, dy) = first.delta();
            for _ in 0..self.hold.min(LOOKAHEAD) {
                at.shift(dx, dy);
            }
            let pull = attraction(world, &at);
            if clear > best.0 || (clear == best.0 && pull < best.1) {
                best = (clear, pull, first);
            }
        }
        self.last = best.2;
        best.2
    }
}

/// Pixels of clearance the heuristic keeps around hazards.
const MARGIN: i32 = 4;
/// Extra pixels of clearance around aliens and missiles (which fire and fly faster than birds).
const ALIEN_MARGIN: i32 = 8;
/// Extra pixels of clearance under sticky actions at `frame_skip` 1 (divided by `frame_skip`): a sticky tick
/// shifts the chopper 5 px off its plan, and at every tick the heuristic would otherwise dodge at the last moment.
const STICKY_MARGIN: i32 = 12;
/// Most hazards the heuristic tracks (the rest are ignored; the screen rarely holds more).
const MAX_HAZARDS: usize = 32;

/// A hazard's known motion: where it is, how fast it flies left, and from which step it exists.
#[derive(Clone, Copy)]
struct Path {
    start: Rect,
    speed: i32,
    from: i32,
    /// Extra clearance around it, beyond `MARGIN`.
    extra: i32,
}

impl Path {
    /// Its box after `t` steps, or `None` before it exists or after it left.
    fn at(&self, t: i32) -> Option<Rect> {
        if t < self.from {
            return None;
        }
        let x = self.start.x - self.speed * (t - self.from);
        let e = self.extra;
        (x + self.speed > X_MIN).then(|| Rect {
            x: x.max(X_MIN) - e,
            y: self.start.y - e,
            w: self.start.w + 2 * e,
            h: self.start.h + 2 * e,
        })
    }
}

/// The hazards on screen, with their predicted motion over `horizon` ticks; no allocation.
struct Hazards {
    paths: [Path; MAX_HAZARDS],
    len: usize,
    horizon: i32,
    /// Pixels of clearance around the chopper.
    margin: i32,
}

impl Hazards {
    fn of(world: &World, horizon: i32, margin: i32) -> Hazards {
        let none = Path { start: Rect::default(), speed: 0, from: i32::MAX, extra: 0 };
        let extra = ALIEN_MARGIN;
        let mut h = Hazards { paths: [none; MAX_HAZARDS], len: 0, horizon, margin };
        let mut push = |p: Path| {
            if h.len < MAX_HAZARDS {
                h.paths[h.len] = p;
                h.len += 1;
            }
        };
        world.birds.iter().for_each(|&b| push(Path { start: b, speed: BIRD_SPEED, from: 0, extra: 0 }));
        world.missiles.iter().for_each(|&m| push(Path { start: m, speed: MISSILE_SPEED, from: 0, extra }));
        for a in &world.aliens {
            push(Path { start: a.body, speed: BIRD_SPEED, from: 0, extra });
            // Its next missiles, each fired from where the alien is then.
            let mut wait = a.steps_to_next_shot() as i32 + 1;
            while wait <= horizon {
                let (ox, oy) = MISSILE_OFFSET;
                let missile = Rect::placed(a.body.x - BIRD_SPEED * wait + ox, a.body.y + oy, MISSILE_SIZE);
                // It moves in the tick it is fired: as if it existed, at the alien's nose, one tick earlier.
                push(Path { start: missile, speed: MISSILE_SPEED, from: wait - 1, extra });
                wait += ALIEN_SHOT_PERIOD as i32;
            }
        }
        h
    }

    /// How good the plan "`first` for `hold` ticks, then hold `then`" is (after `delay` ticks of `prev`, the
    /// previous action): twice the ticks it stays clear of every hazard (up to the horizon), less one for each
    /// hazard still ahead in the chopper's lane at the end (so that fleeing from a bird, which only postpones the
    /// hit, scores below leaving its lane).
    fn clear_steps(&self, mut chopper: Rect, prev: Action, delay: i32, first: Action, hold: i32, then: Action) -> i32 {
        let m = self.margin;
        let grow = |c: &Rect| Rect { x: c.x - m, y: c.y - m, w: c.w + 2 * m, h: c.h + 2 * m };
        for t in 1..=self.horizon {
            let action = if t <= delay {
                prev
            } else if t <= hold + 2 * delay {
                first
            } else {
                then
            };
            let (dx, dy) = action.delta();
            chopper.shift(dx, dy);
            let grown = grow(&chopper);
            if self.paths[..self.len].iter().any(|p| p.at(t).is_some_and(|b| grown.collides(&b))) {
                return 2 * (t - 1);
            }
        }
        let grown = grow(&chopper);
        let in_lane = self.paths[..self.len]
            .iter()
            .filter_map(|p| p.at(self.horizon))
            .filter(|b| b.x + b.w >= grown.x && 2 * (b.centre2().1 - grown.centre2().1).abs() <= 2 * (b.h + grown.h))
            .count();
        2 * self.horizon - in_lane as i32
    }
}

/// Distance cost to where the heuristic wants to be: a reachable fuel tank when fuel is below half, else home.
fn attraction(world: &World, at: &Rect) -> f32 {
    let (cx, cy) = at.centre2();
    let (cx, cy) = (cx as f32 / 2.0, cy as f32 / 2.0);
    let low_fuel = world.fuel_left < 500;
    let tank = world
        .fuel_tanks
        .iter()
        .filter(|t| {
            // Reachable: the chopper can close the horizontal gap before the tank leaves the top of the band.
            let steps_left = (t.y - Y_MIN) / FUEL_TANK_SPEED;
            let gap = ((t.x + t.w / 2) - (at.x + at.w / 2)).abs() - at.w / 2;
            gap <= steps_left * CHOPPER_SPEED
        })
        .min_by_key(|t| ((t.x - at.x).abs(), t.y));
    let (tx, ty) = match (low_fuel, tank) {
        (true, Some(t)) => ((t.x + t.w / 2) as f32, (t.y + t.h / 2 - 4 * FUEL_TANK_SPEED) as f32),
        _ => (200.0, ((Y_MIN + Y_MAX) / 2) as f32),
    };
    let weight = if low_fuel { 1.0 } else { 0.05 };
    weight * ((cx - tx).abs() + (cy - ty).abs())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rules::Game;

    fn mean_return(name: &str, episodes: u64) -> f64 {
        mean_return_with(name, episodes, &[])
    }

    fn mean_return_with(name: &str, episodes: u64, options: &[(&str, &str)]) -> f64 {
        let mut total = 0i64;
        for seed in 0..episodes {
            let mut config = Config { max_episode_steps: Some(1500), ..Config::features() };
            for (k, v) in options {
                config.set(k, v).unwrap();
            }
            let mut game = Game::new(config.clone()).unwrap();
            let mut policy = by_name(name, seed, &config).unwrap();
            game.reset(Some(seed));
            while !game.world().status.is_over() {
                let a = policy.act(game.world());
                game.step(a).unwrap();
            }
            total += game.world().episode_return;
        }
        total as f64 / episodes as f64
    }

    #[test]
    fn heuristic_clearly_beats_random() {
        let random = mean_return("random", 8);
        let heuristic = mean_return("heuristic", 8);
        assert!(heuristic > 2.0 * random.max(1.0), "heuristic {heuristic} vs random {random}");
    }

    #[test]
    fn heuristic_stays_far_above_random_under_every_option() {
        // Planning frame by frame, the heuristic fell to about random under frame_skip 4 and sticky actions.
        for options in [
            &[("frame_skip", "4")][..],
            &[("sticky_prob", "0.25")],
            &[("alien_prob", "0.005")],
            // Random lives about 1100 steps with three lives: a longer cap keeps the comparison meaningful.
            &[("lives", "3"), ("max_episode_steps", "4000")],
            &[("bird_fuel_collision", "destroy")],
        ] {
            let random = mean_return_with("random", 8, options);
            let heuristic = mean_return_with("heuristic", 8, options);
            assert!(heuristic > 2.0 * random.max(1.0), "{options:?}: heuristic {heuristic} vs random {random}");
        }
    }

    #[test]
    fn heuristic_forgets_its_last_action_at_reset() {
        let config = Config { sticky_prob: 0.25, ..Config::features() };
        let mut game = Game::new(config.clone()).unwrap();
        let mut used = Heuristic::for_config(&config);
        game.reset(Some(3));
        for _ in 0..50 {
            let a = used.act(game.world());
            game.step(a).unwrap();
        }
        game.reset(Some(4));
        let mut fresh = Heuristic::for_config(&config);
        assert_eq!(used.act(game.world()), fresh.act(game.world()));
    }

    #[test]
    fn unknown_policy_names_the_known_ones() {
        let err = by_name("genius", 0, &Config::default()).err().unwrap();
        assert!(err.contains("genius") && err.contains("heuristic"), "{err}");
    }

    #[test]
    fn random_policy_is_seeded() {
        let w = World::default();
        let (mut a, mut b) = (RandomPolicy::new(9), RandomPolicy::new(9));
        let xs: Vec<Action> = (0..50).map(|_| a.act(&w)).collect();
        let ys: Vec<Action> = (0..50).map(|_| b.act(&w)).collect();
        assert_eq!(xs, ys);
        assert!(Action::ALL.iter().all(|x| xs.contains(x)));
    }
}
