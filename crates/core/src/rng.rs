//! The environment's own random generator: xoshiro256++ seeded through SplitMix64.
//!
//! Written out here (rather than taken from `rand_xoshiro`) because snapshots must read and write the
//! generator's raw state, which the crate does not expose without serde. A test checks that it
//! produces exactly `rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64`'s stream.
//!
//! Draws are defined on `next_u64` alone, so they are value-stable on every machine and version:
//! - [`Rng::unit`]: the top 53 bits as `f64` in `[0, 1)`;
//! - [`Rng::below`]: `floor(next_u64 · n / 2⁶⁴)` (multiply-shift; one draw, no rejection).

/// xoshiro256++ state.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Rng {
    s: [u64; 4],
}

impl Rng {
    /// Seeds from one `u64`, expanding it with SplitMix64 (as `rand_xoshiro`'s `seed_from_u64`).
    pub fn seed_from_u64(seed: u64) -> Rng {
        let mut z = seed;
        let mut s = [0u64; 4];
        for word in &mut s {
            z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut x = z;
            x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            *word = x ^ (x >> 31);
        }
        Rng { s }
    }

    /// The raw state, for snapshots.
    pub fn state(&self) -> [u64; 4] {
        self.s
    }

    /// Rebuilds a generator from a raw state. Returns `None` for the all-zero state, which xoshiro cannot leave.
    pub fn from_state(s: [u64; 4]) -> Option<Rng> {
        (s != [0; 4]).then_some(Rng { s })
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        let s = &mut self.s;
        let result = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        result
    }

    /// A uniform `f64` in `[0, 1)`.
    #[inline]
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// `true` with probability `p` (one draw, always consumed): exactly `unit() < p`.
    #[inline]
    pub fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }

    /// `true` with the probability `threshold` stands for (see [`Rng::threshold`]): exactly `chance(p)`, in
    /// integers (one draw, always consumed).
    #[inline]
    pub fn chance_below(&mut self, threshold: u64) -> bool {
        (self.next_u64() >> 11) < threshold
    }

    /// The integer form of a probability `p` in [0, 1]: `unit() < p` ⟺ `(next_u64 >> 11) < threshold(p)`,
    /// because `unit()` is `(next_u64 >> 11) · 2⁻⁵³` and scaling by a power of two is exact.
    pub fn threshold(p: f64) -> u64 {
        (p * (1u64 << 53) as f64).ceil() as u64
    }

    /// A uniform integer in `[0, n)`; `n` must be positive.
    #[inline]
    pub fn below(&mut self, n: u32) -> u32 {
        ((self.next_u64() as u128 * n as u128) >> 64) as u32
    }

    /// A uniform integer in `[lo, hi)`; requires `lo < hi`.
    #[inline]
    pub fn range(&mut self, lo: i32, hi: i32) -> i32 {
        lo + self.below((hi - lo) as u32) as i32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::{Rng as _, SeedableRng};

    #[test]
    fn matches_rand_xoshiro_stream() {
        for seed in [0u64, 1, 42, u64::MAX, 0xdead_beef] {
            let mut ours = Rng::seed_from_u64(seed);
            let mut theirs = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
            for _ in 0..1000 {
                assert_eq!(ours.next_u64(), theirs.next_u64());
            }
        }
    }

    #[test]
    fn draws_are_value_stable() {
        // Pinned values: a change here changes every trajectory, which is a new env version.
        let mut r = Rng::seed_from_u64(0);
        let firsts: Vec<i32> = (0..6).map(|_| r.range(40, 80)).collect();
        assert_eq!(firsts, [52, 55, 54, 40, 59, 40]);
    }

    #[test]
    fn range_covers_exactly_its_bounds() {
        let mut r = Rng::seed_from_u64(7);
        let mut seen = [false; 30];
        for _ in 0..10_000 {
            let v = r.range(90, 120);
            assert!((90..120).contains(&v));
            seen[(v - 90) as usize] = true;
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn integer_chance_equals_float_chance() {
        for p in [0.0, 1e-12, 0.01, 0.25, 0.5, 0.999_999, 1.0, f64::from_bits(0x3f84_7ae1_47ae_147b)] {
            let (mut a, mut b) = (Rng::seed_from_u64(5), Rng::seed_from_u64(5));
            let t = Rng::threshold(p);
            for _ in 0..20_000 {
                assert_eq!(a.chance(p), b.chance_below(t), "p = {p}");
            }
        }
        // At the boundary: a draw whose unit() equals p exactly is not below it.
        let p = 0.5;
        assert_eq!(Rng::threshold(p), 1 << 52);
    }

    #[test]
    fn state_round_trips_and_zero_state_is_refused() {
        let mut a = Rng::seed_from_u64(3);
        a.next_u64();
        let mut b = Rng::from_state(a.state()).unwrap();
        assert_eq!(a.next_u64(), b.next_u64());
        assert!(Rng::from_state([0; 4]).is_none());
    }
}
