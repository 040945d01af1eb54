//! Unit tests of each rule of SPEC.md, on hand-built states.

use super::*;

/// A game with no random spawns, reset with seed 0, chopper moved to `(x, y)`.
fn quiet_game(config: Config, x: i32, y: i32) -> Game {
    let mut g = Game::new(Config { bird_prob: 0.0, fuel_prob: 0.0, ..config }).unwrap();
    g.reset(Some(0));
    g.world.chopper = Rect::placed(x, y, CHOPPER_SIZE);
    g
}

fn v0() -> Config {
    Config::features()
}

#[test]
fn reset_places_chopper_in_spawn_area_with_full_fuel_and_empty_sky() {
    let mut g = Game::new(v0()).unwrap();
    for seed in 0..200 {
        g.reset(Some(seed));
        let w = g.world();
        assert!((40..80).contains(&w.chopper.x) && (90..120).contains(&w.chopper.y), "{:?}", w.chopper);
        assert_eq!((w.fuel_left, w.episode_return, w.lives, w.steps), (1000, 0, 1, 0));
        assert!(w.birds.is_empty() && w.fuel_tanks.is_empty() && w.aliens.is_empty() && w.missiles.is_empty());
        assert_eq!(w.status, Status::Running);
    }
}

#[test]
fn each_step_burns_one_fuel_and_pays_one() {
    let mut g = quiet_game(v0(), 100, 100);
    let o = g.step(Action::Noop).unwrap();
    assert_eq!(o.reward, 1.0);
    assert_eq!(g.world.fuel_left, 999);
    assert_eq!(g.world.episode_return, 1);
}

#[test]
fn actions_move_the_chopper_and_clamp_at_the_band() {
    let mut g = quiet_game(v0(), 100, 100);
    for (a, expect) in [
        (Action::Right, (105, 100)),
        (Action::Left, (100, 100)),
        (Action::Down, (100, 105)),
        (Action::Up, (100, 100)),
        (Action::Noop, (100, 100)),
    ] {
        g.step(a).unwrap();
        assert_eq!((g.world.chopper.x, g.world.chopper.y), expect, "{a:?}");
    }
    let mut g = quiet_game(v0(), 2, 62);
    g.step(Action::Left).unwrap();
    g.step(Action::Up).unwrap();
    assert_eq!((g.world.chopper.x, g.world.chopper.y), (0, 60));
    let mut g = quiet_game(v0(), 734, 474);
    g.step(Action::Right).unwrap();
    g.step(Action::Down).unwrap();
    assert_eq!((g.world.chopper.x, g.world.chopper.y), (736, 476));
}

#[test]
fn a_new_bird_appears_at_the_clamped_right_edge_and_moves_in_the_same_step() {
    let mut g = Game::new(Config { bird_prob: 1.0, fuel_prob: 0.0, ..v0() }).unwrap();
    g.reset(Some(1));
    let mut ys = Vec::new();
    for _ in 0..300 {
        g.step(Action::Noop).unwrap();
        assert_eq!(g.world.birds.len(), 1, "one bird appears every step with bird_prob = 1");
        let b = g.world.birds.pop().unwrap(); // taken away before it can reach the chopper
        assert_eq!(b.x, 768 - 5);
        assert!((60..=508).contains(&b.y), "{b:?}");
        ys.push(b.y);
    }
    assert!(ys.contains(&508), "draws in [508, 540) clamp to 508");
    assert!(ys.contains(&60));
}

#[test]
fn a_new_fuel_tank_appears_at_the_clamped_bottom_and_rises_in_the_same_step() {
    let mut g = Game::new(Config { bird_prob: 0.0, fuel_prob: 1.0, ..v0() }).unwrap();
    g.reset(Some(0));
    for _ in 0..50 {
        g.step(Action::Noop).unwrap();
        let t = *g.world.fuel_tanks.last().unwrap();
        assert_eq!(t.y, 508 - 5);
        assert!((0..=768).contains(&t.x), "{t:?}");
    }
}

#[test]
fn bird_leaving_left_edge_is_not_tested_for_collision() {
    let mut g = quiet_game(v0(), 0, 100);
    g.world.birds.push(Rect::placed(0, 100, BIRD_SIZE)); // overlapping the chopper, at x = X_MIN
    let o = g.step(Action::Noop).unwrap();
    assert!(g.world.birds.is_empty());
    assert_eq!(o.reward, 1.0);
    assert!(!o.terminated);
}

#[test]
fn bird_that_moves_onto_the_chopper_hits_it() {
    let mut g = quiet_game(v0(), 0, 100);
    g.world.birds.push(Rect::placed(5, 300, BIRD_SIZE)); // far below: moves to x = 0, no hit
    g.world.birds.push(Rect::placed(5 + 64 + 5, 100, BIRD_SIZE)); // moves to x = 69: 5 px gap, no hit
    g.world.birds.push(Rect::placed(64 + 5, 100, BIRD_SIZE)); // moves to x = 64: touching, hit
    let o = g.step(Action::Noop).unwrap();
    assert_eq!(o.reward, -10.0);
    assert!(o.terminated);
    assert_eq!(g.world.status, Status::Terminated(Cause::Bird));
    assert_eq!(g.world.episode_return, -10);
    assert_eq!(g.world.lives, 0);
    assert_eq!(g.world.birds.len(), 3, "the crash stays on screen");
}

#[test]
fn refuel_in_the_same_step_as_the_last_drop_of_fuel_continues() {
    let mut g = quiet_game(v0(), 100, 100);
    g.world.fuel_left = 1;
    g.world.fuel_tanks.push(Rect::placed(116, 169, FUEL_TANK_SIZE)); // rises to y = 164: touching
    let o = g.step(Action::Noop).unwrap();
    assert!(!o.terminated);
    assert_eq!(g.world.fuel_left, 1000);
    assert!(g.world.fuel_tanks.is_empty());
}

#[test]
fn fuel_runs_out_after_max_fuel_steps() {
    let mut g = quiet_game(Config { max_fuel: 30, ..v0() }, 100, 100);
    g.world.fuel_left = 30;
    for i in 1..=30 {
        let o = g.step(Action::Noop).unwrap();
        assert_eq!(o.reward, 1.0);
        assert_eq!(o.terminated, i == 30, "step {i}");
    }
    assert_eq!(g.world.status, Status::Terminated(Cause::Fuel));
    assert_eq!(g.world.episode_return, 30);
}

#[test]
fn a_tank_leaving_the_top_is_removed_without_refuelling() {
    let mut g = quiet_game(v0(), 100, 60);
    g.world.fuel_left = 10;
    g.world.fuel_tanks.push(Rect::placed(110, 60, FUEL_TANK_SIZE));
    g.step(Action::Noop).unwrap();
    assert!(g.world.fuel_tanks.is_empty());
    assert_eq!(g.world.fuel_left, 9);
}

#[test]
fn with_lives_a_hit_costs_a_life_removes_the_bird_and_goes_on() {
    let mut g = quiet_game(Config { lives: 2, ..v0() }, 100, 100);
    g.world.lives = 2;
    g.world.birds.push(Rect::placed(169, 100, BIRD_SIZE));
    let o = g.step(Action::Noop).unwrap();
    assert_eq!((o.reward, o.terminated), (-10.0, false));
    assert_eq!(g.world.lives, 1);
    assert!(g.world.birds.is_empty());
    g.world.birds.push(Rect::placed(169, 100, BIRD_SIZE));
    let o = g.step(Action::Noop).unwrap();
    assert_eq!((o.reward, o.terminated), (-10.0, true));
    assert_eq!(g.world.status, Status::Terminated(Cause::Bird));
    assert_eq!(g.world.episode_return, -20);
}

#[test]
fn two_hits_in_one_step_give_minus_ten_not_minus_twenty() {
    let mut g = quiet_game(Config { lives: 3, ..v0() }, 100, 100);
    g.world.lives = 3;
    g.world.birds.push(Rect::placed(169, 100, BIRD_SIZE));
    g.world.birds.push(Rect::placed(169, 130, BIRD_SIZE));
    let o = g.step(Action::Noop).unwrap();
    assert_eq!(o.reward, -10.0);
    assert_eq!(g.world.lives, 1);
}

#[test]
fn destroy_removes_a_bird_and_a_tank_that_collide_and_pass_keeps_both() {
    for (mode, left) in [(BirdFuelCollision::Destroy, 0), (BirdFuelCollision::Pass, 1)] {
        let mut g = quiet_game(Config { bird_fuel_collision: mode, ..v0() }, 0, 60);
        g.world.birds.push(Rect::placed(405, 305, BIRD_SIZE)); // moves to (400, 305)
        g.world.fuel_tanks.push(Rect::placed(400, 310, FUEL_TANK_SIZE)); // rises to (400, 305)
        g.step(Action::Noop).unwrap();
        assert_eq!((g.world.birds.len(), g.world.fuel_tanks.len()), (left, left), "{mode:?}");
    }
}

#[test]
fn aliens_fire_twenty_steps_after_they_appear_then_every_forty() {
    let mut g = quiet_game(Config { alien_prob: 1e-12, ..v0() }, 0, 460);
    g.world.aliens.push(Alien { body: Rect::placed(700, 100, ALIEN_SIZE), age: 0 });
    let mut fired = Vec::new();
    for step in 0..101 {
        let before = g.world.missiles.len();
        g.step(Action::Noop).unwrap();
        if g.world.missiles.len() > before {
            let a = g.world.aliens[0].body;
            let m = *g.world.missiles.last().unwrap();
            assert_eq!(
                (m.x, m.y, m.w, m.h),
                (a.x - 16 - 10, a.y + 12, 16, 8),
                "placed at the left edge, then moved 10"
            );
            fired.push(step);
        }
    }
    assert_eq!(fired, [20, 60, 100]);
}

#[test]
fn a_missile_hit_counts_as_a_bird_hit() {
    let mut g = quiet_game(v0(), 100, 100);
    g.world.missiles.push(Rect::placed(174, 120, MISSILE_SIZE)); // moves to 164: touching
    let o = g.step(Action::Noop).unwrap();
    assert_eq!((o.reward, o.terminated), (-10.0, true));
    assert_eq!(g.world.status, Status::Terminated(Cause::Bird));
}

#[test]
fn an_alien_hit_counts_as_a_bird_hit() {
    let mut g = quiet_game(Config { lives: 2, ..v0() }, 100, 100);
    g.world.lives = 2;
    g.world.aliens.push(Alien { body: Rect::placed(169, 100, ALIEN_SIZE), age: 5 });
    let o = g.step(Action::Noop).unwrap();
    assert_eq!((o.reward, o.terminated, g.world.lives), (-10.0, false, 1));
    assert!(g.world.aliens.is_empty());
}

#[test]
fn frame_skip_repeats_the_action_and_sums_rewards_stopping_at_the_end() {
    let mut g = quiet_game(Config { frame_skip: 4, ..v0() }, 100, 100);
    let o = g.step(Action::Right).unwrap();
    assert_eq!(o.reward, 4.0);
    assert_eq!((g.world.chopper.x, g.world.fuel_left, g.world.steps), (120, 996, 1));
    g.world.fuel_left = 2;
    let o = g.step(Action::Right).unwrap();
    assert_eq!((o.reward, o.terminated), (2.0, true));
    assert_eq!(g.world.chopper.x, 130, "stopped after two frames");
}

#[test]
fn sticky_actions_repeat_the_previous_action() {
    let mut g = quiet_game(Config { sticky_prob: 1.0, ..v0() }, 100, 100);
    for a in [Action::Right, Action::Down, Action::Up] {
        g.step(a).unwrap();
    }
    assert_eq!((g.world.chopper.x, g.world.chopper.y), (100, 100), "Do Nothing after reset sticks forever");
}

#[test]
fn episodes_truncate_at_max_episode_steps() {
    let mut g = quiet_game(Config { max_episode_steps: Some(3), ..v0() }, 100, 100);
    assert!(!g.step(Action::Noop).unwrap().truncated);
    assert!(!g.step(Action::Noop).unwrap().truncated);
    let o = g.step(Action::Noop).unwrap();
    assert!(o.truncated && !o.terminated);
    assert_eq!(g.world.status, Status::Truncated);
}

#[test]
fn stepping_before_reset_or_after_the_end_is_an_error_that_changes_nothing() {
    let mut g = Game::new(v0()).unwrap();
    assert_eq!(g.step(Action::Noop), Err(Error::NotReset));
    let mut g = quiet_game(Config { max_fuel: 1, ..v0() }, 100, 100);
    g.world.fuel_left = 1;
    assert!(g.step(Action::Noop).unwrap().terminated);
    let before = g.clone();
    let err = g.step(Action::Noop).unwrap_err();
    assert!(err.to_string().contains("reset()"), "{err}");
    assert_eq!(g, before);
}
