//! The `"features"` observation: a fixed-length `f32` vector that describes the state.
//!
//! # Layout, version 2 ([`FEATURES_LEN`] = 46 values)
//! | index | name | range | meaning |
//! |---|---|---|---|
//! | 0 | `chopper_x` | [0, 1] | `(x − X_MIN) / (X_MAX − X_MIN − 64)` |
//! | 1 | `chopper_y` | [0, 1] | `(y − Y_MIN) / (Y_MAX − Y_MIN − 64)` |
//! | 2 | `fuel` | [0, 1] | `fuel_left / max_fuel` |
//! | 3 | `lives` | [0, 1] | `lives_left / lives` |
//! | 4–19 | `bird[0..4]` | see below | the 4 birds that can still hit, soonest first |
//! | 20–27 | `fuel_tank[0..2]` | see below | the 2 fuel tanks that can still be caught, nearest first |
//! | 28–37 | `alien[0..2]` | see below | the 2 alien birds that can still hit, soonest first |
//! | 38–45 | `missile[0..2]` | see below | the 2 missiles that can still hit, soonest first |
//!
//! Every entity slot starts with `present` (1 or 0), `dx = (cx − chopper_cx) / 800` and
//! `dy = (cy − chopper_cy) / 480`, both in [−1, 1], centre to centre; empty slots are all zero. Then:
//! - birds, aliens and missiles: `in_lane`, 1 when the hazard's row overlaps the chopper's (`2·|dy| ≤ h + 64`,
//!   in pixels): it hits unless one of them changes row before it arrives. Aliens add `next_shot`, the steps
//!   until the alien fires next, / 40, in [0, 1].
//! - fuel tanks: `reachable`, 1 when the chopper, flying straight sideways toward the tank, catches it before it
//!   rises past: with the gap `g = |dx| − (w + 64) / 2` and the room `r = dy + (h + 64) / 2` (pixels), the first
//!   `k ≥ 1` steps with `5k ≥ g` must satisfy `5k ≤ r` (chopper and tanks both move 5 a step).
//!
//! **Which entities fill the slots.** Hazards fly left and the chopper is no faster, so a hazard whose centre is
//! more than `(w + 64) / 2` left of the chopper's can never hit it: such hazards are left out, and the rest fill the
//! slots by centre x, soonest to arrive first. Hazards of one kind all fly at one speed, so a hazard keeps its slot
//! until one ahead of it leaves (slots do not swap as things move). Fuel tanks rise and the chopper is no faster,
//! so a tank whose centre is more than `(h + 64) / 2` above the chopper's can never be caught: those are left out,
//! and the rest fill the slots nearest first (squared centre distance). Ties go to the older entity.
//!
//! With `frame_stack = k`, `k` such vectors are concatenated, oldest first: shape `(46·k,)`.
//!
//! # Version history
//! - 2: hazards that can no longer hit and tanks that can no longer be caught are left out; hazards ordered by
//!   arrival (stable slots); `in_lane`, `reachable` and `next_shot` added (46 values). Made PPO learn the game
//!   (`docs/notes/features-layout.md`).
//! - 1: the 4 nearest birds, 2 tanks, 2 aliens, 2 missiles by distance, each (present, dx, dy) (34 values).

use crate::consts::{ALIEN_SHOT_PERIOD, CHOPPER_SIZE, CHOPPER_SPEED, FUEL_TANK_SPEED, X_MAX, X_MIN, Y_MAX, Y_MIN};

// `reachable` assumes the chopper flies sideways exactly as fast as tanks rise.
const _: () = assert!(CHOPPER_SPEED == FUEL_TANK_SPEED);
use crate::geometry::Rect;
use crate::world::World;

/// The layout version of the features vector (see the module docs).
pub const FEATURES_VERSION: u32 = 2;
/// Slots for birds.
pub const BIRD_SLOTS: usize = 4;
/// Slots for fuel tanks.
pub const FUEL_TANK_SLOTS: usize = 2;
/// Slots for alien birds.
pub const ALIEN_SLOTS: usize = 2;
/// Slots for missiles.
pub const MISSILE_SLOTS: usize = 2;
/// Values per bird, fuel-tank and missile slot: present, dx, dy, and `in_lane` or `reachable`.
pub const SLOT_LEN: usize = 4;
/// Values per alien slot: present, dx, dy, in_lane, next_shot.
pub const ALIEN_SLOT_LEN: usize = 5;
/// Index of the first bird slot.
pub const BIRDS_AT: usize = 4;
/// Index of the first fuel-tank slot.
pub const FUEL_TANKS_AT: usize = BIRDS_AT + SLOT_LEN * BIRD_SLOTS;
/// Index of the first alien slot.
pub const ALIENS_AT: usize = FUEL_TANKS_AT + SLOT_LEN * FUEL_TANK_SLOTS;
/// Index of the first missile slot.
pub const MISSILES_AT: usize = ALIENS_AT + ALIEN_SLOT_LEN * ALIEN_SLOTS;
/// Length of one features vector.
pub const FEATURES_LEN: usize = MISSILES_AT + SLOT_LEN * MISSILE_SLOTS;

/// Lower bound of each value, as declared in the observation space.
pub fn low() -> [f32; FEATURES_LEN] {
    let mut low = [0.0; FEATURES_LEN];
    let slots = (BIRDS_AT..FUEL_TANKS_AT)
        .step_by(SLOT_LEN)
        .chain((FUEL_TANKS_AT..ALIENS_AT).step_by(SLOT_LEN))
        .chain((ALIENS_AT..MISSILES_AT).step_by(ALIEN_SLOT_LEN))
        .chain((MISSILES_AT..FEATURES_LEN).step_by(SLOT_LEN));
    for at in slots {
        low[at + 1] = -1.0;
        low[at + 2] = -1.0;
    }
    low
}

/// Upper bound of each value, as declared in the observation space.
pub fn high() -> [f32; FEATURES_LEN] {
    [1.0; FEATURES_LEN]
}

// Centres are kept doubled (whole numbers), hence the factor 2 in the scales.
const DX_SCALE: f32 = 1.0 / (2 * (X_MAX - X_MIN)) as f32;
const DY_SCALE: f32 = 1.0 / (2 * (Y_MAX - Y_MIN)) as f32;

/// Writes the features of `world` into `out` (`out.len() == FEATURES_LEN`). `lives` and `max_fuel` are the options.
pub fn write(world: &World, lives: u32, max_fuel: u32, out: &mut [f32]) {
    let out: &mut [f32; FEATURES_LEN] = out.try_into().expect("features buffer of FEATURES_LEN values");
    // Empty slots are zero: clear everything once (a few vector stores), then write only what is present.
    *out = [0.0; FEATURES_LEN];
    let c = world.chopper;
    out[0] = (c.x - X_MIN) as f32 * (1.0 / (X_MAX - X_MIN - CHOPPER_SIZE.0) as f32);
    out[1] = (c.y - Y_MIN) as f32 * (1.0 / (Y_MAX - Y_MIN - CHOPPER_SIZE.1) as f32);
    out[2] = world.fuel_left as f32 / max_fuel as f32;
    out[3] = world.lives as f32 / lives as f32;
    hazards::<BIRD_SLOTS, SLOT_LEN, _>(&c, &world.birds, |r| (*r, None), &mut out[BIRDS_AT..FUEL_TANKS_AT]);
    fuel_tanks(&c, &world.fuel_tanks, &mut out[FUEL_TANKS_AT..ALIENS_AT]);
    hazards::<ALIEN_SLOTS, ALIEN_SLOT_LEN, _>(
        &c,
        &world.aliens,
        |a| (a.body, Some(a.steps_to_next_shot())),
        &mut out[ALIENS_AT..MISSILES_AT],
    );
    hazards::<MISSILE_SLOTS, SLOT_LEN, _>(&c, &world.missiles, |r| (*r, None), &mut out[MISSILES_AT..]);
}

/// Keeps the `SLOTS` smallest `(key, entity index)` pairs, sorted; strict `<` keeps the older entity first on ties.
#[inline]
fn keep_smallest<const SLOTS: usize>(best: &mut [(i64, usize); SLOTS], filled: &mut usize, key: i64, index: usize) {
    if *filled == SLOTS && key >= best[SLOTS - 1].0 {
        return;
    }
    let mut i = (*filled).min(SLOTS - 1);
    while i > 0 && key < best[i - 1].0 {
        best[i] = best[i - 1];
        i -= 1;
    }
    best[i] = (key, index);
    *filled = (*filled + 1).min(SLOTS);
}

/// Writes present, dx, dy of `e` relative to the chopper centre `(ccx, ccy)` (doubled) into `slot[..3]`.
#[inline]
fn position(slot: &mut [f32], (ccx, ccy): (i32, i32), e: &Rect) {
    let (ex, ey) = e.centre2();
    slot[0] = 1.0;
    slot[1] = (ex - ccx) as f32 * DX_SCALE;
    slot[2] = (ey - ccy) as f32 * DY_SCALE;
}

/// Fills the slots of hazards (things that fly left and hit): those that can still hit, soonest first.
/// `body` gives the box and, for aliens, the steps to the next shot (written after `in_lane`).
#[inline]
fn hazards<const SLOTS: usize, const LEN: usize, T>(
    chopper: &Rect,
    entities: &[T],
    body: impl Fn(&T) -> (Rect, Option<u32>),
    out: &mut [f32],
) {
    if entities.is_empty() {
        return;
    }
    let (ccx, ccy) = chopper.centre2();
    let mut best = [(i64::MAX, 0usize); SLOTS];
    let mut filled = 0;
    for (i, e) in entities.iter().enumerate() {
        let (r, _) = body(e);
        let ex = r.centre2().0;
        // Passed: more than (w + 64) / 2 left of the chopper's centre (doubled: w + 64).
        if ex < ccx - (r.w + chopper.w) {
            continue;
        }
        keep_smallest(&mut best, &mut filled, ex as i64, i);
    }
    for (slot, &(_, i)) in out.chunks_exact_mut(LEN).zip(&best[..filled]) {
        let (r, next_shot) = body(&entities[i]);
        position(slot, (ccx, ccy), &r);
        let ey = r.centre2().1;
        slot[3] = f32::from((ey - ccy).abs() <= r.h + chopper.h);
        if let Some(steps) = next_shot {
            slot[4] = (steps.min(ALIEN_SHOT_PERIOD)) as f32 * (1.0 / ALIEN_SHOT_PERIOD as f32);
        }
    }
}

/// Fills the fuel-tank slots: tanks that can still be caught, nearest first, with `reachable`.
#[inline]
fn fuel_tanks(chopper: &Rect, tanks: &[Rect], out: &mut [f32]) {
    if tanks.is_empty() {
        return;
    }
    let (ccx, ccy) = chopper.centre2();
    let mut best = [(i64::MAX, 0usize); FUEL_TANK_SLOTS];
    let mut filled = 0;
    for (i, t) in tanks.iter().enumerate() {
        let (tx, ty) = t.centre2();
        // Risen past: more than (h + 64) / 2 above the chopper's centre (doubled: h + 64).
        if ty < ccy - (t.h + chopper.h) {
            continue;
        }
        let (dx, dy) = ((tx - ccx) as i64, (ty - ccy) as i64);
        keep_smallest(&mut best, &mut filled, dx * dx + dy * dy, i);
    }
    for (slot, &(_, i)) in out.chunks_exact_mut(SLOT_LEN).zip(&best[..filled]) {
        let t = &tanks[i];
        position(slot, (ccx, ccy), t);
        let (tx, ty) = t.centre2();
        // Doubled: the gap and the room, in steps of 2 · 5 px (chopper and tank move alike).
        let gap = (tx - ccx).abs() - (t.w + chopper.w);
        let room = (ty - ccy) + (t.h + chopper.h);
        let steps = ((gap + 2 * CHOPPER_SPEED - 1) / (2 * CHOPPER_SPEED)).max(1);
        slot[3] = f32::from(2 * CHOPPER_SPEED * steps <= room);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::consts::{BIRD_SIZE, FUEL_TANK_SIZE};

    fn world_with_birds(xs: &[i32]) -> World {
        World {
            chopper: Rect::placed(100, 100, CHOPPER_SIZE),
            birds: xs.iter().map(|&x| Rect::placed(x, 116, BIRD_SIZE)).collect(),
            fuel_left: 500,
            lives: 1,
            ..World::default()
        }
    }

    fn slot(out: &[f32; FEATURES_LEN], at: usize, k: usize) -> &[f32] {
        &out[at + SLOT_LEN * k..at + SLOT_LEN * (k + 1)]
    }

    #[test]
    fn birds_ahead_fill_slots_soonest_first() {
        let w = world_with_birds(&[700, 300, 500, 200, 600]);
        let mut out = [0.0; FEATURES_LEN];
        write(&w, 1, 1000, &mut out);
        assert_eq!(out[2], 0.5);
        assert_eq!(out[3], 1.0);
        // chopper centre x = 132, bird centres = x + 16.
        let dxs: Vec<f32> = (0..4).map(|k| slot(&out, BIRDS_AT, k)[1]).collect();
        let expect: Vec<f32> = [200, 300, 500, 600].iter().map(|x| (x + 16 - 132) as f32 / 800.0).collect();
        for (a, e) in dxs.iter().zip(&expect) {
            assert!((a - e).abs() < 1e-6, "{dxs:?} vs {expect:?}");
        }
        assert!((0..4).all(|k| slot(&out, BIRDS_AT, k)[0] == 1.0 && slot(&out, BIRDS_AT, k)[3] == 1.0));
        assert!(out[FUEL_TANKS_AT..].iter().all(|&v| v == 0.0), "no tanks, aliens or missiles");
    }

    #[test]
    fn a_bird_that_has_passed_is_left_out_and_one_overlapping_is_kept() {
        // Chopper centre x = 132; a bird collides horizontally while |cx − 132| ≤ 48.
        // Bird at x = 68: centre 84, exactly 48 left: can still hit (touching counts). At x = 67: passed.
        let w = world_with_birds(&[67, 68]);
        let mut out = [0.0; FEATURES_LEN];
        write(&w, 1, 1000, &mut out);
        assert_eq!(slot(&out, BIRDS_AT, 0)[..2], [1.0, (84 - 132) as f32 / 800.0]);
        assert_eq!(slot(&out, BIRDS_AT, 1), [0.0; 4], "the passed bird takes no slot");
    }

    #[test]
    fn in_lane_marks_exactly_the_rows_that_collide() {
        // Chopper y = 100 (centre 132); bird h = 32: rows collide while |cy − 132| ≤ 48, i.e. bird y in [68, 164].
        for (y, lane) in [(68, 1.0), (67, 0.0), (164, 1.0), (165, 0.0), (116, 1.0)] {
            let mut w = world_with_birds(&[400]);
            w.birds[0].y = y;
            let mut out = [0.0; FEATURES_LEN];
            write(&w, 1, 1000, &mut out);
            assert_eq!(slot(&out, BIRDS_AT, 0)[3], lane, "bird y = {y}");
            // And the rules agree: flying straight at it, it hits exactly when in lane.
            let mut bird = w.birds[0];
            bird.x = w.chopper.x + 40;
            assert_eq!(bird.collides(&w.chopper), lane == 1.0, "bird y = {y}");
        }
    }

    #[test]
    fn fuel_tanks_risen_past_are_left_out_and_reachable_is_exact() {
        let mut w = world_with_birds(&[]);
        // Chopper (100, 100): centre (132, 132). A tank is caught while |cx − 132| ≤ 48 and |cy − 132| ≤ 48.
        // Tank at y = 52 + 8 = 60 has centre 76 < 132 − 48 = 84: risen past. At y = 68: centre 84, still catchable.
        w.fuel_tanks = vec![Rect::placed(100, 60, FUEL_TANK_SIZE), Rect::placed(116, 68, FUEL_TANK_SIZE)];
        let mut out = [0.0; FEATURES_LEN];
        write(&w, 1, 1000, &mut out);
        assert_eq!(slot(&out, FUEL_TANKS_AT, 0)[0], 1.0);
        assert_eq!(slot(&out, FUEL_TANKS_AT, 0)[2], (2 * (84 - 132)) as f32 * DY_SCALE);
        assert_eq!(slot(&out, FUEL_TANKS_AT, 1), [0.0; 4], "the risen tank takes no slot");
        // Reachable: a tank 200 px lower (centre dy = 200) has room 248 px, i.e. 49 steps: gaps up to 245 px,
        // |dx| up to 48 + 245 = 293.
        for (dx, reachable) in [(293, 1.0), (294, 0.0), (-293, 1.0), (-294, 0.0), (0, 1.0)] {
            w.chopper = Rect::placed(400, 100, CHOPPER_SIZE);
            w.fuel_tanks = vec![Rect::placed(416 + dx, 316, FUEL_TANK_SIZE)];
            write(&w, 1, 1000, &mut out);
            assert_eq!(slot(&out, FUEL_TANKS_AT, 0)[3], reachable, "dx = {dx}");
        }
    }

    #[test]
    fn reachable_tanks_are_caught_by_flying_sideways() {
        // Brute force the claim behind `reachable` over a grid of positions, away from the band's edges.
        for tx in (40..560).step_by(7) {
            for ty in (120..500).step_by(3) {
                let chopper = Rect::placed(300, 200, CHOPPER_SIZE);
                let tank = Rect::placed(tx, ty, FUEL_TANK_SIZE);
                let w = World { chopper, fuel_tanks: vec![tank], fuel_left: 10, lives: 1, ..World::default() };
                let mut out = [0.0; FEATURES_LEN];
                write(&w, 1, 1000, &mut out);
                if out[FUEL_TANKS_AT] == 0.0 {
                    continue;
                }
                let (mut c, mut t) = (chopper, tank);
                let mut caught = false;
                // As the rules do: the chopper moves, then the tank rises and is tested.
                while !caught && t.centre2().1 >= c.centre2().1 - (t.h + c.h) {
                    let gap = (t.centre2().0 - c.centre2().0).abs() - (t.w + c.w);
                    if gap > 0 {
                        c.shift((t.centre2().0 - c.centre2().0).signum() * CHOPPER_SPEED, 0);
                    }
                    t.y -= FUEL_TANK_SPEED;
                    caught = c.collides(&t);
                }
                assert_eq!(caught, out[FUEL_TANKS_AT + 3] == 1.0, "tank at ({tx}, {ty})");
            }
        }
    }

    #[test]
    fn alien_slots_carry_the_steps_to_the_next_shot() {
        use crate::consts::ALIEN_SIZE;
        use crate::world::Alien;
        let mut w = world_with_birds(&[]);
        w.aliens = vec![Alien { body: Rect::placed(500, 116, ALIEN_SIZE), age: 10 }];
        let mut out = [0.0; FEATURES_LEN];
        write(&w, 1, 1000, &mut out);
        assert_eq!(out[ALIENS_AT..ALIENS_AT + 5], [1.0, (516 - 132) as f32 / 800.0, 0.0, 1.0, 10.0 / 40.0]);
    }

    #[test]
    fn features_stay_within_declared_bounds_at_the_extremes() {
        let mut w = world_with_birds(&[768]);
        w.chopper = Rect::placed(0, 60, CHOPPER_SIZE);
        w.birds.push(Rect::placed(768, 508, BIRD_SIZE));
        w.fuel_tanks.push(Rect::placed(768, 508, FUEL_TANK_SIZE));
        let mut out = [0.0; FEATURES_LEN];
        write(&w, 1, 1000, &mut out);
        let (lo, hi) = (low(), high());
        for i in 0..FEATURES_LEN {
            assert!(lo[i] <= out[i] && out[i] <= hi[i], "index {i}: {}", out[i]);
        }
        w.chopper = Rect::placed(736, 476, CHOPPER_SIZE);
        w.birds = vec![Rect::placed(704, 60, BIRD_SIZE)];
        w.fuel_tanks = vec![Rect::placed(0, 508, FUEL_TANK_SIZE)];
        write(&w, 1, 1000, &mut out);
        for i in 0..FEATURES_LEN {
            assert!(lo[i] <= out[i] && out[i] <= hi[i], "index {i}: {}", out[i]);
        }
    }
}
