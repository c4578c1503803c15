//! Reproducible sample worlds and camera rigs for benchmarks, tests and peer comparisons.
//!
//! [`blocks`] lays out a "city" of boxes and prisms on the ground plane z = 0 with a fixed
//! density (one body per 9 m²), so worlds of 30 and 100,000 bodies look alike from
//! cameras scaled to them; [`ring_cameras`] places cameras around and above such a world,
//! each looking at its centre. Both are deterministic functions of their arguments (a
//! SplitMix64 stream seeded by `seed`), so the same scene can be rebuilt in another
//! process, or written out for another renderer.

use glam::{DQuat, DVec2, DVec3};

use crate::model::{Camera, Color, Intrinsics, Light, Pose, World, WorldError, solids};

/// An L-shaped hexagon, counter-clockwise in the xy plane: the square [0, 2]² without
/// the quarter [1, 2]². Area 3; concave at (1, 1). Swept with
/// [`solids::prism_solid`] it makes the concave prism tests and examples use.
pub const L_SHAPE: [DVec2; 6] = [
    DVec2::new(0.0, 0.0),
    DVec2::new(2.0, 0.0),
    DVec2::new(2.0, 1.0),
    DVec2::new(1.0, 1.0),
    DVec2::new(1.0, 2.0),
    DVec2::new(0.0, 2.0),
];

/// A small, fast, well-mixed deterministic random stream (SplitMix64).
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// The stream for `seed`.
    pub fn new(seed: u64) -> SplitMix64 {
        SplitMix64(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A uniform number in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        let unit = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * unit
    }
}

/// The side of the square a [`blocks`] world of `count` bodies covers, meters.
pub fn blocks_extent(count: usize) -> f64 {
    (count.max(1) as f64 * 9.0).sqrt()
}

/// A world of `count` bodies standing on z = 0 in a square of side
/// [`blocks_extent`]`(count)` centred on the origin: on a jittered 3 m grid, boxes (two
/// in three) 0.6–2 m wide and 0.5–4 m tall, and triangular or hexagonal prisms, each
/// turned about z at random and given a colour. Two suns light it. Refused only if the
/// kernel refuses a solid, which it does not for these sizes.
pub fn blocks(count: usize, seed: u64) -> Result<World, WorldError> {
    let mut rng = SplitMix64::new(seed);
    let mut world = World::new();
    let root = world.root();
    let per_row = (count as f64).sqrt().ceil().max(1.0) as usize;
    let half = blocks_extent(count) / 2.0;
    let pitch = 2.0 * half / per_row as f64;
    for i in 0..count {
        let (row, col) = (i / per_row, i % per_row);
        let centre = DVec2::new(
            -half + pitch * (col as f64 + 0.5) + rng.range(-0.3, 0.3),
            -half + pitch * (row as f64 + 0.5) + rng.range(-0.3, 0.3),
        );
        let height = rng.range(0.5, 4.0);
        let turn = DQuat::from_rotation_z(rng.range(0.0, std::f64::consts::TAU));
        let pose = Pose {
            position: DVec3::new(centre.x, centre.y, height / 2.0),
            rotation: turn,
        };
        let c = rng.next_u64();
        let color = Some(Color([
            96 + (c & 0x7f) as u8,
            96 + ((c >> 8) & 0x7f) as u8,
            96 + ((c >> 16) & 0x7f) as u8,
        ]));
        let kind = rng.next_u64() % 3;
        if kind < 2 {
            let (dx, dy) = (rng.range(0.6, 2.0), rng.range(0.6, 2.0));
            world.insert_colored_with(None, root, pose, color, |s| {
                solids::mkcube(s, dx, dy, height)
            })?;
        } else {
            let sides = if rng.next_u64().is_multiple_of(2) {
                3
            } else {
                6
            };
            let r = rng.range(0.4, 1.0);
            let polygon: Vec<DVec2> = (0..sides)
                .map(|k| {
                    let a = std::f64::consts::TAU * k as f64 / sides as f64;
                    DVec2::new(r * a.cos(), r * a.sin())
                })
                .collect();
            world.insert_colored_with(None, root, pose, color, |s| {
                solids::prism_solid(s, &polygon, height)
            })?;
        }
    }
    let sun = Light::sun(DVec3::new(-0.4, -0.3, -1.0), 0.8).expect("a valid sun");
    world.set_light("sun", sun)?;
    let fill = Light::sun(DVec3::new(0.5, 0.2, -0.6), 0.3).expect("a valid sun");
    world.set_light("fill", fill)?;
    Ok(world)
}

/// `count` cameras of `width × height` pixels with a 60° vertical field of view, evenly
/// spaced on a ring around a [`blocks`] world of `bodies` bodies and above it, each
/// looking at a point near the world's centre, so the whole world is in view.
pub fn ring_cameras(bodies: usize, count: usize, width: u32, height: u32) -> Vec<Camera> {
    let extent = blocks_extent(bodies).max(6.0);
    let k = Intrinsics::from_fov_y(width, height, 60f64.to_radians()).expect("a valid size");
    (0..count)
        .map(|i| {
            let a = std::f64::consts::TAU * (i as f64 + 0.25) / count.max(1) as f64;
            let radius = extent * (0.9 + 0.2 * (i % 3) as f64);
            let eye = DVec3::new(
                radius * a.cos(),
                radius * a.sin(),
                extent * (0.45 + 0.1 * (i % 4) as f64),
            );
            let target = DVec3::new(0.0, 0.0, 1.0);
            Camera::look_at(eye, target, DVec3::Z, k).expect("a valid camera")
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_are_reproducible() {
        let a = blocks(40, 7).unwrap();
        let b = blocks(40, 7).unwrap();
        assert_eq!(a.body_count(), 40);
        let pa: Vec<_> = a.bodies().map(|(_, n)| n.pose).collect();
        let pb: Vec<_> = b.bodies().map(|(_, n)| n.pose).collect();
        assert_eq!(pa, pb);
        assert_eq!(ring_cameras(40, 20, 64, 48).len(), 20);
    }
}
