//! Axis-aligned boxes: placement with clamping to the flight band, and collision by centres.

use crate::consts::{X_MAX, X_MIN, Y_MAX, Y_MIN};

/// An axis-aligned box: top-left corner `(x, y)` and size `(w, h)`, in whole pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Rect {
    /// Left edge (pixels).
    pub x: i32,
    /// Top edge (pixels).
    pub y: i32,
    /// Width (pixels).
    pub w: i32,
    /// Height (pixels).
    pub h: i32,
}

impl Rect {
    /// Places a box of size `(w, h)` at `(x, y)`, clamped into the flight band.
    pub fn placed(x: i32, y: i32, (w, h): (i32, i32)) -> Rect {
        let mut r = Rect { x, y, w, h };
        r.clamp_to_band();
        r
    }

    /// Moves the box by `(dx, dy)` and clamps it into the flight band.
    pub fn shift(&mut self, dx: i32, dy: i32) {
        self.x += dx;
        self.y += dy;
        self.clamp_to_band();
    }

    /// Moves a box that lies in the band `d ≥ 0` pixels left, clamped: the same as `shift(-d, 0)`, since only
    /// the lower bound of `x` can bind (the hot path of birds, aliens and missiles).
    #[inline]
    pub fn shift_left(&mut self, d: i32) {
        debug_assert!(d >= 0 && self.in_band());
        self.x = (self.x - d).max(X_MIN);
    }

    /// Moves a box that lies in the band `d ≥ 0` pixels up, clamped: the same as `shift(0, -d)`.
    #[inline]
    pub fn shift_up(&mut self, d: i32) {
        debug_assert!(d >= 0 && self.in_band());
        self.y = (self.y - d).max(Y_MIN);
    }

    /// Clamps `x` to `[X_MIN, X_MAX − w]` and `y` to `[Y_MIN, Y_MAX − h]`.
    pub fn clamp_to_band(&mut self) {
        self.x = self.x.clamp(X_MIN, X_MAX - self.w);
        self.y = self.y.clamp(Y_MIN, Y_MAX - self.h);
    }

    /// Twice the centre, `(2x + w, 2y + h)`: whole numbers, so collision needs no division.
    pub fn centre2(&self) -> (i32, i32) {
        (2 * self.x + self.w, 2 * self.y + self.h)
    }

    /// Whether two boxes collide: `2·|cx₁ − cx₂| ≤ w₁ + w₂` and `2·|cy₁ − cy₂| ≤ h₁ + h₂`. Touching counts.
    pub fn collides(&self, other: &Rect) -> bool {
        let (ax, ay) = self.centre2();
        let (bx, by) = other.centre2();
        (ax - bx).abs() <= self.w + other.w && (ay - by).abs() <= self.h + other.h
    }

    /// Whether the box lies inside the flight band. Written so that no position overflows, however far out
    /// (a decoded snapshot may hold any `i32`).
    pub fn in_band(&self) -> bool {
        self.x >= X_MIN
            && i64::from(self.x) + i64::from(self.w) <= i64::from(X_MAX)
            && self.y >= Y_MIN
            && i64::from(self.y) + i64::from(self.h) <= i64::from(Y_MAX)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::consts::{BIRD_SIZE, CHOPPER_SIZE};

    #[test]
    fn placing_clamps_into_the_flight_band() {
        let r = Rect::placed(800, 600, BIRD_SIZE);
        assert_eq!((r.x, r.y), (768, 508));
        let r = Rect::placed(-20, 0, CHOPPER_SIZE);
        assert_eq!((r.x, r.y), (0, 60));
    }

    #[test]
    fn moving_clamps_into_the_flight_band() {
        let mut r = Rect::placed(2, 62, CHOPPER_SIZE);
        r.shift(-5, -5);
        assert_eq!((r.x, r.y), (0, 60));
        let mut r = Rect::placed(735, 475, CHOPPER_SIZE);
        r.shift(5, 5);
        assert_eq!((r.x, r.y), (736, 476));
    }

    #[test]
    fn one_way_shifts_equal_clamped_shifts() {
        for (x, y) in [(0, 60), (3, 64), (400, 300), (768, 508)] {
            for d in [0, 5, 10] {
                let (mut a, mut b) = (Rect::placed(x, y, BIRD_SIZE), Rect::placed(x, y, BIRD_SIZE));
                a.shift_left(d);
                b.shift(-d, 0);
                assert_eq!(a, b);
                a.shift_up(d);
                b.shift(0, -d);
                assert_eq!(a, b);
            }
        }
    }

    #[test]
    fn touching_boxes_collide_and_a_pixel_apart_do_not() {
        // Chopper 64 wide at x=100 spans [100,164); a bird at x=164 touches its right edge.
        let chopper = Rect::placed(100, 100, CHOPPER_SIZE);
        let touching = Rect::placed(164, 100, BIRD_SIZE);
        let apart = Rect::placed(165, 100, BIRD_SIZE);
        assert!(chopper.collides(&touching));
        assert!(touching.collides(&chopper));
        assert!(!chopper.collides(&apart));
        let below = Rect::placed(100, 164, BIRD_SIZE);
        let further = Rect::placed(100, 165, BIRD_SIZE);
        assert!(chopper.collides(&below));
        assert!(!chopper.collides(&further));
    }

    #[test]
    fn boxes_far_outside_are_outside_without_overflow() {
        for (x, y) in [(i32::MAX, 100), (i32::MAX - 10, 100), (100, i32::MAX), (i32::MIN, 100), (100, i32::MIN)] {
            assert!(!Rect { x, y, w: 64, h: 64 }.in_band(), "({x}, {y})");
        }
    }

    #[test]
    fn collision_uses_centres_not_top_left_corners() {
        // Top-left corners 40 px apart horizontally: the tutorial's corner test would say no hit
        // for a 32 px threshold, centres say hit (|cx diff| = 24 ≤ (64+32)/2 = 48).
        let chopper = Rect::placed(100, 100, CHOPPER_SIZE);
        let bird = Rect::placed(140, 116, BIRD_SIZE);
        assert!(chopper.collides(&bird));
    }
}
