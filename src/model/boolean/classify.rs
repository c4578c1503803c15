//! Which pieces of one surface lie inside the other, outside it, or on it.
//!
//! The traces cut each surface into regions that the other surface does not cross, so
//! a whole region has one class. Pieces are joined into regions across every edge that
//! is not a trace; one point inside one piece of each region is then classified
//! exactly: on the other surface if it lies in one of its triangles (facing the same
//! way or the opposite way), else inside or outside by the winding number of a ray
//! whose direction is perturbed symbolically, so that it never grazes an edge or a
//! vertex.

use super::{Map, Set};

use super::BooleanError;
use super::intersect::{EdgeKey, Traces, edge_key};
use super::mesh::Mesh;
use super::point::{Def, Pid, Points};
use super::sets::Sets;
use super::split::{cut, dominant_axis};

/// Where a piece of one surface lies with respect to the other operand.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Class {
    /// Outside the other's interior.
    Out,
    /// Inside the other's interior.
    In,
    /// On the other's surface, facing the same way.
    OnSame,
    /// On the other's surface, facing the opposite way.
    OnOpposite,
}

/// One operand's surface cut into pieces.
#[derive(Debug, Default)]
pub(crate) struct Pieces {
    /// The pieces, counter-clockwise seen from outside the operand.
    pub tris: Vec<[Pid; 3]>,
    /// The operand's triangle each piece is part of.
    pub source: Vec<u32>,
    /// The edges among pieces that lie on the other surface.
    pub traced: Set<EdgeKey>,
}

/// Cuts every triangle of `mesh` that the traces touch.
pub(crate) fn pieces(
    pts: &Points,
    mesh: &Mesh,
    segs: &Map<u32, Vec<[Pid; 2]>>,
    traces: &Traces,
) -> Result<Pieces, BooleanError> {
    let mut out = Pieces::default();
    let mut extra: Vec<(Pid, u8)> = Vec::new();
    for (i, &tri) in mesh.tris.iter().enumerate() {
        extra.clear();
        for k in 0..3 {
            if let Some(on) = traces.on_edge.get(&edge_key(tri[k], tri[(k + 1) % 3])) {
                extra.extend(on.iter().map(|&p| (p, 1u8 << k)));
            }
        }
        let mine = segs.get(&(i as u32));
        if let Some(s) = mine {
            for seg in s {
                extra.extend(seg.iter().map(|&p| (p, 0u8)));
            }
        }
        if extra.is_empty() && mine.is_none() {
            out.tris.push(tri);
            out.source.push(i as u32);
            continue;
        }
        let no_segs = Vec::new();
        let c = cut(pts, tri, &extra, mine.unwrap_or(&no_segs)).map_err(|_| {
            BooleanError::Unresolved {
                what: "a triangle could not be cut along the traces on it",
            }
        })?;
        out.traced.extend(c.traced);
        for p in c.pieces {
            out.tris.push(p);
            out.source.push(i as u32);
        }
    }
    Ok(out)
}

/// The class of every piece of `mine` with respect to `other`.
pub(crate) fn classify(
    pts: &mut Points,
    pieces: &Pieces,
    mine: &Mesh,
    other: &Mesh,
) -> Result<Vec<Class>, BooleanError> {
    let n = pieces.tris.len();
    let mut sets = Sets::new(n);
    let mut by_edge: Map<(Pid, Pid), u32> =
        Map::with_capacity_and_hasher(3 * n, Default::default());
    for (i, t) in pieces.tris.iter().enumerate() {
        for k in 0..3 {
            by_edge.insert((t[k], t[(k + 1) % 3]), i as u32);
        }
    }
    for (i, t) in pieces.tris.iter().enumerate() {
        for k in 0..3 {
            let (p, q) = (t[k], t[(k + 1) % 3]);
            if p > q || pieces.traced.contains(&edge_key(p, q)) {
                continue;
            }
            if let Some(&j) = by_edge.get(&(q, p)) {
                sets.join(i as u32, j);
            }
        }
    }
    let mut class_of_root: Map<u32, Class> = Map::default();
    let mut classes = Vec::with_capacity(n);
    for i in 0..n {
        let r = sets.find(i as u32);
        let c = match class_of_root.get(&r) {
            Some(&c) => c,
            None => {
                let c = classify_piece(pts, pieces, i, mine, other)?;
                class_of_root.insert(r, c);
                c
            }
        };
        classes.push(c);
    }
    Ok(classes)
}

/// Weights of the points tried inside a piece, until one does not touch the other
/// surface at an isolated point.
const WEIGHTS: [[u8; 3]; 6] = [
    [1, 1, 1],
    [1, 2, 3],
    [3, 1, 2],
    [2, 3, 1],
    [1, 3, 7],
    [7, 1, 3],
];

fn classify_piece(
    pts: &mut Points,
    pieces: &Pieces,
    i: usize,
    mine: &Mesh,
    other: &Mesh,
) -> Result<Class, BooleanError> {
    let tri = pieces.tris[i];
    let src = mine.tris[pieces.source[i] as usize];
    for w in WEIGHTS {
        let x = pts.add(Def::Mix { p: tri, w });
        if let Some(c) = classify_point(pts, x, src, other) {
            return Ok(c);
        }
    }
    Err(BooleanError::Unresolved {
        what: "no point of a piece could be classified",
    })
}

/// The class of point `x` (inside a triangle `src` of its own surface) with respect to
/// `other`; `None` if `x` touches `other`'s surface where the two are not coplanar.
fn classify_point(pts: &Points, x: Pid, src: [Pid; 3], other: &Mesh) -> Option<Class> {
    let c = pts.approx[x as usize];
    let m = pts.slack[x as usize] + 1e-300;
    let mut winding = 0i32;
    for (t, b) in other.tris.iter().zip(&other.boxes) {
        if b[1].x < c.x - m
            || b[0].y > c.y + m
            || b[1].y < c.y - m
            || b[0].z > c.z + m
            || b[1].z < c.z - m
        {
            continue;
        }
        let s = pts.side(*t, x);
        if s == 0 {
            let axis = dominant_axis(pts, *t);
            let sense = pts.orient2d(axis, *t);
            let inside = (0..3).all(|k| pts.orient2d(axis, [t[k], t[(k + 1) % 3], x]) * sense >= 0);
            if inside {
                if src.iter().all(|&p| pts.side(*t, p) == 0) {
                    let same = pts.orient2d(axis, src) == sense;
                    return Some(if same {
                        Class::OnSame
                    } else {
                        Class::OnOpposite
                    });
                }
                return None;
            }
            continue;
        }
        if let Some(sigma) = pts.ray_crosses(x, *t) {
            winding += sigma as i32;
        }
    }
    let inside = winding + i32::from(other.everted) > 0;
    Some(if inside { Class::In } else { Class::Out })
}
