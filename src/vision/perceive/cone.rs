//! A view's cone as a closed polyhedron: the rays from the camera's centre through a
//! ring of pixels, between two depths.

use glam::{DVec2, DVec3};

use super::mesh::{Maker, Mesh};
use crate::model::camera::Camera;

/// The point at `depth` (metres along the view direction) on the ray through pixel `uv`.
pub fn at_depth(camera: &Camera, uv: DVec2, depth: f64) -> DVec3 {
    let k = &camera.intrinsics;
    let c = DVec3::new((uv.x - k.cx) / k.fx, -(uv.y - k.cy) / k.fy, -1.0) * depth;
    camera.camera_to_world(c)
}

/// The cone through `ring` (pixels, either orientation, at least three points, simple)
/// from `near` to `far` (0 < near < far): a wall per ring edge (made by `Maker::Wall`
/// with `view`, `ring_index` and the edge's index) and the two ends.
///
/// Postconditions: closed, manifold, outward oriented (positive volume); face `k` is
/// the wall of edge `k`, then the near end, then the far end.
pub fn cone(
    camera: &Camera,
    ring: &[DVec2],
    near: f64,
    far: f64,
    view: u32,
    ring_index: u32,
) -> Mesh {
    let walls = (0..ring.len() as u32)
        .map(|edge| Maker::Wall {
            view,
            ring: ring_index,
            edge,
        })
        .collect();
    between(camera, (ring, near), (ring, far), walls, view)
}

/// The solid between ring `near.0` at depth `near.1` and ring `far.0` (as many points,
/// corresponding edges parallel) at depth `far.1`, seen by `camera`: a side face per
/// edge (made by `walls[k]`), then the near end and the far end.
///
/// Postconditions: closed, manifold, outward oriented (positive volume).
pub fn between(
    camera: &Camera,
    near: (&[DVec2], f64),
    far: (&[DVec2], f64),
    walls: Vec<Maker>,
    view: u32,
) -> Mesh {
    let n = near.0.len() as u32;
    let mut positions: Vec<DVec3> = near
        .0
        .iter()
        .map(|&q| at_depth(camera, q, near.1))
        .collect();
    positions.extend(far.0.iter().map(|&q| at_depth(camera, q, far.1)));
    let mut faces: Vec<Vec<u32>> = (0..n)
        .map(|k| {
            let k1 = (k + 1) % n;
            vec![k, n + k, n + k1, k1]
        })
        .collect();
    faces.push((0..n).collect());
    faces.push((n..2 * n).rev().collect());
    let mut makers = walls;
    makers.push(Maker::Near { view });
    makers.push(Maker::Far { view });
    let mut mesh = Mesh {
        positions,
        faces,
        makers,
    };
    if mesh.volume() < 0.0 {
        for f in &mut mesh.faces {
            f.reverse();
        }
    }
    mesh
}
