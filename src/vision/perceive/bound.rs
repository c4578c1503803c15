//! The convex bound carving starts from: one view's frustum around its silhouette's
//! convex hull, cut to the depths every other view spans.
//!
//! Each view's frustum has the hull, widened by [`WIDEN_NEAR_PX`] at the near depth
//! and [`WIDEN_FAR_PX`] at the far depth, as its ends; its side faces are trapezoids
//! between parallel edges. The two widths differ, so no side plane passes through the
//! camera's centre: carving by that same view then meets no face edge-on. At every
//! depth between the ends the frustum holds the hull widened by a positive margin, so
//! it holds the view's cone, and the intersection of the frustums holds the visual
//! hull. Every carving then cuts the margin away again.
//!
//! The frustums are intersected by clipping a convex polyhedron with planes, in floating
//! point with a tolerance: the bound only has to hold the hull and be a closed convex
//! polyhedron, not to be exact.

use crate::model::boolean::Map;

use glam::{DVec2, DVec3};
use robust::{Coord, orient2d};

use super::cone::between;
use super::mesh::{Maker, Mesh};
use crate::model::camera::Camera;

/// How far, in pixels, the hull is widened at the near depth.
pub const WIDEN_NEAR_PX: f64 = 2.0;
/// How far, in pixels, the hull is widened at the far depth.
pub const WIDEN_FAR_PX: f64 = 1.0;

/// One view's frustum: its faces as planes `n·x ≤ d` with what made them, and its
/// polyhedron.
pub struct Frustum {
    /// The frustum as a closed convex polyhedron.
    pub mesh: Mesh,
    /// Outward planes `(n, d)`, `n` of unit length, one per face of `mesh`.
    pub planes: Vec<(DVec3, f64)>,
}

/// The frustum of the convex hull of `points` (pixels) seen by `camera` from `near` to
/// `far`. `None` when the points have no area.
pub fn frustum(
    camera: &Camera,
    points: &[DVec2],
    near: f64,
    far: f64,
    view: u32,
) -> Option<Frustum> {
    let hull = convex_hull(points);
    if hull.len() < 3 {
        return None;
    }
    let wide_near = widen(&hull, WIDEN_NEAR_PX)?;
    let wide_far = widen(&hull, WIDEN_FAR_PX)?;
    let walls = vec![Maker::Bound { view }; hull.len()];
    let mesh = between(camera, (&wide_near, near), (&wide_far, far), walls, view);
    let planes = mesh.faces.iter().map(|f| plane_of(&mesh, f)).collect();
    Some(Frustum { mesh, planes })
}

/// `first`'s frustum cut to the near and far planes of the others: `None` when
/// nothing is left (or too thin to hold a solid).
pub fn start(first: &Frustum, others: &[Frustum]) -> Option<Mesh> {
    let mut body = first.mesh.clone();
    for f in others {
        for (plane, maker) in f.planes.iter().zip(&f.mesh.makers) {
            if matches!(maker, Maker::Near { .. } | Maker::Far { .. })
                && let Some(cut) = clip(&body, *plane, *maker)?
            {
                body = cut;
            }
        }
    }
    Some(body)
}

/// The intersection of the frustums: `None` when it is empty (or too thin to hold a
/// solid).
pub fn intersect(frustums: &[Frustum]) -> Option<Mesh> {
    let (first, rest) = frustums.split_first()?;
    let mut body = first.mesh.clone();
    for f in rest {
        for (plane, maker) in f.planes.iter().zip(&f.mesh.makers) {
            if let Some(cut) = clip(&body, *plane, *maker)? {
                body = cut;
            }
        }
    }
    Some(body)
}

/// The outward plane of a face: unit normal (Newell) and offset.
fn plane_of(mesh: &Mesh, f: &[u32]) -> (DVec3, f64) {
    let p: Vec<DVec3> = f.iter().map(|&v| mesh.positions[v as usize]).collect();
    let mut n = DVec3::ZERO;
    for k in 0..p.len() {
        n += p[k].cross(p[(k + 1) % p.len()]);
    }
    let n = n.normalize();
    let middle = p.iter().sum::<DVec3>() / p.len() as f64;
    (n, n.dot(middle))
}

/// The part of convex `body` where `n·x ≤ d`, its new face made by `maker`: `None`
/// when nothing with volume is left, `Some(None)` when the plane cuts nothing off.
fn clip(body: &Mesh, (n, d): (DVec3, f64), maker: Maker) -> Option<Option<Mesh>> {
    let (lo, hi) = body.bounds();
    let tol = 1e-12 * (hi - lo).length().max(d.abs()).max(1.0);
    let side: Vec<f64> = body.positions.iter().map(|p| n.dot(*p) - d).collect();
    if side.iter().all(|&s| s <= tol) {
        return Some(None);
    }
    if side.iter().all(|&s| s >= -tol) {
        return None;
    }
    let mut out = Mesh::default();
    let mut kept: Map<u32, u32> = Map::default();
    let mut made: Map<(u32, u32), u32> = Map::default();
    let mut on_plane: Vec<u32> = Vec::new();
    let mut keep = |out: &mut Mesh, v: u32| -> u32 {
        *kept.entry(v).or_insert_with(|| {
            out.positions.push(body.positions[v as usize]);
            (out.positions.len() - 1) as u32
        })
    };
    for (f, maker) in body.faces.iter().zip(&body.makers) {
        let mut ring = Vec::new();
        for k in 0..f.len() {
            let (a, b) = (f[k], f[(k + 1) % f.len()]);
            let (sa, sb) = (side[a as usize], side[b as usize]);
            if sa <= tol {
                let v = keep(&mut out, a);
                if sa >= -tol && !on_plane.contains(&v) {
                    on_plane.push(v);
                }
                ring.push(v);
            }
            if (sa < -tol && sb > tol) || (sa > tol && sb < -tol) {
                let key = (a.min(b), a.max(b));
                let v = *made.entry(key).or_insert_with(|| {
                    let (pa, pb) = (body.positions[a as usize], body.positions[b as usize]);
                    let t = side[a as usize] / (side[a as usize] - side[b as usize]);
                    out.positions.push(pa + (pb - pa) * t);
                    (out.positions.len() - 1) as u32
                });
                if !on_plane.contains(&v) {
                    on_plane.push(v);
                }
                ring.push(v);
            }
        }
        let all_on = ring.iter().all(|v| on_plane.contains(v));
        if ring.len() >= 3 && !all_on {
            out.faces.push(ring);
            out.makers.push(*maker);
        }
    }
    if on_plane.len() < 3 || out.faces.len() < 3 {
        return None;
    }
    // The new face: the points on the plane, counter-clockwise about n.
    let centre = on_plane
        .iter()
        .map(|&v| out.positions[v as usize])
        .sum::<DVec3>()
        / on_plane.len() as f64;
    let u = n.any_orthonormal_vector();
    let w = n.cross(u);
    on_plane.sort_by(|&a, &b| {
        let (pa, pb) = (
            out.positions[a as usize] - centre,
            out.positions[b as usize] - centre,
        );
        let ta = pa.dot(w).atan2(pa.dot(u));
        let tb = pb.dot(w).atan2(pb.dot(u));
        ta.total_cmp(&tb)
    });
    out.faces.push(on_plane);
    out.makers.push(maker);
    (out.volume() > 0.0).then_some(Some(out))
}

/// The convex hull of `points`, counter-clockwise in (u, v) (turning from +u toward +v),
/// with no three corners in a line (Andrew's monotone chain, exact orientations).
pub fn convex_hull(points: &[DVec2]) -> Vec<DVec2> {
    let mut p: Vec<DVec2> = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let turn = |a: DVec2, b: DVec2, c: DVec2| {
        orient2d(
            Coord { x: a.x, y: a.y },
            Coord { x: b.x, y: b.y },
            Coord { x: c.x, y: c.y },
        )
    };
    let mut hull: Vec<DVec2> = Vec::with_capacity(p.len() * 2);
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && turn(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// A convex polygon (counter-clockwise in (u, v)) with each edge moved out by `by`;
/// `None` when two consecutive edges are parallel.
fn widen(hull: &[DVec2], by: f64) -> Option<Vec<DVec2>> {
    let n = hull.len();
    // Outward normal of edge k (from hull[k] to hull[k+1]): the polygon is on the left.
    let normal = |k: usize| {
        let d = (hull[(k + 1) % n] - hull[k]).normalize();
        DVec2::new(d.y, -d.x)
    };
    (0..n)
        .map(|k| {
            let (a, b) = (normal((k + n - 1) % n), normal(k));
            // The corner moves to where the two moved edges meet.
            let m = a + b;
            let scale = by / (1.0 + a.dot(b)).max(1e-12);
            let corner = hull[k] + m * scale;
            corner.is_finite().then_some(corner)
        })
        .collect()
}
