//! Projected areas: how much of the image each body covers, alone and among the others,
//! computed exactly (up to rounding) by clipping polygons in the image plane, not by
//! counting pixels.
//!
//! For every body of a [`Scene`] seen through a [`View`], [`projected_areas`] gives the
//! area of the body's own silhouette (as if it were alone), the area where it is the
//! nearest surface inside the image window, and the box of that visible part. Recognition
//! compares them (the visible fraction) and with what a picture shows.
//!
//! # Method
//!
//! * **Front triangles.** Bodies are closed, so a ray meets a front face of a body before
//!   any of its back faces: only the scene's triangles whose face looks toward the eye
//!   ([`SceneFace::faces_toward`](crate::render::SceneFace::faces_toward)) count. Each is
//!   taken to camera coordinates ([`View::to_camera`]), clipped at the near plane
//!   ([`View::clip_polygon_near`], a convex polygon of at most four corners) and
//!   projected ([`View::project`]); what lies in front of the near plane is not seen. A
//!   camera inside a closed body sees all its faces from behind, so that body covers
//!   nothing.
//! * **Depth as a function of the pixel.** Along the ray through pixel `(u, v)`, the camera
//!   point at depth `z` (−ZCC) is `z·r(u, v)` with `r = ((u − cx)/fx, −(v − cy)/fy, −1)`
//!   ([`View::unproject`] at depth 1). On a triangle's plane `n·p = d` (camera
//!   coordinates), `1/z = n·r(u, v) / d`, an affine function of `(u, v)`. So the part of the
//!   image where triangle `g` is nearer than triangle `t` — where `g`'s inverse depth
//!   exceeds `t`'s — is a half-plane, and `g` hides `t` exactly on the convex polygon
//!   `proj(g) ∩ {g nearer than t}`. "Nearer" means nearer by more than [`DEPTH_TOL`] of the
//!   depth, so coplanar triangles (of one face, or of touching bodies) never hide each
//!   other.
//! * **Nearest surface.** Among a set `S` of front triangles, `t` is the nearest surface
//!   on `proj(t) ∖ ⋃_{g ∈ S, g ≠ t} (proj(g) ∩ {g nearer than t})`. That remainder is kept
//!   as a list of convex pieces; subtracting a convex polygon `C` from a convex piece `P`
//!   cuts `P` along `C`'s sides in turn, keeping each part outside a side (at most `|C|`
//!   convex pieces) and dropping what is left inside `C`. Pieces smaller than
//!   [`MIN_AREA`] (or than [`REL_AREA`] of their triangle's projection) are rounding
//!   and are dropped. The remainders of distinct triangles do not overlap (each point of
//!   the image is given to the nearest triangle there), so their areas add up.
//! * **The three answers.** `whole`: `S` is the body's own front triangles, nothing else,
//!   and the image plane is unbounded (its area is that of the union of their
//!   projections, the silhouette). `visible`: `S` is every front triangle of the scene,
//!   and each `proj(t)` is first clipped to the window `[0, w] × [0, h]`. `bbox`: the
//!   corners' extremes over the visible pieces.
//!
//! # Acceleration
//!
//! Projected triangles are sorted nearest first (by their nearest depth). Candidate pairs
//! come from a sort-and-sweep over their bounding boxes: sorted by u0, each box is
//! compared with the later ones whose u0 is at most its u1, and kept when their v ranges
//! meet (for `visible` the boxes are first clipped to the window, and triangles wholly
//! outside it take no part; for `whole` each body is swept on its own). Of such a pair,
//! `g` goes on `t`'s list only when `g` is nearer than `t`'s plane at one of `g`'s own
//! corners: the difference of inverse depths is affine, so otherwise `g` is nowhere
//! nearer than `t` and hides none of it. This leaves a convex body no pairs of its own at
//! all. Lists are kept nearest first.
//!
//! While subtracting, an occluder is passed over when its box misses the box of the
//! pieces left, or when the half-plane where it is nearer misses that box (an affine
//! function's maximum over a box is at a corner); a piece is left as it is when its box
//! misses the occluder's, or when one side of the occluder separates them. A triangle
//! stops as soon as nothing of it is left. Sweeps and triangles run in parallel (rayon).

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use crate::camera::View;
use crate::render::Scene;

/// Pieces of a remainder smaller than this (pixels²) are rounding noise: dropped.
pub const MIN_AREA: f64 = 1e-9;

/// Pieces smaller than this fraction of their triangle's projected area are rounding
/// noise too (it matters only for triangles projecting to very large areas, near the
/// near plane).
pub const REL_AREA: f64 = 1e-12;

/// Sides of an occluder shorter than this fraction of its extent are dropped (their
/// direction is mostly rounding).
const SHORT_SIDE: f64 = 1e-9;

/// A triangle hides another only where it is nearer by more than this fraction of its
/// depth.
pub const DEPTH_TOL: f64 = 1e-9;

/// One body's projected areas (pixels²) and the box of its visible part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyArea {
    /// The area of the body's own silhouette in the (unbounded) image plane, of what lies
    /// beyond the near plane, ignoring every other body.
    pub whole: f64,
    /// The area where the body is the nearest surface, within the image window
    /// `[0, w] × [0, h]`.
    pub visible: f64,
    /// The box `[u0, v0, u1, v1]` of the visible part, `None` when nothing is visible.
    pub bbox: Option<[f64; 4]>,
}

impl BodyArea {
    /// Nothing seen.
    const NONE: BodyArea = BodyArea {
        whole: 0.0,
        visible: 0.0,
        bbox: None,
    };
}

/// Every body's projected areas seen through `view`; index `i` of the answer is body `i`
/// of `scene.bodies`. See the [module documentation](self) for the method.
///
/// Preconditions: `view` comes from a valid camera ([`View::new`]); the bodies are closed
/// solids (a lamina counts from the side it faces). Interpenetrating bodies are handled
/// (depths are compared point by point), as are touching and coplanar faces.
///
/// Postconditions: one entry per body; every area is finite and ≥ 0; `visible ≤ whole`
/// and the sum of `visible` over the bodies is at most `w·h` (up to rounding); `bbox` is
/// `Some` exactly when `visible > 0` and then lies within the window. Deterministic for a
/// given scene and view. Never panics: degenerate triangles, geometry behind the camera
/// or cut by the near plane, and a camera inside a body give the areas of what lies
/// beyond the near plane (a camera inside a closed body sees none of that body).
pub fn projected_areas(scene: &Scene, view: &View) -> Vec<BodyArea> {
    let mut areas = vec![BodyArea::NONE; scene.bodies.len()];
    let fronts = front_triangles(scene, view);
    if fronts.is_empty() {
        return areas;
    }
    let (w, h) = view.size();
    let window = [0.0, 0.0, f64::from(w), f64::from(h)];

    // Occluder lists: within each body for `whole`, over the window for `visible`.
    let everyone: Vec<Option<[f64; 4]>> = fronts.iter().map(|f| Some(f.bbox)).collect();
    let mut by_body: Vec<Vec<u32>> = vec![Vec::new(); scene.bodies.len()];
    for (i, f) in fronts.iter().enumerate() {
        if let Some(list) = by_body.get_mut(f.body as usize) {
            list.push(i as u32);
        }
    }
    let own = Lists::build(&fronts, &everyone, &by_body);
    let in_window: Vec<Option<[f64; 4]>> =
        fronts.iter().map(|f| intersect(f.bbox, window)).collect();
    let all: Vec<u32> = (0..fronts.len() as u32)
        .filter(|&i| in_window[i as usize].is_some())
        .collect();
    let shared = Lists::build(&fronts, &in_window, &[all]);

    let results: Vec<(f64, f64, Option<[f64; 4]>)> = (0..fronts.len())
        .into_par_iter()
        .with_min_len(8)
        .map_init(Scratch::default, |scratch, t| {
            let (whole, _) = remainder(&fronts, t, own.of(t), None, scratch);
            let (visible, bbox) = if in_window[t].is_some() {
                remainder(&fronts, t, shared.of(t), Some(window), scratch)
            } else {
                (0.0, None)
            };
            (whole, visible, bbox)
        })
        .collect();

    for (front, (whole, visible, bbox)) in fronts.iter().zip(results) {
        let Some(area) = areas.get_mut(front.body as usize) else {
            continue;
        };
        area.whole += whole;
        area.visible += visible;
        area.bbox = match (area.bbox, bbox) {
            (Some(a), Some(b)) => Some(union(a, b)),
            (a, b) => a.or(b),
        };
    }
    areas
}

/// One front triangle, clipped at the near plane and projected.
#[derive(Clone, Copy, Debug)]
struct Front {
    /// Index into [`Scene::bodies`].
    body: u32,
    /// The projected corners, counter-clockwise in `(u, v)` taken as plain numbers
    /// (positive shoelace area); `corners[..len]` are used.
    corners: [DVec2; 4],
    /// Number of corners, 3 or 4.
    len: usize,
    /// Inverse depth as an affine function `w` of the pixel: `1/depth = w.x·u + w.y·v +
    /// w.z` on the triangle's plane.
    inverse_depth: DVec3,
    /// Smallest and largest depth (−ZCC) of the clipped corners.
    near: f64,
    far: f64,
    /// Bounding box of the projection: u0, v0, u1, v1 (pixels, not clamped).
    bbox: [f64; 4],
    /// Projected area, pixels².
    area: f64,
}

impl Front {
    fn corners(&self) -> &[DVec2] {
        &self.corners[..self.len]
    }
}

/// The scene's front triangles that keep a projected area beyond the near plane, sorted
/// nearest first (by nearest depth, then scene order).
fn front_triangles(scene: &Scene, view: &View) -> Vec<Front> {
    let eye = view.eye();
    let mut fronts: Vec<(usize, Front)> = scene
        .triangles
        .par_iter()
        .zip(scene.triangle_faces.par_iter())
        .enumerate()
        .with_min_len(256)
        .map_init(Default::default, |work, (i, (tri, &face))| {
            let face = scene.faces.get(face as usize)?;
            if !face.faces_toward(eye) {
                return None;
            }
            let corners = tri.map(|v| scene.points.get(v as usize).copied());
            let [Some(a), Some(b), Some(c)] = corners else {
                return None;
            };
            project_triangle(view, face.body, [a, b, c], work).map(|f| (i, f))
        })
        .flatten()
        .collect();
    fronts.par_sort_unstable_by(|(i, a), (j, b)| a.near.total_cmp(&b.near).then(i.cmp(j)));
    fronts.into_iter().map(|(_, f)| f).collect()
}

/// World triangle `tri` of body `body` clipped at the near plane and projected, or `None`
/// when nothing of positive area is left of it. `work` is working storage.
fn project_triangle(
    view: &View,
    body: u32,
    tri: [DVec3; 3],
    work: &mut (Vec<DVec3>, Vec<DVec2>),
) -> Option<Front> {
    let (clipped, projected) = work;
    let [a, b, c] = tri.map(|p| view.to_camera(p));
    // The plane n·p = d; the eye (the origin) is off it for a triangle of positive area
    // that is not seen edge-on.
    let n = (b - a).cross(c - a);
    let d = n.dot(a);
    if d == 0.0 || !d.is_finite() || !n.is_finite() {
        return None;
    }
    view.clip_polygon_near(&[a, b, c], clipped);
    projected.clear();
    projected.extend(clipped.iter().map(|&p| view.project(p)));
    drop_short_sides(projected);
    // A triangle cut by one plane keeps at most four corners.
    let len = projected.len();
    if !(3..=4).contains(&len) {
        return None;
    }
    let mut corners = [DVec2::ZERO; 4];
    corners[..len].copy_from_slice(projected);
    let (near, far) = clipped
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(-p.z), hi.max(-p.z))
        });
    let mut area = signed_area(&corners[..len]);
    if area < 0.0 {
        corners[..len].reverse();
        area = -area;
    }
    if !(area >= MIN_AREA && area.is_finite()) {
        return None;
    }
    let k = &view.intrinsics;
    // n·r(u, v) with r = ((u − cx)/fx, −(v − cy)/fy, −1), divided by d.
    let inverse_depth = DVec3::new(
        n.x / k.fx,
        -n.y / k.fy,
        -n.x * k.cx / k.fx + n.y * k.cy / k.fy - n.z,
    ) / d;
    if !inverse_depth.is_finite() {
        return None;
    }
    let bbox = bbox_of(&corners[..len])?;
    Some(Front {
        body,
        corners,
        len,
        inverse_depth,
        near,
        far,
        bbox,
        area,
    })
}

/// For each front triangle, the triangles that may hide part of it, nearest first:
/// `items[start[t]..start[t + 1]]`.
struct Lists {
    start: Vec<usize>,
    items: Vec<u32>,
}

impl Lists {
    /// The lists of `fronts` (sorted nearest first), pairing only members of one group,
    /// by their boxes `boxes` (a triangle with `None` takes no part). Each group is swept
    /// along u: sorted by u0, each box meets the later ones whose u0 is at most its u1
    /// and whose v range meets its own. Of such a pair, `g` goes on `t`'s list when it
    /// [`may_hide`] it.
    fn build(fronts: &[Front], boxes: &[Option<[f64; 4]>], groups: &[Vec<u32>]) -> Lists {
        let orders: Vec<Vec<(u32, [f64; 4])>> = groups
            .par_iter()
            .map(|members| {
                let mut order: Vec<(u32, [f64; 4])> = members
                    .iter()
                    .filter_map(|&i| boxes.get(i as usize).copied().flatten().map(|b| (i, b)))
                    .collect();
                order.sort_unstable_by(|a, b| a.1[0].total_cmp(&b.1[0]).then(a.0.cmp(&b.0)));
                order
            })
            .collect();
        // Pairs (t, g) as t·2³² + g, so that sorting groups them by t, nearest g first.
        let key = |t: u32, g: u32| (u64::from(t) << 32) | u64::from(g);
        let mut keys: Vec<u64> = orders
            .par_iter()
            .flat_map(|order| {
                (0..order.len())
                    .into_par_iter()
                    .with_min_len(64)
                    .flat_map_iter(move |p| {
                        let (i, bi) = order[p];
                        let fi = &fronts[i as usize];
                        let mut pairs = Vec::new();
                        for &(j, bj) in &order[p + 1..] {
                            if bj[0] > bi[2] {
                                break;
                            }
                            if bj[1] > bi[3] || bj[3] < bi[1] {
                                continue;
                            }
                            let fj = &fronts[j as usize];
                            if may_hide(fj, fi) {
                                pairs.push(key(i, j));
                            }
                            if may_hide(fi, fj) {
                                pairs.push(key(j, i));
                            }
                        }
                        pairs
                    })
            })
            .collect();
        keys.par_sort_unstable();
        let mut start = vec![0usize; fronts.len() + 1];
        for &k in &keys {
            start[(k >> 32) as usize + 1] += 1;
        }
        for i in 0..fronts.len() {
            start[i + 1] += start[i];
        }
        let items = keys.iter().map(|&k| k as u32).collect();
        Lists { start, items }
    }

    /// The list of triangle `t`.
    fn of(&self, t: usize) -> &[u32] {
        match (self.start.get(t), self.start.get(t + 1)) {
            (Some(&s), Some(&e)) => &self.items[s..e],
            _ => &[],
        }
    }
}

/// Whether triangle `g` is nearer than triangle `t` (by more than [`DEPTH_TOL`]) at some
/// point of `g`'s projection, where `t`'s plane is extended beyond `t`: a necessary
/// condition for `g` to hide part of `t`. Exact: the difference of inverse depths is
/// affine, so its maximum over `g`'s convex projection is at a corner.
fn may_hide(g: &Front, t: &Front) -> bool {
    if g.near >= t.far {
        return false;
    }
    let nearer = nearer_than(g, t);
    g.corners().iter().any(|&q| affine(nearer, q) > 0.0)
}

/// The affine function of the pixel that is positive where `g` is nearer than `t` by more
/// than [`DEPTH_TOL`] of the depth: `(1 − tol)·w_g − w_t` of the inverse depths.
#[inline]
fn nearer_than(g: &Front, t: &Front) -> DVec3 {
    g.inverse_depth * (1.0 - DEPTH_TOL) - t.inverse_depth
}

/// Convex polygons kept flat, each with its box and area. A piece is replaced by
/// marking it dead and appending what replaces it; [`Pieces::sweep`] drops the dead.
#[derive(Default)]
struct Pieces {
    points: Vec<DVec2>,
    slots: Vec<Slot>,
}

/// One piece of [`Pieces`].
#[derive(Clone, Copy, Debug)]
struct Slot {
    /// Its corners: `points[start..end]`.
    start: usize,
    end: usize,
    bbox: [f64; 4],
    area: f64,
    alive: bool,
}

impl Pieces {
    fn clear(&mut self) {
        self.points.clear();
        self.slots.clear();
    }

    /// Adds the polygon `poly` of area `area`; one with a corner not finite is left out.
    fn push(&mut self, poly: &[DVec2], area: f64) {
        if let Some(bbox) = bbox_of(poly) {
            let start = self.points.len();
            self.points.extend_from_slice(poly);
            self.slots.push(Slot {
                start,
                end: self.points.len(),
                bbox,
                area,
                alive: true,
            });
        }
    }

    fn len(&self) -> usize {
        self.slots.len()
    }

    fn get(&self, k: usize) -> &[DVec2] {
        let s = &self.slots[k];
        &self.points[s.start..s.end]
    }

    /// Drops the dead pieces, keeping the order of the others.
    fn sweep(&mut self) {
        self.slots.retain(|s| s.alive);
    }

    /// The box around every piece, `None` when there are none.
    fn bbox(&self) -> Option<[f64; 4]> {
        self.slots.iter().map(|s| s.bbox).reduce(union)
    }

    fn area(&self) -> f64 {
        self.slots.iter().map(|s| s.area).sum()
    }
}

/// Per-thread working storage.
#[derive(Default)]
struct Scratch {
    pieces: Pieces,
    /// The occluder's part nearer than the current triangle.
    cover: Vec<DVec2>,
    split: Split,
}

/// Working storage of [`subtract`].
#[derive(Default)]
struct Split {
    rest: Vec<DVec2>,
    inside: Vec<DVec2>,
    outside: Vec<DVec2>,
}

/// The area and box of the part of `fronts[t]` (clipped to `window` if given) where it is
/// the nearest surface among itself and `occluders` (indices into `fronts`, nearest
/// first). `(0, None)` when nothing is left.
fn remainder(
    fronts: &[Front],
    t: usize,
    occluders: &[u32],
    window: Option<[f64; 4]>,
    s: &mut Scratch,
) -> (f64, Option<[f64; 4]>) {
    let Some(ft) = fronts.get(t) else {
        return (0.0, None);
    };
    let min_area = MIN_AREA.max(REL_AREA * ft.area);
    let sp = &mut s.split;
    sp.rest.clear();
    sp.rest.extend_from_slice(ft.corners());
    if let Some([u0, v0, u1, v1]) = window {
        // The window's sides as half-planes a·u + b·v + c ≥ 0.
        for line in [
            DVec3::new(1.0, 0.0, -u0),
            DVec3::new(-1.0, 0.0, u1),
            DVec3::new(0.0, 1.0, -v0),
            DVec3::new(0.0, -1.0, v1),
        ] {
            split(
                &sp.rest,
                |q| affine(line, q),
                &mut sp.inside,
                &mut sp.outside,
            );
            std::mem::swap(&mut sp.rest, &mut sp.inside);
            if sp.rest.len() < 3 {
                return (0.0, None);
            }
        }
        // Crossing points can land a rounding error outside.
        let (lo, hi) = (DVec2::new(u0, v0), DVec2::new(u1, v1));
        for q in &mut sp.rest {
            *q = q.clamp(lo, hi);
        }
    }
    let area = signed_area(&sp.rest);
    if area < min_area {
        return (0.0, None);
    }
    s.pieces.clear();
    s.pieces.push(&sp.rest, area);
    let Some(mut bbox) = s.pieces.bbox() else {
        return (0.0, None);
    };

    for &g in occluders {
        let Some(fg) = fronts.get(g as usize) else {
            continue;
        };
        if g as usize == t || fg.near >= ft.far || intersect(fg.bbox, bbox).is_none() {
            continue;
        }
        let nearer = nearer_than(fg, ft);
        let [u0, v0, u1, v1] = bbox;
        let most = [(u0, v0), (u1, v0), (u0, v1), (u1, v1)]
            .into_iter()
            .map(|(u, v)| affine(nearer, DVec2::new(u, v)))
            .fold(f64::NEG_INFINITY, f64::max);
        // (`f64::max` passes NaN over: `most` is never NaN.)
        if most <= 0.0 {
            continue;
        }
        split(
            fg.corners(),
            |q| affine(nearer, q),
            &mut s.cover,
            &mut s.split.outside,
        );
        drop_short_sides(&mut s.cover);
        if s.cover.len() < 3 || signed_area(&s.cover) < min_area {
            continue;
        }
        let Some(cover_box) = bbox_of(&s.cover) else {
            continue;
        };
        if intersect(cover_box, bbox).is_none() {
            continue;
        }
        let mut changed = false;
        for k in 0..s.pieces.len() {
            if intersect(s.pieces.slots[k].bbox, cover_box).is_some() {
                changed |= subtract(&mut s.pieces, k, &s.cover, min_area, &mut s.split);
            }
        }
        if changed {
            s.pieces.sweep();
            match s.pieces.bbox() {
                Some(b) => bbox = b,
                None => return (0.0, None),
            }
        }
    }
    let bbox = match (s.pieces.bbox(), window) {
        (Some(b), Some(w)) => intersect(b, w),
        (b, _) => b,
    };
    (s.pieces.area(), bbox)
}

/// Replaces piece `k` of `pieces` by its convex parts outside the convex polygon `cover`
/// (both counter-clockwise), cut along `cover`'s sides in turn: marks it dead and appends
/// the parts, dropping those below `min_area`. Leaves it as it is, and returns false,
/// when a side of `cover` separates them.
fn subtract(pieces: &mut Pieces, k: usize, cover: &[DVec2], min_area: f64, sp: &mut Split) -> bool {
    let n = cover.len();
    // The side through a → b as a function positive on cover's side (to its left).
    let side = |i: usize| {
        let (a, b) = (cover[i], cover[(i + 1) % n]);
        move |q: DVec2| (b - a).perp_dot(q - a)
    };
    let piece = pieces.get(k);
    let separates = |i: usize| {
        let f = side(i);
        cover[i] != cover[(i + 1) % n] && piece.iter().all(|&q| f(q) <= 0.0)
    };
    if (0..n).any(separates) {
        return false;
    }
    sp.rest.clear();
    sp.rest.extend_from_slice(piece);
    pieces.slots[k].alive = false;
    for i in 0..n {
        let f = side(i);
        if cover[i] == cover[(i + 1) % n] || sp.rest.iter().all(|&q| f(q) >= 0.0) {
            continue;
        }
        split(&sp.rest, f, &mut sp.inside, &mut sp.outside);
        if sp.outside.len() >= 3 {
            let area = signed_area(&sp.outside);
            if area >= min_area {
                pieces.push(&sp.outside, area);
            }
        }
        std::mem::swap(&mut sp.rest, &mut sp.inside);
        if sp.rest.len() < 3 || signed_area(&sp.rest) < min_area {
            break;
        }
    }
    // What is left lies inside `cover`: hidden.
    true
}

/// Cuts the convex polygon `poly` by the line `f = 0` of an affine function `f`: the part
/// where `f ≥ 0` into `pos`, where `f ≤ 0` into `neg` (both cleared first, orientation
/// kept). A crossing point is computed once and shared by both parts.
fn split(poly: &[DVec2], f: impl Fn(DVec2) -> f64, pos: &mut Vec<DVec2>, neg: &mut Vec<DVec2>) {
    pos.clear();
    neg.clear();
    let Some(&first) = poly.first() else {
        return;
    };
    let f_first = f(first);
    let mut fp = f_first;
    for (i, &p) in poly.iter().enumerate() {
        let (q, fq) = match poly.get(i + 1) {
            Some(&q) => (q, f(q)),
            None => (first, f_first),
        };
        if fp >= 0.0 {
            pos.push(p);
        }
        if fp <= 0.0 {
            neg.push(p);
        }
        if (fp > 0.0 && fq < 0.0) || (fp < 0.0 && fq > 0.0) {
            let x = p + (q - p) * (fp / (fp - fq));
            pos.push(x);
            neg.push(x);
        }
        fp = fq;
    }
}

/// Removes from the polygon `poly` the corners that lie within [`SHORT_SIDE`] of its
/// extent (or of its distance from the origin, if larger, in thousandths) from the
/// previous corner kept, so that every side left has a direction rounding does not
/// swamp. The polygon moves by at most that much.
fn drop_short_sides(poly: &mut Vec<DVec2>) {
    let Some(b) = bbox_of(poly) else {
        poly.clear();
        return;
    };
    let extent = (b[2] - b[0]).max(b[3] - b[1]);
    let far = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let min = SHORT_SIDE * extent.max(1e-3 * far);
    let short = |p: DVec2, q: DVec2| (p - q).abs().max_element() <= min;
    let mut kept = 0;
    for i in 0..poly.len() {
        if kept == 0 || !short(poly[i], poly[kept - 1]) {
            poly[kept] = poly[i];
            kept += 1;
        }
    }
    while kept > 1 && short(poly[kept - 1], poly[0]) {
        kept -= 1;
    }
    poly.truncate(kept);
}

/// `a·u + b·v + c` for `line = (a, b, c)`.
#[inline]
fn affine(line: DVec3, q: DVec2) -> f64 {
    line.x * q.x + line.y * q.y + line.z
}

/// Shoelace area, positive for counter-clockwise in `(u, v)` as plain numbers.
fn signed_area(poly: &[DVec2]) -> f64 {
    let Some(&o) = poly.first() else {
        return 0.0;
    };
    let mut twice = 0.0;
    for w in poly.windows(2).skip(1) {
        twice += (w[0] - o).perp_dot(w[1] - o);
    }
    0.5 * twice
}

/// The bounding box `[u0, v0, u1, v1]` of `points`, `None` when there are none or one is
/// not finite.
fn bbox_of(points: &[DVec2]) -> Option<[f64; 4]> {
    let first = *points.first()?;
    let (lo, hi) = points
        .iter()
        .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    (lo.is_finite() && hi.is_finite()).then_some([lo.x, lo.y, hi.x, hi.y])
}

/// The common part of two boxes, `None` when they do not meet.
fn intersect(a: [f64; 4], b: [f64; 4]) -> Option<[f64; 4]> {
    let c = [
        a[0].max(b[0]),
        a[1].max(b[1]),
        a[2].min(b[2]),
        a[3].min(b[3]),
    ];
    (c[0] <= c[2] && c[1] <= c[3]).then_some(c)
}

/// The smallest box around two boxes.
fn union(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0].min(b[0]),
        a[1].min(b[1]),
        a[2].max(b[2]),
        a[3].max(b[3]),
    ]
}

#[cfg(test)]
mod tests {
    use std::time::Instant;

    use glam::{DQuat, DVec2, DVec3};

    use super::*;
    use crate::camera::DEFAULT_NEAR;
    use crate::model::{Camera, Intrinsics, Pose, World, solids};
    use crate::render::sample::{L_SHAPE, SplitMix64, blocks, ring_cameras};

    /// A world of boxes: (pose, size) each, in body order.
    fn boxes(list: &[(Pose, [f64; 3])]) -> World {
        let mut w = World::new();
        let root = w.root();
        for &(pose, [x, y, z]) in list {
            w.insert_with(None, root, pose, |s| solids::mkcube(s, x, y, z))
                .unwrap();
        }
        w
    }

    fn view(eye: DVec3, target: DVec3, up: DVec3, k: Intrinsics) -> View {
        let cam = Camera::look_at(eye, target, up, k).unwrap();
        View::new(&cam, DEFAULT_NEAR)
    }

    fn at(x: f64, y: f64, z: f64) -> Pose {
        Pose::from_translation(DVec3::new(x, y, z))
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    fn close_box(a: [f64; 4], b: [f64; 4], tol: f64) -> bool {
        a.iter().zip(&b).all(|(x, y)| close(*x, *y, tol))
    }

    /// Independent estimates by casting rays through a grid of sample points.
    struct Caster {
        /// Every scene triangle (front or back) in camera coordinates, with its body.
        triangles: Vec<([DVec3; 3], u32)>,
        view: View,
    }

    impl Caster {
        fn new(scene: &Scene, view: &View) -> Caster {
            let triangles = scene
                .triangles
                .iter()
                .zip(&scene.triangle_faces)
                .map(|(t, &f)| {
                    (
                        t.map(|i| view.to_camera(scene.points[i as usize])),
                        scene.faces[f as usize].body,
                    )
                })
                .collect();
            Caster {
                triangles,
                view: *view,
            }
        }

        /// The depth at which the ray through `uv` meets triangle `t` beyond the near
        /// plane (Möller–Trumbore), if it does.
        fn hit(&self, t: &[DVec3; 3], uv: DVec2) -> Option<f64> {
            let r = self.view.unproject(uv, 1.0);
            let [a, b, c] = *t;
            let (e1, e2) = (b - a, c - a);
            let p = r.cross(e2);
            let det = e1.dot(p);
            if det.abs() < 1e-300 {
                return None;
            }
            let s = -a;
            let x = s.dot(p) / det;
            if !(0.0..=1.0).contains(&x) {
                return None;
            }
            let q = s.cross(e1);
            let y = r.dot(q) / det;
            if y < 0.0 || x + y > 1.0 {
                return None;
            }
            let depth = e2.dot(q) / det;
            (depth >= self.view.near).then_some(depth)
        }

        /// The body nearest along the ray through `uv`, if any.
        fn nearest(&self, uv: DVec2) -> Option<u32> {
            self.triangles
                .iter()
                .filter_map(|(t, b)| self.hit(t, uv).map(|d| (d, *b)))
                .min_by(|x, y| x.0.total_cmp(&y.0))
                .map(|(_, b)| b)
        }

        /// The sample points: cell centres of a grid of side `step` over `region`.
        fn samples(region: [f64; 4], step: f64) -> impl Iterator<Item = DVec2> {
            let nx = ((region[2] - region[0]) / step).ceil() as usize;
            let ny = ((region[3] - region[1]) / step).ceil() as usize;
            (0..ny).flat_map(move |j| {
                (0..nx).map(move |i| {
                    DVec2::new(
                        region[0] + (i as f64 + 0.5) * step,
                        region[1] + (j as f64 + 0.5) * step,
                    )
                })
            })
        }

        /// Estimated silhouette area of body `b` alone: samples over the box of its
        /// projected corners (all must be in front of the camera) whose ray meets it.
        fn whole(&self, b: u32, step: f64) -> f64 {
            let own: Vec<&[DVec3; 3]> = self
                .triangles
                .iter()
                .filter(|(_, body)| *body == b)
                .map(|(t, _)| t)
                .collect();
            let mut region = [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ];
            for p in own.iter().flat_map(|t| t.iter()) {
                assert!(
                    p.z < -self.view.near,
                    "the estimate needs every corner in front"
                );
                let q = self.view.project(*p);
                region = [
                    region[0].min(q.x),
                    region[1].min(q.y),
                    region[2].max(q.x),
                    region[3].max(q.y),
                ];
            }
            let count = Caster::samples(region, step)
                .filter(|&uv| own.iter().any(|t| self.hit(t, uv).is_some()))
                .count();
            count as f64 * step * step
        }

        /// Estimated visible area of each of `bodies` bodies within the window, and the
        /// box of its samples.
        fn visible(&self, bodies: usize, step: f64) -> Vec<(f64, Option<[f64; 4]>)> {
            let (w, h) = self.view.size();
            let mut out = vec![(0.0, None::<[f64; 4]>); bodies];
            for uv in Caster::samples([0.0, 0.0, f64::from(w), f64::from(h)], step) {
                if let Some(b) = self.nearest(uv) {
                    let e = &mut out[b as usize];
                    e.0 += step * step;
                    let q = [uv.x, uv.y, uv.x, uv.y];
                    e.1 = Some(e.1.map_or(q, |r| union(r, q)));
                }
            }
            out
        }
    }

    /// The sum of the projected areas of body `b`'s front triangles, overlaps counted
    /// twice (every corner must be in front of the camera).
    fn front_area_sum(scene: &Scene, view: &View, b: u32) -> f64 {
        scene
            .triangles
            .iter()
            .zip(&scene.triangle_faces)
            .filter(|(_, f)| {
                let face = &scene.faces[**f as usize];
                face.body == b && face.faces_toward(view.eye())
            })
            .map(|(t, _)| {
                let q = t.map(|i| view.project(view.to_camera(scene.points[i as usize])));
                signed_area(&q).abs()
            })
            .sum()
    }

    #[test]
    fn inverse_depth_is_affine_in_the_pixel() {
        let k = Intrinsics::new(640, 480, 500.0, 520.0, 300.0, 250.0).unwrap();
        let v = view(
            DVec3::new(1.0, -4.0, 3.0),
            DVec3::new(0.2, 0.1, 0.3),
            DVec3::Z,
            k,
        );
        let tri = [
            DVec3::new(0.3, 0.1, -0.4),
            DVec3::new(1.2, 0.5, 0.9),
            DVec3::new(-0.7, 0.9, 0.2),
        ];
        let mut work = Default::default();
        let f = project_triangle(&v, 0, tri, &mut work).unwrap();
        assert!(f.area > 1.0);
        // At the corners and at points inside, 1/w(u, v) is the true depth.
        let cam = tri.map(|p| v.to_camera(p));
        for (wa, wb, wc) in [
            (1.0, 0.0, 0.0),
            (0.0, 1.0, 0.0),
            (0.2, 0.3, 0.5),
            (0.6, 0.1, 0.3),
        ] {
            let c = cam[0] * wa + cam[1] * wb + cam[2] * wc;
            let uv = v.project(c);
            let depth = 1.0 / affine(f.inverse_depth, uv);
            assert!(close(depth, -c.z, 1e-9 * -c.z), "{depth} vs {}", -c.z);
            assert!((v.unproject(uv, depth) - c).length() <= 1e-9 * c.length());
        }
        // Corners counter-clockwise in (u, v) as numbers.
        assert!(signed_area(f.corners()) > 0.0);
    }

    #[test]
    fn degenerate_triangles_are_left_out() {
        let k = Intrinsics::centered(640, 480, 500.0).unwrap();
        let v = view(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y, k);
        let mut work = Default::default();
        let collinear = [DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        assert!(project_triangle(&v, 0, collinear, &mut work).is_none());
        let repeated = [DVec3::ZERO, DVec3::ZERO, DVec3::Y];
        assert!(project_triangle(&v, 0, repeated, &mut work).is_none());
        let behind = [
            DVec3::new(0.0, 0.0, 6.0),
            DVec3::new(1.0, 0.0, 6.0),
            DVec3::new(0.0, 1.0, 6.0),
        ];
        assert!(project_triangle(&v, 0, behind, &mut work).is_none());
        let edge_on = [DVec3::ZERO, DVec3::Z, DVec3::new(0.0, 1.0, 0.0)];
        assert!(project_triangle(&v, 0, edge_on, &mut work).is_none());
        // Cut by the near plane: four corners, all beyond it.
        let across = [
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, -1.0, 6.0),
        ];
        let f = project_triangle(&v, 0, across, &mut work).unwrap();
        assert_eq!(f.corners().len(), 4);
        assert!(f.near >= DEFAULT_NEAR * (1.0 - 1e-12) && f.far <= 5.0 + 1e-12);
    }

    #[test]
    fn subtracting_a_square_leaves_a_frame() {
        let sq = |lo: f64, hi: f64| {
            [
                DVec2::new(lo, lo),
                DVec2::new(hi, lo),
                DVec2::new(hi, hi),
                DVec2::new(lo, hi),
            ]
        };
        let mut sp = Split::default();
        let mut p = Pieces::default();
        p.push(&sq(0.0, 4.0), 16.0);
        assert!(subtract(&mut p, 0, &sq(1.0, 2.0), MIN_AREA, &mut sp));
        p.sweep();
        let total: f64 = (0..p.len()).map(|k| signed_area(p.get(k))).sum();
        assert!(close(total, 15.0, 1e-12));
        assert!(close(p.area(), 15.0, 1e-12));
        assert_eq!(p.bbox(), Some([0.0, 0.0, 4.0, 4.0]));
        assert_eq!(p.len(), 4);
        // A cover holding the whole piece leaves nothing; a disjoint one, everything.
        p.clear();
        p.push(&sq(1.0, 2.0), 1.0);
        assert!(subtract(&mut p, 0, &sq(0.0, 4.0), MIN_AREA, &mut sp));
        p.sweep();
        assert_eq!(p.len(), 0);
        p.push(&sq(5.0, 6.0), 1.0);
        assert!(!subtract(&mut p, 0, &sq(0.0, 4.0), MIN_AREA, &mut sp));
        p.sweep();
        assert_eq!(p.len(), 1);
        assert!(close(signed_area(p.get(0)), 1.0, 1e-12));
    }

    #[test]
    fn short_sides_are_dropped() {
        let mut p = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1e-12, 1e-13),
            DVec2::new(10.0, 0.0),
            DVec2::new(10.0, 10.0),
            DVec2::new(0.0, 10.0),
            DVec2::new(1e-13, 0.0),
        ];
        drop_short_sides(&mut p);
        assert_eq!(p.len(), 4, "{p:?}");
        assert!(close(signed_area(&p), 100.0, 1e-9));
        // A cover with a repeated corner still hides what it covers.
        let mut pieces = Pieces::default();
        let square = [
            DVec2::new(2.0, 2.0),
            DVec2::new(3.0, 2.0),
            DVec2::new(3.0, 3.0),
            DVec2::new(2.0, 3.0),
        ];
        pieces.push(&square, 1.0);
        let cover = [
            DVec2::new(0.0, 0.0),
            DVec2::new(10.0, 0.0),
            DVec2::new(10.0, 0.0),
            DVec2::new(10.0, 10.0),
            DVec2::new(0.0, 10.0),
        ];
        let mut sp = Split::default();
        assert!(subtract(&mut pieces, 0, &cover, MIN_AREA, &mut sp));
        pieces.sweep();
        assert_eq!(pieces.len(), 0);
    }

    #[test]
    fn a_box_seen_face_on_covers_its_square() {
        let w = boxes(&[(Pose::IDENTITY, [2.0, 2.0, 2.0])]);
        let k = Intrinsics::centered(640, 480, 500.0).unwrap();
        let v = view(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y, k);
        let a = projected_areas(&Scene::build(&w), &v);
        assert_eq!(a.len(), 1);
        // The front face z = 1 at depth 4: a square of side 2·500/4 = 250 pixels.
        assert!(close(a[0].whole, 250.0 * 250.0, 1e-6), "{:?}", a[0]);
        assert!(close(a[0].visible, 250.0 * 250.0, 1e-6), "{:?}", a[0]);
        let b = a[0].bbox.unwrap();
        assert!(close_box(b, [195.0, 115.0, 445.0, 365.0], 1e-9), "{b:?}");
    }

    #[test]
    fn a_box_half_out_of_the_window_shows_half() {
        let w = boxes(&[(Pose::IDENTITY, [2.0, 2.0, 2.0])]);
        // The principal point on the window's left side: the square straddles it.
        let k = Intrinsics::new(640, 480, 500.0, 500.0, 0.0, 240.0).unwrap();
        let v = view(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y, k);
        let a = projected_areas(&Scene::build(&w), &v);
        assert!(close(a[0].whole, 62_500.0, 1e-6), "{:?}", a[0]);
        assert!(close(a[0].visible, 31_250.0, 1e-6), "{:?}", a[0]);
        assert!(close_box(
            a[0].bbox.unwrap(),
            [0.0, 115.0, 125.0, 365.0],
            1e-9
        ));
    }

    #[test]
    fn a_box_behind_another_loses_the_overlap() {
        // Near box A: its front face z = 1 at depth 4. Far box B: front face z = −2 at
        // depth 7, its x and y ranges containing the eye's, so only that face is front.
        let w = boxes(&[
            (Pose::IDENTITY, [2.0, 2.0, 2.0]),
            (at(0.8, 0.5, -3.0), [2.0, 2.0, 2.0]),
        ]);
        let k = Intrinsics::centered(640, 480, 500.0).unwrap();
        let v = view(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y, k);
        let a = projected_areas(&Scene::build(&w), &v);
        let rect = |x0: f64, y0: f64, x1: f64, y1: f64, depth: f64| {
            let s = 500.0 / depth;
            [
                320.0 + s * x0,
                240.0 - s * y1,
                320.0 + s * x1,
                240.0 - s * y0,
            ]
        };
        let ra = rect(-1.0, -1.0, 1.0, 1.0, 4.0);
        let rb = rect(-0.2, -0.5, 1.8, 1.5, 7.0);
        let area = |r: [f64; 4]| (r[2] - r[0]) * (r[3] - r[1]);
        let overlap = area(intersect(ra, rb).unwrap());
        assert!(overlap > 0.5 * area(rb), "the set-up hides most of B");
        assert!(close(a[0].whole, area(ra), 1e-6));
        assert!(close(a[0].visible, area(ra), 1e-6));
        assert!(close(a[1].whole, area(rb), 1e-6), "{:?}", a[1]);
        assert!(
            close(a[1].visible, area(rb) - overlap, 1e-6),
            "{:?} vs {}",
            a[1],
            area(rb) - overlap
        );
        // B shows as the strip right of A.
        let strip = [ra[2], rb[1], rb[2], rb[3]];
        assert!(
            close_box(a[1].bbox.unwrap(), strip, 1e-9),
            "{:?} vs {strip:?}",
            a[1].bbox
        );
    }

    #[test]
    fn a_concave_prism_hiding_part_of_itself_covers_its_silhouette() {
        let mut w = World::new();
        let root = w.root();
        w.insert_with(None, root, Pose::IDENTITY, |s| {
            solids::prism_solid(s, &L_SHAPE, 1.0)
        })
        .unwrap();
        let k = Intrinsics::centered(640, 480, 400.0).unwrap();
        // From beyond the end of the x arm, a little to the side and above: the x arm
        // stands in front of the y arm.
        let v = view(
            DVec3::new(6.0, -1.5, 2.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::Z,
            k,
        );
        let scene = Scene::build(&w);
        let a = projected_areas(&scene, &v);
        let sum = front_area_sum(&scene, &v, 0);
        assert!(
            sum > 1.05 * a[0].whole,
            "the prism hides part of itself: {sum} vs {}",
            a[0].whole
        );
        let caster = Caster::new(&scene, &v);
        let estimate = caster.whole(0, 0.25);
        assert!(
            close(a[0].whole, estimate, 0.005 * estimate),
            "{} vs {estimate}",
            a[0].whole
        );
        // Wholly in the window: visible = whole.
        assert!(
            close(a[0].visible, a[0].whole, 1e-6 * a[0].whole),
            "{:?}",
            a[0]
        );
    }

    #[test]
    fn random_boxes_agree_with_cast_rays() {
        let (width, height) = (320u32, 240u32);
        let window = f64::from(width * height);
        let step = 0.5;
        let (mut whole_sum, mut visible_sum, mut cut_by_window) = (0.0, 0.0, 0);
        for seed in [11, 12, 13] {
            let mut rng = SplitMix64::new(seed);
            let list: Vec<(Pose, [f64; 3])> = (0..7)
                .map(|_| {
                    let position = DVec3::new(
                        rng.range(-5.0, 5.0),
                        rng.range(-2.0, 2.5),
                        rng.range(-0.5, 1.5),
                    );
                    let axis = DVec3::new(
                        rng.range(-1.0, 1.0),
                        rng.range(-1.0, 1.0),
                        rng.range(-1.0, 1.0),
                    )
                    .normalize();
                    let rotation =
                        DQuat::from_axis_angle(axis, rng.range(0.0, std::f64::consts::TAU));
                    let size = [
                        rng.range(0.4, 1.8),
                        rng.range(0.4, 1.8),
                        rng.range(0.4, 1.8),
                    ];
                    (Pose { position, rotation }, size)
                })
                .collect();
            let w = boxes(&list);
            let k = Intrinsics::centered(width, height, 380.0).unwrap();
            let v = view(
                DVec3::new(0.5, -8.0, 3.0),
                DVec3::new(0.0, 0.0, 0.5),
                DVec3::Z,
                k,
            );
            let scene = Scene::build(&w);
            let a = projected_areas(&scene, &v);
            assert_eq!(a.len(), list.len());
            let caster = Caster::new(&scene, &v);
            let seen = caster.visible(list.len(), step);
            for (b, (area, (estimate, sample_box))) in a.iter().zip(&seen).enumerate() {
                let whole = caster.whole(b as u32, step);
                assert!(
                    close(area.whole, whole, 0.005 * whole + 4.0),
                    "seed {seed}, body {b}: whole {} vs {whole}",
                    area.whole
                );
                assert!(
                    close(area.visible, *estimate, 0.01 * estimate + 4.0),
                    "seed {seed}, body {b}: visible {} vs {estimate}",
                    area.visible
                );
                assert!(area.visible <= area.whole * (1.0 + 1e-9));
                assert_eq!(area.bbox.is_some(), area.visible > 0.0);
                if let Some(bb) = area.bbox {
                    // Within the window, and around every sample the body owns.
                    assert!(bb[0] >= 0.0 && bb[1] >= 0.0);
                    assert!(bb[2] <= f64::from(width) && bb[3] <= f64::from(height));
                    let s = sample_box.unwrap();
                    assert!(
                        bb[0] <= s[0] && bb[1] <= s[1] && bb[2] >= s[2] && bb[3] >= s[3],
                        "{bb:?} {s:?}"
                    );
                    if bb[0] == 0.0 || bb[2] == f64::from(width) {
                        cut_by_window += 1;
                    }
                }
                whole_sum += area.whole;
                visible_sum += area.visible;
            }
            let visible: f64 = a.iter().map(|b| b.visible).sum();
            let covered: f64 = seen.iter().map(|s| s.0).sum();
            assert!(
                close(visible, covered, 0.002 * window),
                "seed {seed}: {visible} vs {covered}"
            );
            assert!(visible <= window * (1.0 + 1e-9));
        }
        // The scenes are a real test of occlusion and of the window.
        assert!(
            whole_sum > 1.2 * visible_sum,
            "{whole_sum} vs {visible_sum}"
        );
        assert!(
            cut_by_window >= 2,
            "{cut_by_window} bodies cut by the window"
        );
    }

    #[test]
    fn touching_boxes_neither_hide_nor_double_count() {
        // Three unit cubes in a row, touching face to face; their front faces z = 0.5
        // are coplanar, at depth 4.5. The outer cubes turn their inner sides to the eye,
        // behind the middle cube's front face.
        let w = boxes(&[
            (at(-1.0, 0.0, 0.0), [1.0, 1.0, 1.0]),
            (Pose::IDENTITY, [1.0, 1.0, 1.0]),
            (at(1.0, 0.0, 0.0), [1.0, 1.0, 1.0]),
        ]);
        let k = Intrinsics::centered(640, 480, 500.0).unwrap();
        let v = view(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y, k);
        let a = projected_areas(&Scene::build(&w), &v);
        let side = 500.0 / 4.5;
        let square = side * side;
        // The inner side x = ±0.5 between depths 4.5 and 5.5: a trapezoid.
        let trapezoid = 250.0 * (1.0 / 4.5 - 1.0 / 5.5) * (500.0 / 4.5 + 500.0 / 5.5) / 2.0;
        // Where a side meets the middle front face their depths differ by less than
        // DEPTH_TOL over a sliver about 1e-7 pixels wide: millionths of a pixel².
        for (b, whole) in [
            (0, square + trapezoid),
            (1, square),
            (2, square + trapezoid),
        ] {
            assert!(close(a[b].whole, whole, 1e-4), "body {b}: {:?}", a[b]);
            assert!(close(a[b].visible, square, 1e-4), "body {b}: {:?}", a[b]);
        }
        let (lo, hi) = (320.0 - side / 2.0, 320.0 + side / 2.0);
        let rows = (240.0 - side / 2.0, 240.0 + side / 2.0);
        let middle = a[1].bbox.unwrap();
        assert!(
            close_box(middle, [lo, rows.0, hi, rows.1], 1e-9),
            "{middle:?}"
        );
        let left = a[0].bbox.unwrap();
        assert!(
            close_box(left, [lo - side, rows.0, lo, rows.1], 1e-6),
            "{left:?}"
        );
    }

    #[test]
    fn a_camera_inside_a_box_sees_nothing_of_it() {
        let w = boxes(&[
            (Pose::IDENTITY, [2.0, 2.0, 2.0]),
            (at(0.0, 0.0, -6.0), [2.0, 2.0, 2.0]),
        ]);
        let k = Intrinsics::centered(640, 480, 500.0).unwrap();
        let v = view(
            DVec3::new(0.1, -0.2, 0.3),
            DVec3::new(0.1, -0.2, -6.0),
            DVec3::Y,
            k,
        );
        let a = projected_areas(&Scene::build(&w), &v);
        assert_eq!(a[0], BodyArea::NONE);
        // The other box's front face z = −5 at depth 5.3: seen through the first.
        let side = 2.0 * 500.0 / 5.3;
        assert!(close(a[1].whole, side * side, 1e-6), "{:?}", a[1]);
        assert!(close(a[1].visible, side * side, 1e-6), "{:?}", a[1]);
    }

    #[test]
    fn geometry_behind_or_across_the_near_plane_is_handled() {
        // A box behind the camera, and a wide slab under it reaching behind it.
        let w = boxes(&[
            (at(0.0, -8.0, 0.0), [2.0, 2.0, 2.0]),
            (at(0.0, 0.0, -1.5), [40.0, 40.0, 1.0]),
        ]);
        let k = Intrinsics::centered(320, 240, 200.0).unwrap();
        let v = view(
            DVec3::new(0.0, -2.0, 0.0),
            DVec3::new(0.0, 6.0, -1.0),
            DVec3::Z,
            k,
        );
        let scene = Scene::build(&w);
        let a = projected_areas(&scene, &v);
        assert_eq!(a[0], BodyArea::NONE);
        assert!(a[1].whole.is_finite() && a[1].whole > a[1].visible);
        let seen = Caster::new(&scene, &v).visible(2, 0.5);
        assert!(
            close(a[1].visible, seen[1].0, 0.002 * 320.0 * 240.0),
            "{:?} vs {:?}",
            a[1],
            seen[1]
        );
        assert!(a[1].visible > 0.2 * 320.0 * 240.0);
        // Degenerate input: an empty scene.
        assert!(projected_areas(&Scene::default(), &v).is_empty());
    }

    #[test]
    fn time_on_a_city_of_fifteen_bodies() {
        let mut w = blocks(12, 5).unwrap();
        let root = w.root();
        for (i, x) in [-2.5, 0.0, 2.5].into_iter().enumerate() {
            w.insert_with(None, root, at(x, 0.5 * i as f64, 1.5), |s| {
                solids::sphere(s, 1.0, 48, 24)
            })
            .unwrap();
        }
        let scene = Scene::build(&w);
        let cam = ring_cameras(15, 1, 640, 480)[0];
        let v = View::new(&cam, DEFAULT_NEAR);
        let front = scene
            .triangle_faces
            .iter()
            .filter(|&&f| scene.faces[f as usize].faces_toward(v.eye()))
            .count();
        let mut times = Vec::new();
        let mut a = Vec::new();
        for _ in 0..15 {
            let start = Instant::now();
            a = projected_areas(&scene, &v);
            times.push(start.elapsed().as_secs_f64() * 1e3);
        }
        times.sort_by(f64::total_cmp);
        let visible: f64 = a.iter().map(|b| b.visible).sum();
        println!(
            "projected_areas: {} bodies, {} triangles ({front} front), 640×480: median {:.2} ms, \
             best {:.2} ms; visible {visible:.0} px²",
            scene.bodies.len(),
            scene.triangles.len(),
            times[times.len() / 2],
            times[0],
        );
        assert_eq!(a.len(), 15);
        assert!(visible > 0.0 && visible <= 640.0 * 480.0 * (1.0 + 1e-9));
    }
}
