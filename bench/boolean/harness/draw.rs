//! Integer and choice draws on top of the benches' deterministic generator
//! (`bench/rng.rs`), and the seed mixing that makes neighbouring seeds independent.

use super::rng::Rng;

/// SplitMix64's finaliser: spreads a small seed over all 64 bits, so that seeds 1, 2,
/// 3 … start the linear congruential generator far apart.
pub fn mix(seed: u64) -> u64 {
    let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A generator for `(stream, seed)`: each family draws from its own stream.
pub fn rng_for(stream: u64, seed: u64) -> Rng {
    Rng(mix(mix(stream) ^ seed))
}

/// Draws beyond the uniform `[0, 1)` of [`Rng::next`].
pub trait Draw {
    /// Uniform in `0..n` (`n > 0`).
    fn below(&mut self, n: usize) -> usize;
    /// Uniform in `lo..=hi`.
    fn int(&mut self, lo: i64, hi: i64) -> i64;
    /// True with probability `p`.
    fn chance(&mut self, p: f64) -> bool;
    /// One of `xs` (non-empty), uniformly.
    fn pick<T: Copy>(&mut self, xs: &[T]) -> T;
}

impl Draw for Rng {
    fn below(&mut self, n: usize) -> usize {
        ((self.next() * n as f64) as usize).min(n.saturating_sub(1))
    }

    fn int(&mut self, lo: i64, hi: i64) -> i64 {
        lo + self.below((hi - lo + 1) as usize) as i64
    }

    fn chance(&mut self, p: f64) -> bool {
        self.next() < p
    }

    fn pick<T: Copy>(&mut self, xs: &[T]) -> T {
        xs[self.below(xs.len())]
    }
}
