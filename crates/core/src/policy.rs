//! Built-in pilots for demos, tests and baselines.
//!
//! - `random`: a uniform action from the policy's own seeded generator (independent of the env's).
//! - `right`, `left`, `down`, `up`, `noop`: one fixed action.
//! - `heuristic`: a scripted pilot. For each first action it tries every plan "this action, then hold one action"
//!   over the next [`LOOKAHEAD`] steps against the hazards' known motion (birds and aliens 5 px left per step,
//!   missiles 10, an alien's next missile from when it fires), and scores the first action by the longest time its
//!   best plan stays clear of every hazard (with a small safety margin). Among equally safe actions it flies toward
//!   the nearest reachable fuel tank when fuel is below half, else home (left quarter, mid height). Ties go to the
//!   lower action index, so it is deterministic.

use crate::action::Action;
use crate::consts::{
    BIRD_SPEED, CHOPPER_SPEED, FUEL_TANK_SPEED, MISSILE_OFFSET, MISSILE_SIZE, MISSILE_SPEED, X_MIN, Y_MAX, Y_MIN,
};
use crate::geometry::Rect;
use crate::rng::Rng;
use crate::world::World;

/// Every built-in policy name, as `by_name` accepts it.
pub const NAMES: &[&str] = &["random", "heuristic", "right", "left", "down", "up", "noop"];

/// Steps ahead the heuristic pilot looks for hazards.
pub const LOOKAHEAD: i32 = 32;

/// A pilot: picks an action from the world it sees.
pub trait Policy {
    /// The action for this state.
    fn act(&mut self, world: &World) -> Action;
}

/// Builds a built-in policy by name; `seed` seeds `random`'s own generator (the others ignore it).
///
/// # Errors
/// An unknown name; the message lists the known ones.
pub fn by_name(name: &str, seed: u64) -> Result<Box<dyn Policy + Send>, String> {
    Ok(match name {
        "random" => Box::new(RandomPolicy::new(seed)),
        "heuristic" => Box::new(Heuristic),
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
    /// A random pilot whose generator is seeded with `seed`.
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

/// The scripted pilot (see the module docs).
#[derive(Clone, Copy, Debug, Default)]
pub struct Heuristic;

impl Policy for Heuristic {
    fn act(&mut self, world: &World) -> Action {
        let hazards = Hazards::of(world);
        let mut best = (i32::MIN, f32::INFINITY, Action::Noop);
        for first in Action::ALL {
            let clear =
                Action::ALL.iter().map(|&then| hazards.clear_steps(world.chopper, first, then)).max().unwrap_or(0);
            let mut at = world.chopper;
            let (dx, dy) = first.delta();
            at.shift(dx, dy);
            let pull = attraction(world, &at);
            if clear > best.0 || (clear == best.0 && pull < best.1) {
                best = (clear, pull, first);
            }
        }
        best.2
    }
}

/// Pixels of clearance the heuristic keeps around hazards.
const MARGIN: i32 = 4;
/// Most hazards the heuristic tracks (the rest are ignored; the screen rarely holds more).
const MAX_HAZARDS: usize = 32;

/// A hazard's known motion: where it is, how fast it flies left, and from which step it exists.
#[derive(Clone, Copy)]
struct Path {
    start: Rect,
    speed: i32,
    from: i32,
}

impl Path {
    /// Its box after `t` steps, or `None` before it exists or after it left.
    fn at(&self, t: i32) -> Option<Rect> {
        if t < self.from {
            return None;
        }
        let x = self.start.x - self.speed * (t - self.from);
        (x + self.speed > X_MIN).then(|| Rect { x: x.max(X_MIN), ..self.start })
    }
}

/// The hazards on screen, with their predicted motion; no allocation.
struct Hazards {
    paths: [Path; MAX_HAZARDS],
    len: usize,
}

impl Hazards {
    fn of(world: &World) -> Hazards {
        let none = Path { start: Rect::default(), speed: 0, from: i32::MAX };
        let mut h = Hazards { paths: [none; MAX_HAZARDS], len: 0 };
        let mut push = |p: Path| {
            if h.len < MAX_HAZARDS {
                h.paths[h.len] = p;
                h.len += 1;
            }
        };
        world.birds.iter().for_each(|&b| push(Path { start: b, speed: BIRD_SPEED, from: 0 }));
        world.missiles.iter().for_each(|&m| push(Path { start: m, speed: MISSILE_SPEED, from: 0 }));
        for a in &world.aliens {
            push(Path { start: a.body, speed: BIRD_SPEED, from: 0 });
            // Its next missile, fired from where the alien is then.
            let wait = a.steps_to_next_shot() as i32 + 1;
            if wait <= LOOKAHEAD {
                let (ox, oy) = MISSILE_OFFSET;
                let missile = Rect::placed(a.body.x - BIRD_SPEED * wait + ox, a.body.y + oy, MISSILE_SIZE);
                push(Path { start: missile, speed: MISSILE_SPEED, from: wait });
            }
        }
        h
    }

    /// How good the plan "`first`, then hold `then`" is: twice the steps it stays clear of every hazard (up to
    /// `LOOKAHEAD`), less one for each hazard still ahead in the chopper's lane at the end (so that fleeing from a
    /// bird, which only postpones the hit, scores below leaving its lane).
    fn clear_steps(&self, mut chopper: Rect, first: Action, then: Action) -> i32 {
        let grow = |c: &Rect| Rect { x: c.x - MARGIN, y: c.y - MARGIN, w: c.w + 2 * MARGIN, h: c.h + 2 * MARGIN };
        for t in 1..=LOOKAHEAD {
            let (dx, dy) = if t == 1 { first.delta() } else { then.delta() };
            chopper.shift(dx, dy);
            let grown = grow(&chopper);
            if self.paths[..self.len].iter().any(|p| p.at(t).is_some_and(|b| grown.collides(&b))) {
                return 2 * (t - 1);
            }
        }
        let grown = grow(&chopper);
        let in_lane = self.paths[..self.len]
            .iter()
            .filter_map(|p| p.at(LOOKAHEAD))
            .filter(|b| b.x + b.w >= grown.x && 2 * (b.centre2().1 - grown.centre2().1).abs() <= 2 * (b.h + grown.h))
            .count();
        2 * LOOKAHEAD - in_lane as i32
    }
}

/// Distance cost to where the pilot wants to be: a reachable fuel tank when fuel is below half, else home.
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
    use crate::config::Config;
    use crate::rules::Game;

    fn mean_return(name: &str, episodes: u64) -> f64 {
        let mut total = 0i64;
        for seed in 0..episodes {
            let config = Config { max_episode_steps: Some(1500), ..Config::features() };
            let mut game = Game::new(config).unwrap();
            let mut policy = by_name(name, seed).unwrap();
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
    fn unknown_policy_names_the_known_ones() {
        let err = by_name("genius", 0).err().unwrap();
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
