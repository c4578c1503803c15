//! One view carves a polyhedron: the polyhedron's intersection with the cone of rays from
//! the camera's centre through a silhouette.
//!
//! # Method
//!
//! Every point of the polyhedron `P` lies in front of the camera (the caller's
//! precondition), so projection maps `P`'s vertices, edges and faces to points, segments
//! and polygons of the image, and a ray from the centre meets the cone's walls exactly
//! where its pixel meets the silhouette's outline. Every decision is made in the image,
//! by Shewchuk's exact orientation of projected points (`robust`), so the decisions
//! agree with each other; points are then placed in space once each:
//!
//! * a vertex of `P` whose pixel is inside the silhouette stays;
//! * an edge of `P` whose projection crosses an outline edge gives a point on that edge
//!   of `P`, where it meets the wall's plane;
//! * an outline corner inside a face's projection gives the point where the corner's
//!   ray meets the face's plane.
//!
//! Each face of `P` keeps the part of it whose projection is inside the silhouette: the
//! pieces of its edges inside, and the pieces of the outline inside its projection,
//! linked into rings at the points above. Each outline edge makes a wall face from the
//! same outline pieces, reversed, and the segments of its end rays that lie inside `P`
//! (the ray enters `P` through a face turned toward the camera and leaves through one
//! turned away). Because each point is named by what defines it (a vertex; an edge and
//! an outline edge; an outline corner and a face), the faces share their points and
//! edges by construction.
//!
//! # Refusals
//!
//! A face or wall left around a hole (a winged-edge face is one ring) is cut into
//! rings without holes by chords ([`super::holes`]).
//!
//! Where the image decisions meet a degenerate configuration (a vertex's projection on
//! the outline, an edge through an outline corner, a face seen edge-on, rays that do
//! not alternate in and out), or no clear chord cuts a face around a hole, [`carve`]
//! refuses with [`Unsure`] and leaves the caller to use the general boolean. A refusal
//! changes nothing.

use crate::model::boolean::{Map, Set};

use glam::{DVec2, DVec3};
use robust::{Coord, orient2d};

use super::holes;
use super::mesh::{Maker, Mesh};
use crate::model::camera::Camera;

/// A face whose normal is this close to perpendicular to the line of sight (the cosine
/// of their angle) is taken as seen edge-on.
const EDGE_ON: f64 = 1e-9;

/// Why one view could not carve a polyhedron by the image method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Unsure {
    /// A vertex lies on or behind the plane of the camera's centre.
    #[error("vertex {vertex} is not in front of the camera")]
    Behind {
        /// The vertex.
        vertex: u32,
    },
    /// A projected vertex or edge touches the silhouette's outline.
    #[error("the polyhedron's projection touches the silhouette's outline")]
    Touching,
    /// A face's plane passes through the camera's centre.
    #[error("face {face} is seen edge-on")]
    EdgeOn {
        /// The face.
        face: u32,
    },
    /// The pieces of a face or a wall do not link into rings.
    #[error("the pieces of a face do not link into rings")]
    Tangled,
    /// A face or wall of the result would surround a hole that no clear chords cut.
    #[error("a face of the result surrounds a hole that no clear chords cut")]
    Hole,
}

/// A silhouette in pixels: rings with the silhouette on their left (turning from +u
/// toward +v): the outer ring of positive area first, then the holes.
///
/// Invariants: each ring has at least three points; rings neither cross nor touch.
#[derive(Clone, Debug, PartialEq)]
pub struct Outline {
    /// The rings.
    pub rings: Vec<Vec<DVec2>>,
}

/// The parts of `mesh` inside the cone of rays from `camera`'s centre through
/// `outline`, as connected pieces; walls are made by `view`.
///
/// Preconditions: `mesh` is closed, manifold, outward oriented, without cavities; every
/// vertex is in front of the camera (depth > 0).
///
/// Postconditions: each piece is closed, manifold and outward oriented; faces of
/// `mesh` keep their makers; the union of the pieces is `mesh ∩ cone` (the polyhedron
/// entirely inside gives itself back, entirely outside gives no piece). On `Err`,
/// nothing was made.
pub fn carve(
    mesh: &Mesh,
    camera: &Camera,
    outline: &Outline,
    view: u32,
) -> Result<Vec<Mesh>, Unsure> {
    let s = Flat::new(outline);
    let centre = camera.position();
    // Projected vertices and whether each is inside the silhouette.
    let mut uv = Vec::with_capacity(mesh.positions.len());
    for (i, p) in mesh.positions.iter().enumerate() {
        let c = camera.world_to_camera(*p);
        if c.z >= 0.0 || c.z.is_nan() {
            return Err(Unsure::Behind { vertex: i as u32 });
        }
        let k = &camera.intrinsics;
        uv.push(DVec2::new(
            k.cx + k.fx * c.x / -c.z,
            k.cy - k.fy * c.y / -c.z,
        ));
    }
    let inside: Vec<bool> = uv
        .iter()
        .map(|q| s.locate(*q).ok_or(Unsure::Touching))
        .collect::<Result<_, _>>()?;

    // Undirected edges of the mesh.
    let mut edge_ids: Map<(u32, u32), u32> = Map::default();
    let mut edge_ends: Vec<(u32, u32)> = Vec::new();
    for f in &mesh.faces {
        for k in 0..f.len() {
            let (a, b) = (f[k], f[(k + 1) % f.len()]);
            let key = (a.min(b), a.max(b));
            edge_ids.entry(key).or_insert_with(|| {
                edge_ends.push(key);
                (edge_ends.len() - 1) as u32
            });
        }
    }

    // Crossings of projected edges with outline edges.
    let mut crossings: Vec<Crossing> = Vec::new();
    let mut on_edge: Vec<Vec<u32>> = vec![Vec::new(); edge_ends.len()];
    let mut stamp = vec![u32::MAX; s.points.len()];
    for (e, &(a, b)) in edge_ends.iter().enumerate() {
        let (qa, qb) = (uv[a as usize], uv[b as usize]);
        let mut hit = |g: u32| -> Result<(), Unsure> {
            if stamp[g as usize] == e as u32 {
                return Ok(());
            }
            stamp[g as usize] = e as u32;
            let (sa, sb) = s.edge(g);
            if let Some((t, mu)) = cross(qa, qb, sa, sb)? {
                let n = s.wall_normal(camera, g);
                let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
                let lambda = (n.dot(centre - pa) / n.dot(pb - pa)).clamp(0.0, 1.0);
                on_edge[e].push(crossings.len() as u32);
                crossings.push(Crossing {
                    edge: e as u32,
                    outline: g,
                    t,
                    mu,
                    uv: qa + (qb - qa) * t,
                    at: pa + (pb - pa) * lambda,
                });
            }
            Ok(())
        };
        s.grid.each_edge_near(qa.min(qb), qa.max(qb), &mut hit)?;
    }
    for list in &mut on_edge {
        list.sort_by(|&x, &y| crossings[x as usize].t.total_cmp(&crossings[y as usize].t));
    }

    // Faces: projections, facing, and the outline corners inside each.
    let mut faces = Vec::with_capacity(mesh.faces.len());
    let mut rays: Vec<Vec<RayHit>> = vec![Vec::new(); s.points.len()];
    for (fi, f) in mesh.faces.iter().enumerate() {
        let ring: Vec<DVec2> = f.iter().map(|&v| uv[v as usize]).collect();
        let area2: f64 = (0..ring.len())
            .map(|k| ring[k].perp_dot(ring[(k + 1) % ring.len()]))
            .sum();
        let normal = newell(mesh, f);
        let middle = f.iter().map(|&v| mesh.positions[v as usize]).sum::<DVec3>() / f.len() as f64;
        let toward = normal.dot(centre - middle);
        let slant = toward / (normal.length() * (centre - middle).length());
        if slant.is_nan() {
            return Err(Unsure::EdgeOn { face: fi as u32 });
        }
        // Turned toward the camera, a face runs clockwise in (u, v), where v points down.
        // A face whose plane passes through the centre (a wall an earlier view from the
        // same place made) is seen edge-on: no outline corner is inside it, and it keeps
        // the part between the rays where its line in the image crosses the outline.
        if slant.abs() <= EDGE_ON || area2 == 0.0 || (toward > 0.0) != (area2 < 0.0) {
            faces.push(FaceView {
                sense: 0,
                corners: Vec::new(),
            });
            continue;
        }
        let (lo, hi) = ring
            .iter()
            .fold((ring[0], ring[0]), |(lo, hi), q| (lo.min(*q), hi.max(*q)));
        let mut corners = Vec::new();
        let mut err = None;
        s.grid.each_point_in(lo, hi, |g| {
            match locate_in_ring(&ring, s.points[g as usize]) {
                None => err = Some(Unsure::Touching),
                Some(true) => corners.push(g),
                Some(false) => {}
            }
        });
        if let Some(e) = err {
            return Err(e);
        }
        for &g in &corners {
            let r = camera.pixel_ray(s.points[g as usize]);
            let depth = normal.dot(middle - centre) / normal.dot(r);
            rays[g as usize].push(RayHit {
                face: fi as u32,
                depth,
                enters: toward > 0.0,
                at: centre + r * depth,
            });
        }
        faces.push(FaceView {
            sense: if area2 > 0.0 { 1 } else { -1 },
            corners,
        });
    }

    // Rings of each kept face, and the pieces of the outline along each wall.
    let mut keys = Keys::default();
    let mut out = Mesh::default();
    let mut walls: Vec<Vec<(Key, Key)>> = vec![Vec::new(); s.points.len()];
    for (fi, f) in mesh.faces.iter().enumerate() {
        let fv = &faces[fi];
        let mut pieces: Vec<(Key, Key)> = Vec::new();
        // Pieces of the face's own edges inside the silhouette.
        let mut along: Map<u32, Vec<u32>> = Map::default();
        for k in 0..f.len() {
            let (a, b) = (f[k], f[(k + 1) % f.len()]);
            let e = edge_ids[&(a.min(b), a.max(b))];
            let mut xs: Vec<u32> = on_edge[e as usize].clone();
            if a > b {
                xs.reverse();
            }
            let mut inside_now = inside[a as usize];
            let mut from = Key::Vertex(a);
            for &x in &xs {
                along
                    .entry(crossings[x as usize].outline)
                    .or_default()
                    .push(x);
                let to = Key::Cross(x);
                if inside_now {
                    pieces.push((from, to));
                }
                inside_now = !inside_now;
                from = to;
            }
            if inside_now != inside[b as usize] {
                return Err(Unsure::Tangled);
            }
            if inside_now {
                pieces.push((from, Key::Vertex(b)));
            }
        }
        // Pieces of the outline inside the face's projection.
        for &g in &fv.corners {
            along.entry(g).or_default();
            along.entry(s.prev[g as usize]).or_default();
        }
        let mut outline_edges: Vec<u32> = along.keys().copied().collect();
        outline_edges.sort_unstable();
        if fv.sense == 0 {
            // Seen edge-on: along each ray where the face's line crosses the outline,
            // the face's crossings pair up (in, out) by depth; each pair is an edge of
            // the face's part inside the cone, and of that outline edge's wall.
            let ends: Set<Key> = pieces.iter().map(|p| p.1).collect();
            for g in outline_edges {
                let mut xs = along.remove(&g).unwrap_or_default();
                xs.sort_by(|&x, &y| {
                    let d = |x: u32| (crossings[x as usize].at - centre).length();
                    d(x).total_cmp(&d(y))
                });
                if !xs.len().is_multiple_of(2) {
                    return Err(Unsure::Tangled);
                }
                for pair in xs.chunks(2) {
                    let (a, b) = (Key::Cross(pair[0]), Key::Cross(pair[1]));
                    let (a, b) = if ends.contains(&a) { (a, b) } else { (b, a) };
                    pieces.push((a, b));
                    walls[g as usize].push((b, a));
                }
            }
            let normal = newell(mesh, f).normalize();
            let e1 = normal.any_orthonormal_vector();
            let e2 = normal.cross(e1);
            let rings = holes::without_holes(link(&pieces)?, |k| {
                let p = position(k, mesh, &crossings, &rays);
                DVec2::new(p.dot(e1), p.dot(e2))
            })
            .ok_or(Unsure::Hole)?;
            for ring in rings {
                push_face(&mut out, &mut keys, &ring, mesh.makers[fi], |k| {
                    position(k, mesh, &crossings, &rays)
                });
            }
            continue;
        }
        for g in outline_edges {
            let mut xs = along.remove(&g).unwrap_or_default();
            xs.sort_by(|&x, &y| {
                crossings[x as usize]
                    .mu
                    .total_cmp(&crossings[y as usize].mu)
            });
            let next = s.next[g as usize];
            let start_in = fv.corners.contains(&g);
            let end_in = fv.corners.contains(&next);
            let mut chain: Vec<(Key, Key)> = Vec::new();
            let mut inside_now = start_in;
            let mut from = Key::Ray(g, fi as u32);
            for &x in &xs {
                let to = Key::Cross(x);
                if inside_now {
                    chain.push((from, to));
                }
                inside_now = !inside_now;
                from = to;
            }
            if inside_now != end_in {
                return Err(Unsure::Tangled);
            }
            if inside_now {
                chain.push((from, Key::Ray(next, fi as u32)));
            }
            for (a, b) in chain {
                let (a, b) = if fv.sense > 0 { (a, b) } else { (b, a) };
                pieces.push((a, b));
                walls[g as usize].push((b, a));
            }
        }
        // In the image with v mirrored for faces turned toward the camera, the face's
        // outer rings turn counter-clockwise and its holes clockwise.
        let mirror = DVec2::new(1.0, f64::from(fv.sense));
        let rings = holes::without_holes(link(&pieces)?, |k| {
            Keys::uv(*k, &uv, &crossings, &s) * mirror
        })
        .ok_or(Unsure::Hole)?;
        for ring in rings {
            push_face(&mut out, &mut keys, &ring, mesh.makers[fi], |k| {
                position(k, mesh, &crossings, &rays)
            });
        }
    }

    // Segments of each outline corner's ray inside the mesh.
    for (g, hits) in rays.iter_mut().enumerate() {
        hits.sort_by(|a, b| a.depth.total_cmp(&b.depth));
        if hits.len() % 2 != 0 {
            return Err(Unsure::Tangled);
        }
        let prev = s.prev[g] as usize;
        for pair in hits.chunks(2) {
            if !pair[0].enters || pair[1].enters {
                return Err(Unsure::Tangled);
            }
            let entry = Key::Ray(g as u32, pair[0].face);
            let exit = Key::Ray(g as u32, pair[1].face);
            // Wall g starts at corner g; the wall before it ends there.
            walls[g].push((exit, entry));
            walls[prev].push((entry, exit));
        }
    }
    for (g, pieces) in walls.iter().enumerate() {
        if pieces.is_empty() {
            continue;
        }
        let mut rings = link(pieces)?;
        if rings.len() > 1 {
            // Outer rings turn like the largest ring; coordinates in the wall's plane
            // that make them counter-clockwise.
            let at = |k: &Key| position(k, mesh, &crossings, &rays);
            let normal = s.wall_normal(camera, g as u32).normalize();
            let largest = rings
                .iter()
                .map(|r| ring_vector_area(r, at).dot(normal))
                .max_by(|a, b| a.abs().total_cmp(&b.abs()))
                .unwrap_or(1.0);
            let up = if largest > 0.0 { normal } else { -normal };
            let e1 = up.any_orthonormal_vector();
            let e2 = up.cross(e1);
            rings = holes::without_holes(rings, |k| {
                let p = at(k);
                DVec2::new(p.dot(e1), p.dot(e2))
            })
            .ok_or(Unsure::Hole)?;
        }
        let (ring, edge) = s.ring_of[g];
        let maker = Maker::Wall { view, ring, edge };
        for ring in rings {
            push_face(&mut out, &mut keys, &ring, maker, |k| {
                position(k, mesh, &crossings, &rays)
            });
        }
    }
    check_closed(&out)?;
    Ok(out.pieces())
}

/// A point of the result, named by what defines it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Key {
    /// A vertex of the mesh carved.
    Vertex(u32),
    /// A crossing of a mesh edge with an outline edge.
    Cross(u32),
    /// The ray through an outline corner meeting a face.
    Ray(u32, u32),
}

/// Where a mesh edge's projection crosses an outline edge.
struct Crossing {
    #[allow(dead_code)]
    edge: u32,
    outline: u32,
    /// Parameter along the mesh edge's projection, from its lesser vertex.
    t: f64,
    /// Parameter along the outline edge.
    mu: f64,
    uv: DVec2,
    at: DVec3,
}

/// Where the ray through an outline corner meets a face.
#[derive(Clone, Copy)]
struct RayHit {
    face: u32,
    depth: f64,
    /// The face is turned toward the camera: the ray enters the mesh there.
    enters: bool,
    at: DVec3,
}

struct FaceView {
    /// +1 where the projected ring turns from +u toward +v, −1 the other way, 0 for a
    /// face seen edge-on.
    sense: i8,
    /// The outline corners inside the projection.
    corners: Vec<u32>,
}

/// The result's vertices, numbered as they are first used.
#[derive(Default)]
struct Keys {
    index: Map<Key, u32>,
}

impl Keys {
    fn uv(k: Key, uv: &[DVec2], crossings: &[Crossing], s: &Flat) -> DVec2 {
        match k {
            Key::Vertex(v) => uv[v as usize],
            Key::Cross(x) => crossings[x as usize].uv,
            Key::Ray(g, _) => s.points[g as usize],
        }
    }
}

fn position(k: &Key, mesh: &Mesh, crossings: &[Crossing], rays: &[Vec<RayHit>]) -> DVec3 {
    match *k {
        Key::Vertex(v) => mesh.positions[v as usize],
        Key::Cross(x) => crossings[x as usize].at,
        Key::Ray(g, f) => rays[g as usize]
            .iter()
            .find(|h| h.face == f)
            .map(|h| h.at)
            .unwrap_or(DVec3::NAN),
    }
}

fn push_face(
    out: &mut Mesh,
    keys: &mut Keys,
    ring: &[Key],
    maker: Maker,
    at: impl Fn(&Key) -> DVec3,
) {
    let face = ring
        .iter()
        .map(|k| {
            *keys.index.entry(*k).or_insert_with(|| {
                out.positions.push(at(k));
                (out.positions.len() - 1) as u32
            })
        })
        .collect();
    out.faces.push(face);
    out.makers.push(maker);
}

/// Directed pieces linked into rings: each point must start exactly one piece.
fn link(pieces: &[(Key, Key)]) -> Result<Vec<Vec<Key>>, Unsure> {
    let mut next: Map<Key, Key> = Map::with_capacity_and_hasher(pieces.len(), Default::default());
    for &(a, b) in pieces {
        if next.insert(a, b).is_some() {
            return Err(Unsure::Tangled);
        }
    }
    let mut rings = Vec::new();
    let mut order: Vec<Key> = pieces.iter().map(|p| p.0).collect();
    order.dedup();
    for start in order {
        let Some(mut at) = next.remove(&start) else {
            continue;
        };
        let mut ring = vec![start];
        while at != start {
            ring.push(at);
            at = next.remove(&at).ok_or(Unsure::Tangled)?;
        }
        if ring.len() < 3 {
            return Err(Unsure::Tangled);
        }
        rings.push(ring);
    }
    Ok(rings)
}

/// Twice the vector area of a ring of space points (Newell).
fn ring_vector_area<K>(ring: &[K], at: impl Fn(&K) -> DVec3) -> DVec3 {
    let pts: Vec<DVec3> = ring.iter().map(at).collect();
    let o = pts[0];
    (1..pts.len() - 1)
        .map(|k| (pts[k] - o).cross(pts[k + 1] - o))
        .sum()
}

fn newell(mesh: &Mesh, f: &[u32]) -> DVec3 {
    ring_vector_area(f, |&v| mesh.positions[v as usize])
}

/// Every directed edge once, and its reverse once.
fn check_closed(mesh: &Mesh) -> Result<(), Unsure> {
    let mut seen = Set::default();
    for f in &mesh.faces {
        for k in 0..f.len() {
            if !seen.insert((f[k], f[(k + 1) % f.len()])) {
                return Err(Unsure::Tangled);
            }
        }
    }
    if seen.iter().all(|&(a, b)| seen.contains(&(b, a))) {
        Ok(())
    } else {
        Err(Unsure::Tangled)
    }
}

fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    orient2d(
        Coord { x: a.x, y: a.y },
        Coord { x: b.x, y: b.y },
        Coord { x: c.x, y: c.y },
    )
}

/// Where segment `qa qb` properly crosses segment `sa sb`: the parameters along each;
/// `None` when they do not meet; refused when they touch.
fn cross(qa: DVec2, qb: DVec2, sa: DVec2, sb: DVec2) -> Result<Option<(f64, f64)>, Unsure> {
    if qa.max(qb).cmplt(sa.min(sb)).any() || sa.max(sb).cmplt(qa.min(qb)).any() {
        return Ok(None);
    }
    let (o1, o2) = (orient(sa, sb, qa), orient(sa, sb, qb));
    if (o1 > 0.0 && o2 > 0.0) || (o1 < 0.0 && o2 < 0.0) {
        return Ok(None);
    }
    let (o3, o4) = (orient(qa, qb, sa), orient(qa, qb, sb));
    if (o3 > 0.0 && o4 > 0.0) || (o3 < 0.0 && o4 < 0.0) {
        return Ok(None);
    }
    if o1 == 0.0 || o2 == 0.0 || o3 == 0.0 || o4 == 0.0 {
        return Err(Unsure::Touching);
    }
    let (d, e, w) = (qb - qa, sb - sa, sa - qa);
    let den = d.perp_dot(e);
    Ok(Some((
        (w.perp_dot(e) / den).clamp(0.0, 1.0),
        (w.perp_dot(d) / den).clamp(0.0, 1.0),
    )))
}

/// Whether `q` is inside a ring (either orientation), exactly; `None` on its boundary.
fn locate_in_ring(ring: &[DVec2], q: DVec2) -> Option<bool> {
    let mut inside = false;
    for k in 0..ring.len() {
        let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
        if let Some(flip) = ray_crossing(a, b, q) {
            inside ^= flip;
        } else {
            return None;
        }
    }
    Some(inside)
}

/// Whether the ray from `q` toward +u crosses edge `a b` (half-open in v); `None` when
/// `q` is on the edge.
#[inline]
fn ray_crossing(a: DVec2, b: DVec2, q: DVec2) -> Option<bool> {
    let within = q.cmpge(a.min(b)).all() && q.cmple(a.max(b)).all();
    let straddles = (a.y > q.y) != (b.y > q.y);
    if !within && !straddles {
        return Some(false);
    }
    let o = orient(a, b, q);
    if o == 0.0 && within {
        return None;
    }
    Some(straddles && ((b.y > a.y && o > 0.0) || (b.y < a.y && o < 0.0)))
}

/// The outline flattened: corner `g` starts edge `g`, which ends at corner `next[g]`.
struct Flat {
    points: Vec<DVec2>,
    next: Vec<u32>,
    prev: Vec<u32>,
    /// The ring and the edge within it of each flat edge.
    ring_of: Vec<(u32, u32)>,
    grid: Grid,
}

impl Flat {
    fn new(outline: &Outline) -> Flat {
        let mut points = Vec::new();
        let (mut next, mut prev, mut ring_of) = (Vec::new(), Vec::new(), Vec::new());
        for (r, ring) in outline.rings.iter().enumerate() {
            let base = points.len() as u32;
            let n = ring.len() as u32;
            for (k, p) in ring.iter().enumerate() {
                let k = k as u32;
                points.push(*p);
                next.push(base + (k + 1) % n);
                prev.push(base + (k + n - 1) % n);
                ring_of.push((r as u32, k));
            }
        }
        let grid = Grid::new(&points, &next);
        Flat {
            points,
            next,
            prev,
            ring_of,
            grid,
        }
    }

    fn edge(&self, g: u32) -> (DVec2, DVec2) {
        (
            self.points[g as usize],
            self.points[self.next[g as usize] as usize],
        )
    }

    /// A normal of wall `g`'s plane (through the centre and the edge's two rays).
    fn wall_normal(&self, camera: &Camera, g: u32) -> DVec3 {
        let (a, b) = self.edge(g);
        camera.pixel_ray(a).cross(camera.pixel_ray(b))
    }

    /// Whether `q` is inside the silhouette, exactly; `None` on the outline.
    fn locate(&self, q: DVec2) -> Option<bool> {
        let mut inside = false;
        let mut on = false;
        self.grid.each_edge_right_of(q, |g| {
            let (a, b) = self.edge(g);
            match ray_crossing(a, b, q) {
                Some(flip) => inside ^= flip,
                None => on = true,
            }
        });
        (!on).then_some(inside)
    }
}

/// A uniform grid over the outline's bounding box: the edges whose boxes meet each cell,
/// and the corners in each cell.
struct Grid {
    lo: DVec2,
    hi: DVec2,
    inv: f64,
    nx: usize,
    ny: usize,
    edges: Vec<Vec<u32>>,
    corners: Vec<Vec<u32>>,
    stamp: std::cell::RefCell<(u32, Vec<u32>)>,
}

impl Grid {
    fn new(points: &[DVec2], next: &[u32]) -> Grid {
        let (lo, hi) = points.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let size = (hi - lo).max(DVec2::splat(1e-9));
        let cells = (points.len() as f64).sqrt().ceil().max(1.0);
        let cell = size.max_element() / cells;
        let inv = 1.0 / cell;
        let nx = ((size.x * inv) as usize + 1).min(4096);
        let ny = ((size.y * inv) as usize + 1).min(4096);
        let mut grid = Grid {
            lo,
            hi,
            inv,
            nx,
            ny,
            edges: vec![Vec::new(); nx * ny],
            corners: vec![Vec::new(); nx * ny],
            stamp: std::cell::RefCell::new((0, vec![0; points.len()])),
        };
        for (g, p) in points.iter().enumerate() {
            let q = points[next[g] as usize];
            let ((x0, y0), (x1, y1)) = (grid.cell(p.min(q)), grid.cell(p.max(q)));
            for y in y0..=y1 {
                for x in x0..=x1 {
                    grid.edges[y * nx + x].push(g as u32);
                }
            }
            let (x, y) = grid.cell(*p);
            grid.corners[y * nx + x].push(g as u32);
        }
        grid
    }

    fn cell(&self, p: DVec2) -> (usize, usize) {
        let c = ((p - self.lo) * self.inv).max(DVec2::ZERO);
        (
            (c.x as usize).min(self.nx - 1),
            (c.y as usize).min(self.ny - 1),
        )
    }

    fn misses(&self, lo: DVec2, hi: DVec2) -> bool {
        hi.cmplt(self.lo).any() || lo.cmpgt(self.hi).any()
    }

    /// Calls `f` once for each edge whose cell range meets the box `lo..hi`.
    fn each_edge_near(
        &self,
        lo: DVec2,
        hi: DVec2,
        f: &mut impl FnMut(u32) -> Result<(), Unsure>,
    ) -> Result<(), Unsure> {
        if self.misses(lo, hi) {
            return Ok(());
        }
        let ((x0, y0), (x1, y1)) = (self.cell(lo), self.cell(hi));
        for y in y0..=y1 {
            for x in x0..=x1 {
                for &g in &self.edges[y * self.nx + x] {
                    f(g)?;
                }
            }
        }
        Ok(())
    }

    /// Calls `f` for each corner in the box `lo..hi` (and perhaps a few near it).
    fn each_point_in(&self, lo: DVec2, hi: DVec2, mut f: impl FnMut(u32)) {
        if self.misses(lo, hi) {
            return;
        }
        let ((x0, y0), (x1, y1)) = (self.cell(lo), self.cell(hi));
        for y in y0..=y1 {
            for x in x0..=x1 {
                for &g in &self.corners[y * self.nx + x] {
                    f(g);
                }
            }
        }
    }

    /// Calls `f` once for each edge that may meet the ray from `q` toward +u or contain
    /// `q`.
    fn each_edge_right_of(&self, q: DVec2, mut f: impl FnMut(u32)) {
        if q.y < self.lo.y || q.y > self.hi.y || q.x > self.hi.x {
            return;
        }
        let (x0, y) = self.cell(q);
        let mut stamp = self.stamp.borrow_mut();
        stamp.0 = stamp.0.wrapping_add(1);
        let mark = stamp.0;
        for x in x0..self.nx {
            for &g in &self.edges[y * self.nx + x] {
                if stamp.1[g as usize] != mark {
                    stamp.1[g as usize] = mark;
                    f(g);
                }
            }
        }
    }
}
