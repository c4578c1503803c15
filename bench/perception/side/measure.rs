//! Measures of a carved hull against the truth: validity, winding numbers, a fast
//! inside test for many points, the spill of the hull's outline over each mask, and
//! Monte Carlo volumes of visual hulls.

use std::collections::HashMap;

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use winged::model::Serials;
use winged::model::camera::Camera;
use winged::model::check_solid;
use winged::vision::image::Mask;
use winged::vision::perceive::{Mesh, Outline};

use crate::rng::Rng;

/// Why a piece is not a valid closed body, if one is not: `to_body`'s refusal or the
/// validator's first violation (with the count).
pub fn invalid(pieces: &[Mesh]) -> Option<String> {
    for (i, p) in pieces.iter().enumerate() {
        let body = match p.to_body(&mut Serials::new()) {
            Ok(b) => b,
            Err(e) => return Some(format!("piece {i}: to_body: {e}")),
        };
        let report = check_solid(&body, 1e-9);
        if !report.is_ok() {
            return Some(format!(
                "piece {i}: {} violations, first {:?}",
                report.violations.len(),
                report.violations[0]
            ));
        }
        if p.volume() <= 0.0 {
            return Some(format!("piece {i}: volume {}", p.volume()));
        }
    }
    None
}

/// The winding number of the closed meshes about `x` (1 inside, 0 outside).
pub fn winding(pieces: &[Mesh], x: DVec3) -> f64 {
    pieces.iter().map(|mesh| mesh.winding(x)).sum()
}

/// Containment: how many of `points` have a winding number other than 1 (beyond 1e-6)
/// in `pieces`, and the winding number farthest from 1.
pub fn containment(pieces: &[Mesh], points: &[DVec3]) -> (usize, f64) {
    let w: Vec<f64> = points.par_iter().map(|&x| winding(pieces, x)).collect();
    let outside = w.iter().filter(|w| (*w - 1.0).abs() > 1e-6).count();
    let worst = w
        .iter()
        .copied()
        .max_by(|a, b| (a - 1.0).abs().total_cmp(&(b - 1.0).abs()))
        .unwrap_or(1.0);
    (outside, worst)
}

/// A quick inside test for many points: the parity of a ray toward +x through the
/// pieces' triangles, found through a grid over (y, z).
pub struct Parity {
    lo: DVec2,
    cell: DVec2,
    n: usize,
    cells: Vec<Vec<u32>>,
    triangles: Vec<[DVec3; 3]>,
}

impl Parity {
    /// The index of `pieces` (closed meshes).
    pub fn new(pieces: &[Mesh]) -> Parity {
        let mut triangles = Vec::new();
        for mesh in pieces {
            for f in &mesh.faces {
                let a = mesh.positions[f[0] as usize];
                for k in 1..f.len() - 1 {
                    triangles.push([
                        a,
                        mesh.positions[f[k] as usize],
                        mesh.positions[f[k + 1] as usize],
                    ]);
                }
            }
        }
        let yz = |p: DVec3| DVec2::new(p.y, p.z);
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for t in &triangles {
            for p in t {
                lo = lo.min(yz(*p));
                hi = hi.max(yz(*p));
            }
        }
        let n = 64;
        let cell = ((hi - lo) / n as f64).max(DVec2::splat(1e-12));
        let mut cells = vec![Vec::new(); n * n];
        for (i, t) in triangles.iter().enumerate() {
            let (a, b) = t.iter().fold(
                (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
                |(a, b), p| (a.min(yz(*p)), b.max(yz(*p))),
            );
            let (i0, i1) = (
                ((a - lo) / cell).floor().as_ivec2(),
                ((b - lo) / cell).floor().as_ivec2(),
            );
            for cy in i0.y.max(0)..=i1.y.min(n as i32 - 1) {
                for cx in i0.x.max(0)..=i1.x.min(n as i32 - 1) {
                    cells[cy as usize * n + cx as usize].push(i as u32);
                }
            }
        }
        Parity {
            lo,
            cell,
            n,
            cells,
            triangles,
        }
    }

    /// Whether `p` is inside (an odd number of crossings toward +x).
    pub fn inside(&self, p: DVec3) -> bool {
        let q = DVec2::new(p.y, p.z);
        let c = ((q - self.lo) / self.cell).floor().as_ivec2();
        if c.x < 0 || c.y < 0 || c.x >= self.n as i32 || c.y >= self.n as i32 {
            return false;
        }
        let mut odd = false;
        for &i in &self.cells[c.y as usize * self.n + c.x as usize] {
            let [a, b, cc] = self.triangles[i as usize];
            let (a2, b2, c2) = (
                DVec2::new(a.y, a.z),
                DVec2::new(b.y, b.z),
                DVec2::new(cc.y, cc.z),
            );
            let area = (b2 - a2).perp_dot(c2 - a2);
            if area == 0.0 {
                continue;
            }
            let (wa, wb, wc) = (
                (b2 - q).perp_dot(c2 - q) / area,
                (c2 - q).perp_dot(a2 - q) / area,
                (a2 - q).perp_dot(b2 - q) / area,
            );
            if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                continue;
            }
            if wa * a.x + wb * b.x + wc * cc.x > p.x {
                odd = !odd;
            }
        }
        odd
    }
}

/// The largest distance, in pixels, from a point of the outline of `pieces` seen by
/// `camera` to the pixel squares inside `mask` (0 on them): the contour edges (between
/// a face turned toward the camera and one turned away) are projected and sampled
/// every quarter pixel. Distances beyond `reach` pixels count as `reach`.
pub fn spill(pieces: &[Mesh], camera: &Camera, mask: &Mask, reach: i64) -> f64 {
    let centre = camera.position();
    let mut points: Vec<DVec2> = Vec::new();
    for mesh in pieces {
        let facing: Vec<bool> = mesh
            .faces
            .iter()
            .map(|f| {
                let p = |i: usize| mesh.positions[f[i % f.len()] as usize];
                let normal: DVec3 = (0..f.len()).map(|i| p(i).cross(p(i + 1))).sum();
                normal.dot(centre - p(0)) > 0.0
            })
            .collect();
        let mut by_edge: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
        for (fi, f) in mesh.faces.iter().enumerate() {
            for k in 0..f.len() {
                let (a, b) = (f[k], f[(k + 1) % f.len()]);
                by_edge.entry((a.min(b), a.max(b))).or_default().push(fi);
            }
        }
        for ((a, b), faces) in by_edge {
            if faces.len() == 2 && facing[faces[0]] == facing[faces[1]] {
                continue;
            }
            let (Some(ua), Some(ub)) = (
                camera.project(mesh.positions[a as usize]),
                camera.project(mesh.positions[b as usize]),
            ) else {
                return f64::INFINITY;
            };
            let steps = ((ub - ua).length() / 0.25).ceil().max(1.0) as usize;
            points.extend((0..=steps).map(|s| ua + (ub - ua) * (s as f64 / steps as f64)));
        }
    }
    points
        .par_iter()
        .map(|&q| distance_to_mask(mask, q, reach))
        .reduce(|| 0.0, f64::max)
}

/// The distance from `q` to the nearest pixel square inside `mask`, searched out to
/// `reach` pixels (beyond it, `reach`).
fn distance_to_mask(mask: &Mask, q: DVec2, reach: i64) -> f64 {
    let (x0, y0) = (q.x.floor() as i64, q.y.floor() as i64);
    let inside = |x: i64, y: i64| x >= 0 && y >= 0 && mask.get(x as u32, y as u32);
    if inside(x0, y0) {
        return 0.0;
    }
    let mut best = f64::INFINITY;
    for r in 1..=reach {
        for dy in -r..=r {
            for dx in -r..=r {
                if dx.abs() != r && dy.abs() != r {
                    continue;
                }
                let (x, y) = (x0 + dx, y0 + dy);
                if inside(x, y) {
                    let ex = (x as f64 - q.x).max(q.x - (x + 1) as f64).max(0.0);
                    let ey = (y as f64 - q.y).max(q.y - (y + 1) as f64).max(0.0);
                    best = best.min(ex.hypot(ey));
                }
            }
        }
        // Every pixel of the next ring is farther than r.
        if best <= r as f64 {
            return best;
        }
    }
    best.min(reach as f64)
}

/// An outline's rings, their edges bucketed by pixel row, for quick inside tests.
pub struct Rows {
    top: i64,
    rows: Vec<Vec<(DVec2, DVec2)>>,
}

impl Rows {
    /// The index of `outline`.
    pub fn new(outline: &Outline) -> Rows {
        let edges: Vec<(DVec2, DVec2)> = outline
            .rings
            .iter()
            .flat_map(|r| (0..r.len()).map(move |k| (r[k], r[(k + 1) % r.len()])))
            .collect();
        let top = edges
            .iter()
            .map(|(a, b)| a.y.min(b.y).floor() as i64)
            .min()
            .unwrap_or(0);
        let bottom = edges
            .iter()
            .map(|(a, b)| a.y.max(b.y).floor() as i64)
            .max()
            .unwrap_or(0);
        let mut rows = vec![Vec::new(); (bottom - top + 1).max(0) as usize];
        for &(a, b) in &edges {
            let (y0, y1) = (a.y.min(b.y).floor() as i64, a.y.max(b.y).floor() as i64);
            for y in y0..=y1 {
                rows[(y - top) as usize].push((a, b));
            }
        }
        Rows { top, rows }
    }

    /// Whether `q` is inside the outline (an odd number of ring crossings toward +u).
    pub fn inside(&self, q: DVec2) -> bool {
        let row = q.y.floor() as i64 - self.top;
        if row < 0 || row >= self.rows.len() as i64 {
            return false;
        }
        let mut odd = false;
        for &(a, b) in &self.rows[row as usize] {
            if (a.y > q.y) != (b.y > q.y) {
                let x = a.x + (q.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if x > q.x {
                    odd = !odd;
                }
            }
        }
        odd
    }
}

/// Monte Carlo volumes of two visual hulls of a ball of radius `r` about the origin,
/// from the same uniform samples of the box `lo..hi`: the true hull (a point is in when
/// every camera's ray through it meets the ball) and the hull of the polygons (a point
/// is in when it projects inside every view's outline).
pub struct BallHulls {
    /// Samples drawn.
    pub samples: usize,
    /// The box's volume.
    pub box_volume: f64,
    /// Samples in the true hull.
    pub in_true: usize,
    /// Samples in the polygons' hull.
    pub in_polygons: usize,
    /// Samples in the polygons' hull but outside `inner` (the box before it was
    /// enlarged): nonzero means the box was too small.
    pub beyond_inner: usize,
}

impl BallHulls {
    /// The volume of a count of samples, and its standard error.
    pub fn volume(&self, count: usize) -> (f64, f64) {
        let p = count as f64 / self.samples as f64;
        let se = (p * (1.0 - p) / self.samples as f64).sqrt();
        (p * self.box_volume, se * self.box_volume)
    }
}

/// Draws `samples` points in `lo..hi` (in chunks, each from its own seed, so the
/// result does not depend on the threads) and counts them in both hulls.
pub fn ball_hulls(
    r: f64,
    cameras: &[Camera],
    outlines: &[Outline],
    (lo, hi): (DVec3, DVec3),
    inner: (DVec3, DVec3),
    samples: usize,
    seed: u64,
) -> BallHulls {
    let rows: Vec<Rows> = outlines.iter().map(Rows::new).collect();
    let centres: Vec<DVec3> = cameras.iter().map(Camera::position).collect();
    const CHUNK: usize = 1 << 16;
    let chunks = samples.div_ceil(CHUNK);
    let counts = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut rng = Rng(crate::spread(seed ^ (c as u64).wrapping_mul(0x9E37)));
            let n = CHUNK.min(samples - c * CHUNK);
            let mut out = (0usize, 0usize, 0usize);
            for _ in 0..n {
                let p = DVec3::new(
                    rng.range(lo.x, hi.x),
                    rng.range(lo.y, hi.y),
                    rng.range(lo.z, hi.z),
                );
                let seen = centres.iter().all(|&c| {
                    // The ray from c through p passes within r of the origin, ahead.
                    let (v, w) = (p - c, -c);
                    v.dot(w) > 0.0 && v.cross(w).length_squared() <= r * r * v.length_squared()
                });
                if seen {
                    out.0 += 1;
                }
                let kept = cameras
                    .iter()
                    .zip(&rows)
                    .all(|(cam, rows)| cam.project(p).is_some_and(|q| rows.inside(q)));
                if kept {
                    out.1 += 1;
                    if p.cmplt(inner.0).any() || p.cmpgt(inner.1).any() {
                        out.2 += 1;
                    }
                }
            }
            out
        })
        .reduce(|| (0, 0, 0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
    BallHulls {
        samples,
        box_volume: (hi - lo).element_product(),
        in_true: counts.0,
        in_polygons: counts.1,
        beyond_inner: counts.2,
    }
}
