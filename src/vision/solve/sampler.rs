//! The random sampler of the RANSAC loops ([`ransac_pnp`](super::ransac::ransac_pnp) and
//! [`solve_pnp_focal`](super::focal::solve_pnp_focal)): small, seeded and reproducible, so
//! that one seed always draws the same samples and a solve can be repeated exactly.

/// xorshift64* (Vigna), its state seeded through SplitMix64 so that every seed, 0
/// included, gives a non-zero state.
pub(super) struct Sampler(u64);

impl Sampler {
    pub(super) fn new(seed: u64) -> Sampler {
        let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        Sampler(if z == 0 { 0x2545_F491_4F6C_DD1D } else { z })
    }

    pub(super) fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in `0..n` (Lemire's multiply-shift; the bias is below 2⁻⁴⁰ for any slice
    /// that fits in memory). `n ≥ 1`.
    pub(super) fn below(&mut self, n: usize) -> usize {
        ((u128::from(self.next_u64()) * n as u128) >> 64) as usize
    }

    /// Three distinct indices in `0..n`, uniformly over all such triples, without
    /// rejection. `n ≥ 3`.
    pub(super) fn sample3(&mut self, n: usize) -> [usize; 3] {
        let a = self.below(n);
        let mut b = self.below(n - 1);
        if b >= a {
            b += 1;
        }
        let (lo, hi) = (a.min(b), a.max(b));
        let mut c = self.below(n - 2);
        if c >= lo {
            c += 1;
        }
        if c >= hi {
            c += 1;
        }
        [a, b, c]
    }

    /// Fills `out` with distinct indices in `0..n`, uniformly over such sets, by rejection
    /// of repeats (meant for small samples: `out.len()` a few, and `≤ n`).
    pub(super) fn distinct(&mut self, n: usize, out: &mut [usize]) {
        debug_assert!(out.len() <= n);
        for k in 0..out.len() {
            loop {
                let i = self.below(n);
                if !out[..k].contains(&i) {
                    out[k] = i;
                    break;
                }
            }
        }
    }
}

/// The number of `k`-element subsets of `n` things, when it is at most `cap`; `None` when
/// there are more.
pub(super) fn subsets_up_to(n: usize, k: usize, cap: usize) -> Option<usize> {
    if k > n {
        return Some(0);
    }
    let k = k.min(n - k);
    // C(n, i) = C(n, i − 1)·(n − i + 1)/i, exact at every step; never above C(n, k).
    let mut count: u128 = 1;
    for i in 1..=k {
        count = count * (n - i + 1) as u128 / i as u128;
        if count > cap as u128 {
            return None;
        }
    }
    Some(count as usize)
}

/// Steps `subset` (ascending distinct indices below `n`) to the next subset of its size in
/// lexicographic order; `false`, leaving it as it was, after the last. Starting from
/// `0, 1, …, k − 1`, every `k`-subset is visited once.
pub(super) fn next_subset(n: usize, subset: &mut [usize]) -> bool {
    let k = subset.len();
    // The rightmost entry that can still grow.
    let Some(i) = (0..k).rev().find(|&i| subset[i] < n - k + i) else {
        return false;
    };
    subset[i] += 1;
    for j in i + 1..k {
        subset[j] = subset[j - 1] + 1;
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_are_three_distinct_uniform_indices() {
        let mut rng = Sampler::new(0);
        let mut counts = [0usize; 5];
        for _ in 0..30_000 {
            let [a, b, c] = rng.sample3(5);
            assert!(a != b && b != c && a != c && a < 5 && b < 5 && c < 5);
            for i in [a, b, c] {
                counts[i] += 1;
            }
        }
        // Each index is in 3/5 of the samples: 18,000 expected, σ ≈ 85.
        assert!(
            counts.iter().all(|&k| k.abs_diff(18_000) < 600),
            "{counts:?}"
        );
        assert_eq!(Sampler::new(3).next_u64(), Sampler::new(3).next_u64());
        assert_ne!(Sampler::new(3).next_u64(), Sampler::new(4).next_u64());
    }

    #[test]
    fn distinct_samples_are_distinct_and_uniform() {
        let mut s = Sampler::new(9);
        let mut out = [0usize; 6];
        let mut counts = [0usize; 7];
        for _ in 0..7_000 {
            s.distinct(7, &mut out);
            let mut sorted = out;
            sorted.sort_unstable();
            assert!(sorted.windows(2).all(|w| w[0] < w[1]), "{out:?}");
            for &i in &out {
                counts[i] += 1;
            }
        }
        // Each index is in 6/7 of the samples: 6,000 expected, σ ≈ 29.
        assert!(
            counts.iter().all(|&k| k.abs_diff(6_000) < 200),
            "{counts:?}"
        );
    }

    #[test]
    fn subsets_are_counted_and_each_visited_once() {
        assert_eq!(subsets_up_to(6, 6, 100), Some(1));
        assert_eq!(subsets_up_to(10, 6, 1000), Some(210));
        assert_eq!(subsets_up_to(10, 6, 209), None);
        assert_eq!(subsets_up_to(3, 4, 10), Some(0));
        assert_eq!(
            subsets_up_to(1000, 6, usize::MAX),
            Some(1_368_173_298_991_500)
        );
        let mut subset = [0, 1, 2];
        let mut seen = vec![subset];
        while next_subset(7, &mut subset) {
            assert!(subset.windows(2).all(|w| w[0] < w[1]) && subset[2] < 7);
            seen.push(subset);
        }
        assert_eq!(seen.len(), 35);
        assert_eq!(subset, [4, 5, 6]);
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), 35);
    }
}
