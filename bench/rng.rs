//! The small deterministic random generator the criterion benches draw their data from
//! (benches cannot use the crate's test-only helpers): PCG-style steps, so that a seed
//! always gives the same data.

use glam::DVec3;

/// A linear congruential state; `next` is uniform in [0, 1).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }

    /// Standard normal (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let (u, v) = (self.next().max(1e-300), self.next());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }

    /// A direction uniform on the unit sphere.
    pub fn unit_vector(&mut self) -> DVec3 {
        DVec3::new(self.normal(), self.normal(), self.normal()).normalize()
    }
}
