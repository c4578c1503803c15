//! Helpers shared by the kernel tests: exact dumps and canonical topology of a body.

#![allow(dead_code)]

use std::collections::BTreeMap;

use glam::DVec3;
use winged::model::{Body, FaceId, check_topology};

/// Everything observable about a body, by serial number: for an exact "unchanged" test.
#[derive(Debug, PartialEq)]
pub struct Dump {
    faces: Vec<(u64, u64)>,
    edges: Vec<(u64, [u64; 8])>,
    vertices: Vec<(u64, [u64; 3], u64)>,
    handles: u32,
}

pub fn dump(b: &Body) -> Dump {
    let es = |e: winged::model::EdgeId| b.edge_serial(e).get();
    let mut faces: Vec<_> = b
        .faces()
        .map(|f| (b.face_serial(f).get(), es(b.face(f).ped)))
        .collect();
    let mut edges: Vec<_> = b
        .edges()
        .map(|e| {
            let r = b.edge(e);
            (
                es(e),
                [
                    b.vertex_serial(r.vt[0]).get(),
                    b.vertex_serial(r.vt[1]).get(),
                    b.face_serial(r.face[0]).get(),
                    b.face_serial(r.face[1]).get(),
                    es(r.cw[0]),
                    es(r.cw[1]),
                    es(r.ccw[0]),
                    es(r.ccw[1]),
                ],
            )
        })
        .collect();
    let mut vertices: Vec<_> = b
        .vertices()
        .map(|v| {
            let p = b.position(v);
            (
                b.vertex_serial(v).get(),
                [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()],
                es(b.vertex(v).ped),
            )
        })
        .collect();
    faces.sort();
    edges.sort();
    vertices.sort();
    Dump {
        faces,
        edges,
        vertices,
        handles: b.handles(),
    }
}

/// The topology and geometry up to face and edge serial numbers: each face as its cycle
/// of vertex serials (rotated to start at the smallest), sorted; each vertex's locus.
#[derive(Debug, PartialEq)]
pub struct Canon {
    cycles: Vec<Vec<u64>>,
    loci: BTreeMap<u64, [u64; 3]>,
    handles: u32,
}

pub fn canon(b: &Body) -> Canon {
    let mut cycles: Vec<Vec<u64>> = b
        .faces()
        .map(|f| {
            let c: Vec<u64> = b
                .face_vertices(f)
                .map(|v| b.vertex_serial(v).get())
                .collect();
            least_rotation(c)
        })
        .collect();
    cycles.sort();
    let loci = b
        .vertices()
        .map(|v| {
            let p = b.position(v);
            (
                b.vertex_serial(v).get(),
                [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()],
            )
        })
        .collect();
    Canon {
        cycles,
        loci,
        handles: b.handles(),
    }
}

/// Face cycles by vertex locus (for comparing bodies whose vertices were remade).
pub fn canon_by_locus(b: &Body) -> Vec<Vec<[i64; 3]>> {
    let key = |v| {
        let p = b.position(v) * 1e6;
        [p.x.round() as i64, p.y.round() as i64, p.z.round() as i64]
    };
    let mut cycles: Vec<Vec<[i64; 3]>> = b
        .faces()
        .map(|f| least_rotation(b.face_vertices(f).map(key).collect()))
        .collect();
    cycles.sort();
    cycles
}

pub fn assert_valid(b: &Body) {
    let r = check_topology(b);
    assert!(r.is_ok(), "{r}");
}

/// The lexicographically least rotation of a cycle (a cycle may visit a vertex twice).
fn least_rotation<T: Ord + Clone>(c: Vec<T>) -> Vec<T> {
    (0..c.len().max(1))
        .map(|k| {
            let mut r = c.clone();
            if !r.is_empty() {
                r.rotate_left(k);
            }
            r
        })
        .min()
        .unwrap_or_default()
}

/// The first face whose outward normal points along `n` (within about 25°).
pub fn face_towards(b: &Body, n: DVec3) -> FaceId {
    b.faces()
        .find(|&f| b.face_plane(f).is_some_and(|p| p.normal.dot(n) > 0.9))
        .expect("a face pointing that way")
}

/// Moves every vertex of `b` by `d`.
pub fn shift(b: &mut Body, d: DVec3) {
    for v in b.vertices().collect::<Vec<_>>() {
        let p = b.position(v);
        b.set_position(v, p + d);
    }
}
