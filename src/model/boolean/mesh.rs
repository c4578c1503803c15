//! The operands as closed triangle meshes over one table of points.
//!
//! Each face (a polygon, possibly concave and, after rounding, a hair off planar) is cut
//! into triangles of its own vertices by ear clipping with exact orientations in the
//! projection along the face's dominant normal axis; no triangle has zero area in that
//! projection. The triangles, not the polygon, are the surface the boolean works on:
//! each is exactly planar, so every decision is exact. The triangles of one face are
//! merged back into polygons at the end.
//!
//! Loci equal in both operands become one point, so shared vertices, edges and faces
//! are recognised by ids, not by tolerances.

use super::Map;

use glam::DVec3;

use super::point::{Pid, Points};
use super::sets::Sets;
use super::{BooleanError, Operand, Which};
use crate::model::ids::Serial;

/// One operand as triangles.
#[derive(Debug, Default)]
pub(crate) struct Mesh {
    /// Triangles, counter-clockwise seen from outside.
    pub tris: Vec<[Pid; 3]>,
    /// The input face (serial) of each triangle.
    pub face: Vec<Serial>,
    /// The bounding box of each triangle (of its input loci, exact).
    pub boxes: Vec<[DVec3; 2]>,
    /// Whether the operand is everted (its interior is unbounded).
    pub everted: bool,
}

/// Reads both operands into one point table and two meshes.
pub(crate) fn meshes(a: Operand<'_>, b: Operand<'_>) -> Result<(Points, Mesh, Mesh), BooleanError> {
    let mut pts = Points::default();
    let mut index: Map<[u64; 3], Pid> = Map::default();
    let ma = mesh(&mut pts, &mut index, a, Which::A)?;
    let mb = mesh(&mut pts, &mut index, b, Which::B)?;
    Ok((pts, ma, mb))
}

fn key(p: DVec3) -> [u64; 3] {
    // + 0.0 makes −0.0 into 0.0, so equal loci have equal bits.
    [
        (p.x + 0.0).to_bits(),
        (p.y + 0.0).to_bits(),
        (p.z + 0.0).to_bits(),
    ]
}

fn mesh(
    pts: &mut Points,
    index: &mut Map<[u64; 3], Pid>,
    op: Operand<'_>,
    which: Which,
) -> Result<Mesh, BooleanError> {
    let body = op.body;
    closed(body, which)?;
    let mut pid = vec![u32::MAX; body.vertices.slots()];
    for v in body.vertices() {
        let p = op.place.transform_point3(body.position(v));
        if !p.is_finite() {
            return Err(BooleanError::NonFinite { operand: which });
        }
        let p = p + DVec3::ZERO;
        let id = *index.entry(key(p)).or_insert_with(|| pts.add_input(p));
        pid[v.index()] = id;
    }
    let mut m = Mesh::default();
    let mut ring: Vec<Pid> = Vec::new();
    let mut six_volume = 0.0;
    let mut first_tri = vec![u32::MAX; body.faces.slots()];
    for f in body.faces() {
        ring.clear();
        ring.extend(body.face_vertices(f).map(|v| pid[v.index()]));
        let serial = body.face_serial(f);
        let first = m.tris.len();
        first_tri[f.index()] = first as u32;
        triangulate(pts, &ring, &mut m.tris).map_err(|()| BooleanError::BadFace {
            operand: which,
            face: serial,
        })?;
        for t in &m.tris[first..] {
            let [p, q, r] = t.map(|i| pts.approx[i as usize]);
            six_volume += p.dot(q.cross(r));
            m.face.push(serial);
            m.boxes.push([p.min(q).min(r), p.max(q).max(r)]);
        }
    }
    merge_flat_neighbours(pts, body, &pid, &first_tri, &mut m);
    m.everted = six_volume < 0.0;
    Ok(m)
}

/// Faces of the body that meet along an edge and lie in one plane (exactly) are one
/// face to the boolean: their triangles take the serial of the first of them, so their
/// pieces merge into one polygon. (A face split by an earlier boolean around a hole
/// would otherwise keep its cut, and every later cut across it would leave a corner
/// there.)
fn merge_flat_neighbours(
    pts: &Points,
    body: &crate::model::Body,
    pid: &[Pid],
    first_tri: &[u32],
    m: &mut Mesh,
) {
    let mut sets = Sets::new(body.faces.slots());
    let mut any = false;
    for e in body.edges() {
        let [f, g] = body.edge(e).face;
        if f == g {
            continue;
        }
        let tri = m.tris[first_tri[f.index()] as usize];
        if body
            .face_vertices(g)
            .all(|v| pts.side(tri, pid[v.index()]) == 0)
        {
            any |= sets.join(f.index() as u32, g.index() as u32);
        }
    }
    if !any {
        return;
    }
    // The smallest serial of each group stands for it.
    let mut name: Map<u32, Serial> = Map::default();
    for f in body.faces() {
        let r = sets.find(f.index() as u32);
        let s = body.face_serial(f);
        name.entry(r)
            .and_modify(|n| {
                if s.0 < n.0 {
                    *n = s;
                }
            })
            .or_insert(s);
    }
    let mut of_serial: Map<Serial, Serial> = Map::default();
    for f in body.faces() {
        of_serial.insert(body.face_serial(f), name[&sets.find(f.index() as u32)]);
    }
    for s in &mut m.face {
        *s = of_serial[s];
    }
}

/// Refuses a body that does not bound a volume: no faces, fewer than four, an edge with
/// one face on both sides (a wire or a spur), or a face of fewer than three vertices.
fn closed(body: &crate::model::Body, which: Which) -> Result<(), BooleanError> {
    let not = |why: String| BooleanError::NotClosed {
        operand: which,
        why,
    };
    if body.face_count() < 4 {
        return Err(not(format!(
            "it has {} face(s); a closed solid has at least 4",
            body.face_count()
        )));
    }
    for e in body.edges() {
        let r = body.edge(e);
        if r.face[0] == r.face[1] {
            return Err(not(format!(
                "edge {} has face {} on both sides",
                body.edge_serial(e),
                body.face_serial(r.face[0])
            )));
        }
    }
    for f in body.faces() {
        let n = body.face_vertices(f).count();
        if n < 3 {
            return Err(not(format!(
                "face {} has {} vertices",
                body.face_serial(f),
                n
            )));
        }
    }
    Ok(())
}

/// Cuts the polygon `ring` (counter-clockwise seen from outside) into triangles of its
/// own vertices, appended to `out`. Refused (`Err`) if the ring repeats a point or its
/// projection is not a simple polygon of non-zero area.
fn triangulate(pts: &Points, ring: &[Pid], out: &mut Vec<[Pid; 3]>) -> Result<(), ()> {
    let n = ring.len();
    {
        let mut sorted = ring.to_vec();
        sorted.sort_unstable();
        if sorted.windows(2).any(|w| w[0] == w[1]) {
            return Err(());
        }
    }
    if n == 3 {
        out.push([ring[0], ring[1], ring[2]]);
        return Ok(());
    }
    // Dominant axis of Newell's normal, and the sense the ring turns in that projection.
    let mut normal = DVec3::ZERO;
    for i in 0..n {
        let a = pts.approx[ring[i] as usize];
        let b = pts.approx[ring[(i + 1) % n] as usize];
        normal += DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let abs = normal.abs();
    let axis: u8 = if abs.x >= abs.y && abs.x >= abs.z {
        0
    } else if abs.y >= abs.z {
        1
    } else {
        2
    };
    let sense: i8 = if normal[axis as usize] >= 0.0 { 1 } else { -1 };
    let turn = |p: Pid, q: Pid, r: Pid| pts.orient2d(axis, [p, q, r]) * sense;
    // A strictly convex polygon (the common case) is a fan.
    if (0..n).all(|i| turn(ring[i], ring[(i + 1) % n], ring[(i + 2) % n]) > 0) {
        for i in 1..n - 1 {
            out.push([ring[0], ring[i], ring[i + 1]]);
        }
        return Ok(());
    }
    // Ear clipping: an ear is strictly convex and holds no other vertex, not even on its
    // boundary.
    let mut poly: Vec<Pid> = ring.to_vec();
    let mut guard = 0usize;
    let mut i = 0usize;
    while poly.len() > 3 {
        let m = poly.len();
        let (p, q, r) = (poly[(i + m - 1) % m], poly[i % m], poly[(i + 1) % m]);
        let ear = turn(p, q, r) > 0
            && poly.iter().all(|&x| {
                x == p
                    || x == q
                    || x == r
                    || !(turn(p, q, x) >= 0 && turn(q, r, x) >= 0 && turn(r, p, x) >= 0)
            });
        if ear {
            out.push([p, q, r]);
            poly.remove(i % m);
            guard = 0;
            i %= poly.len();
        } else {
            i = (i + 1) % m;
            guard += 1;
            if guard > m {
                return Err(());
            }
        }
    }
    if turn(poly[0], poly[1], poly[2]) <= 0 {
        return Err(());
    }
    out.push([poly[0], poly[1], poly[2]]);
    Ok(())
}
