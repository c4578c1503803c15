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
    let n = ring.len() as u32;
    let mut positions: Vec<DVec3> = ring.iter().map(|&q| at_depth(camera, q, near)).collect();
    positions.extend(ring.iter().map(|&q| at_depth(camera, q, far)));
    let mut faces: Vec<Vec<u32>> = (0..n)
        .map(|k| {
            let k1 = (k + 1) % n;
            vec![k, n + k, n + k1, k1]
        })
        .collect();
    faces.push((0..n).collect());
    faces.push((n..2 * n).rev().collect());
    let mut makers: Vec<Maker> = (0..n)
        .map(|edge| Maker::Wall {
            view,
            ring: ring_index,
            edge,
        })
        .collect();
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
