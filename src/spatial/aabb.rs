//! Axis-aligned boxes in `f64`, with the conversions the hierarchy needs.

use glam::DVec3;

use crate::model::Pose;

/// A closed axis-aligned box `min..=max`; empty when any `min` exceeds its `max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: DVec3,
    /// Largest corner.
    pub max: DVec3,
}

impl Aabb {
    /// The empty box: the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    /// The box `min..=max`.
    #[inline]
    pub fn new(min: DVec3, max: DVec3) -> Aabb {
        Aabb { min, max }
    }

    /// The smallest box holding every point of `pts` (empty for none).
    pub fn of_points(pts: impl IntoIterator<Item = DVec3>) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in pts {
            b.grow(p);
        }
        b
    }

    /// Whether the box holds no point.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// The centre.
    #[inline]
    pub fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    /// The smallest box holding both.
    #[inline]
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Grows the box to hold `p`.
    #[inline]
    pub fn grow(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// Half the surface area (0 for an empty box).
    #[inline]
    pub fn half_area(&self) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.max - self.min;
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    /// Whether `o` lies inside this box.
    pub fn contains(&self, o: &Aabb) -> bool {
        o.is_empty() || (self.min.cmple(o.min).all() && self.max.cmpge(o.max).all())
    }

    /// Whether `p` lies inside this (closed) box.
    #[inline]
    pub fn contains_point(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Whether the two closed boxes share a point.
    #[inline]
    pub fn overlaps(&self, o: &Aabb) -> bool {
        self.min.cmple(o.max).all() && self.max.cmpge(o.min).all()
    }

    /// Squared distance from `p` to the box (0 inside; infinite for an empty box).
    #[inline]
    pub fn distance_squared(&self, p: DVec3) -> f64 {
        if self.is_empty() {
            return f64::INFINITY;
        }
        let d = (self.min - p).max(p - self.max).max(DVec3::ZERO);
        d.length_squared()
    }

    /// Where the ray `o + t·d` (t ≥ 0) first enters the box, or `None` (always for the
    /// empty box).
    pub fn ray_entry(&self, o: DVec3, d: DVec3) -> Option<f64> {
        if self.is_empty() {
            return None;
        }
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for k in 0..3 {
            if d[k] == 0.0 {
                if o[k] < self.min[k] || o[k] > self.max[k] {
                    return None;
                }
                continue;
            }
            let (mut a, mut b) = ((self.min[k] - o[k]) / d[k], (self.max[k] - o[k]) / d[k]);
            if a > b {
                std::mem::swap(&mut a, &mut b);
            }
            t0 = t0.max(a);
            t1 = t1.min(b);
        }
        (t0 <= t1).then_some(t0)
    }

    /// The box in `f32`, each bound rounded outward so that it still holds the original.
    pub fn to_f32_outward(&self) -> ([f32; 3], [f32; 3]) {
        if self.is_empty() {
            return ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        }
        let down = |x: f64| {
            let y = x as f32;
            if f64::from(y) > x { y.next_down() } else { y }
        };
        let up = |x: f64| {
            let y = x as f32;
            if f64::from(y) < x { y.next_up() } else { y }
        };
        (self.min.to_array().map(down), self.max.to_array().map(up))
    }

    /// The box holding this one moved by `pose` (the bounds of its eight corners),
    /// widened by a relative hair for the rounding of the move.
    pub fn transformed(&self, pose: &Pose) -> Aabb {
        if self.is_empty() {
            return *self;
        }
        let c = pose.transform_point(self.center());
        let h = (self.max - self.min) * 0.5;
        let m = pose.rotation_matrix();
        // The half-extent of a rotated box: |R| applied to the half-extent.
        let e = DVec3::new(
            m.row(0).abs().dot(h),
            m.row(1).abs().dot(h),
            m.row(2).abs().dot(h),
        );
        let slack = (c.abs() + e) * 1e-12;
        Aabb::new(c - e - slack, c + e + slack)
    }

    /// The box widened by `by` on every side.
    #[inline]
    pub fn inflated(&self, by: f64) -> Aabb {
        Aabb::new(self.min - by, self.max + by)
    }
}
