//! The `"features"` observation: a fixed-length `f32` vector that describes the state.
//!
//! # Layout ([`FEATURES_LEN`] = 34 values)
//! | index | name | range | meaning |
//! |---|---|---|---|
//! | 0 | `chopper_x` | [0, 1] | `(x − X_MIN) / (X_MAX − X_MIN − 64)` |
//! | 1 | `chopper_y` | [0, 1] | `(y − Y_MIN) / (Y_MAX − Y_MIN − 64)` |
//! | 2 | `fuel` | [0, 1] | `fuel_left / max_fuel` |
//! | 3 | `lives` | [0, 1] | `lives_left / lives` |
//! | 4–15 | `bird[0..4]` | see below | the 4 nearest birds |
//! | 16–21 | `fuel_tank[0..2]` | see below | the 2 nearest fuel tanks |
//! | 22–27 | `alien[0..2]` | see below | the 2 nearest alien birds |
//! | 28–33 | `missile[0..2]` | see below | the 2 nearest missiles |
//!
//! Each entity slot is three values: `present` (1 or 0), `dx = (cx − chopper_cx) / 800` and
//! `dy = (cy − chopper_cy) / 480`, both in [−1, 1], centre to centre. Slots are filled nearest first
//! (squared centre distance; ties go to the older entity); empty slots are all zero.
//!
//! With `frame_stack = k`, `k` such vectors are concatenated, oldest first: shape `(34·k,)`.

use crate::consts::{CHOPPER_SIZE, X_MAX, X_MIN, Y_MAX, Y_MIN};
use crate::geometry::Rect;
use crate::world::World;

/// Slots for birds.
pub const BIRD_SLOTS: usize = 4;
/// Slots for fuel tanks.
pub const FUEL_TANK_SLOTS: usize = 2;
/// Slots for alien birds.
pub const ALIEN_SLOTS: usize = 2;
/// Slots for missiles.
pub const MISSILE_SLOTS: usize = 2;
/// Values per entity slot: present, dx, dy.
pub const SLOT_LEN: usize = 3;
/// Length of one features vector.
pub const FEATURES_LEN: usize = 4 + SLOT_LEN * (BIRD_SLOTS + FUEL_TANK_SLOTS + ALIEN_SLOTS + MISSILE_SLOTS);

/// Lower bound of each value, as declared in the observation space.
pub fn low() -> [f32; FEATURES_LEN] {
    let mut low = [0.0; FEATURES_LEN];
    for slot in low[4..].chunks_exact_mut(SLOT_LEN) {
        slot[1] = -1.0;
        slot[2] = -1.0;
    }
    low
}

/// Upper bound of each value, as declared in the observation space.
pub fn high() -> [f32; FEATURES_LEN] {
    [1.0; FEATURES_LEN]
}

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
    let (birds, rest) = out[4..].split_at_mut(SLOT_LEN * BIRD_SLOTS);
    let (tanks, rest) = rest.split_at_mut(SLOT_LEN * FUEL_TANK_SLOTS);
    let (aliens, missiles) = rest.split_at_mut(SLOT_LEN * ALIEN_SLOTS);
    nearest::<BIRD_SLOTS, _>(&c, &world.birds, |r| *r, birds);
    nearest::<FUEL_TANK_SLOTS, _>(&c, &world.fuel_tanks, |r| *r, tanks);
    nearest::<ALIEN_SLOTS, _>(&c, &world.aliens, |a| a.body, aliens);
    nearest::<MISSILE_SLOTS, _>(&c, &world.missiles, |r| *r, missiles);
}

/// Fills the first slots of `out` (all zero) with the `SLOTS` entities nearest the chopper.
#[inline]
fn nearest<const SLOTS: usize, T>(chopper: &Rect, entities: &[T], body: impl Fn(&T) -> Rect, out: &mut [f32]) {
    if entities.is_empty() {
        return;
    }
    // Centres are kept doubled (whole numbers), hence the factor 2 in the scales.
    const DX_SCALE: f32 = 1.0 / (2 * (X_MAX - X_MIN)) as f32;
    const DY_SCALE: f32 = 1.0 / (2 * (Y_MAX - Y_MIN)) as f32;
    let (ccx, ccy) = chopper.centre2();
    // (squared distance, dx, dy), kept sorted; strict `<` keeps the older entity first on ties.
    let mut best = [(i64::MAX, 0i32, 0i32); SLOTS];
    let mut filled = 0;
    for e in entities {
        let (ex, ey) = body(e).centre2();
        let (dx, dy) = (ex - ccx, ey - ccy);
        let d = dx as i64 * dx as i64 + dy as i64 * dy as i64;
        if filled == SLOTS && d >= best[SLOTS - 1].0 {
            continue;
        }
        let mut i = filled.min(SLOTS - 1);
        while i > 0 && d < best[i - 1].0 {
            best[i] = best[i - 1];
            i -= 1;
        }
        best[i] = (d, dx, dy);
        filled = (filled + 1).min(SLOTS);
    }
    for (slot, &(_, dx, dy)) in out.chunks_exact_mut(SLOT_LEN).zip(&best[..filled]) {
        slot[0] = 1.0;
        slot[1] = dx as f32 * DX_SCALE;
        slot[2] = dy as f32 * DY_SCALE;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::consts::BIRD_SIZE;

    fn world_with_birds(xs: &[i32]) -> World {
        World {
            chopper: Rect::placed(100, 100, CHOPPER_SIZE),
            birds: xs.iter().map(|&x| Rect::placed(x, 116, BIRD_SIZE)).collect(),
            fuel_left: 500,
            lives: 1,
            ..World::default()
        }
    }

    #[test]
    fn nearest_birds_fill_slots_nearest_first() {
        let w = world_with_birds(&[700, 300, 500, 200, 600]);
        let mut out = [0.0; FEATURES_LEN];
        write(&w, 1, 1000, &mut out);
        assert_eq!(out[2], 0.5);
        assert_eq!(out[3], 1.0);
        // chopper centre x = 132, bird centres = x + 16.
        let dxs: Vec<f32> = (0..4).map(|k| out[4 + 3 * k + 1]).collect();
        let expect: Vec<f32> = [200, 300, 500, 600].iter().map(|x| (x + 16 - 132) as f32 / 800.0).collect();
        for (a, e) in dxs.iter().zip(&expect) {
            assert!((a - e).abs() < 1e-6, "{dxs:?} vs {expect:?}");
        }
        assert!((0..4).all(|k| out[4 + 3 * k] == 1.0));
        assert!(out[16..].iter().all(|&v| v == 0.0), "no tanks, aliens or missiles");
    }

    #[test]
    fn features_stay_within_declared_bounds_at_the_extremes() {
        let mut w = world_with_birds(&[768]);
        w.chopper = Rect::placed(0, 60, CHOPPER_SIZE);
        w.birds.push(Rect::placed(768, 508, BIRD_SIZE));
        let mut out = [0.0; FEATURES_LEN];
        write(&w, 1, 1000, &mut out);
        let (lo, hi) = (low(), high());
        for i in 0..FEATURES_LEN {
            assert!(lo[i] <= out[i] && out[i] <= hi[i], "index {i}: {}", out[i]);
        }
    }
}
