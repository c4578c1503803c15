//! What the vision tests share: a small deterministic random stream.

use glam::{DMat3, DQuat, DVec3};

/// SplitMix64 with Box–Muller normals: a small deterministic random stream, the same for
/// a given seed on every machine.
pub(crate) struct Rng(pub u64);

impl Rng {
    /// The next 64 random bits.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    pub(crate) fn range(&mut self, lo: f64, hi: f64) -> f64 {
        let unit = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * unit
    }

    /// Each coordinate uniform in `[lo, hi)`, drawn x, y, z in turn.
    pub(crate) fn vector(&mut self, lo: f64, hi: f64) -> DVec3 {
        DVec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }

    /// Standard normal.
    pub(crate) fn normal(&mut self) -> f64 {
        let u1 = self.range(f64::MIN_POSITIVE, 1.0);
        let u2 = self.range(0.0, 1.0);
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// Uniform on the unit sphere.
    pub(crate) fn unit_vector(&mut self) -> DVec3 {
        loop {
            let v = self.vector(-1.0, 1.0);
            let n = v.length();
            if n > 0.1 && n <= 1.0 {
                return v / n;
            }
        }
    }

    /// A rotation about a uniform axis by a uniform angle in `[-π, π)`.
    pub(crate) fn axis_angle_rotation(&mut self) -> DMat3 {
        let axis = self.unit_vector();
        DMat3::from_axis_angle(
            axis,
            self.range(-std::f64::consts::PI, std::f64::consts::PI),
        )
    }

    /// A rotation uniform over SO(3) (a normalised Gaussian quaternion).
    pub(crate) fn uniform_rotation(&mut self) -> DMat3 {
        loop {
            let q = DQuat::from_xyzw(self.normal(), self.normal(), self.normal(), self.normal());
            if q.length() > 1e-3 {
                return DMat3::from_quat(q.normalize());
            }
        }
    }
}
