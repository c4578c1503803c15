//! Each Euler operator's refusals (typed error, body untouched), and GLUE/UNGLUE as
//! inverses of each other.

#[path = "support/kernel.rs"]
mod common;

use common::{assert_valid, canon, canon_by_locus, dump, face_towards, shift};
use glam::DVec3;
use winged::model::solids::mkcube;
use winged::model::{Body, EdgeId, EulerError, FaceId, Serials, VertexId, check_solid};

fn cube(s: &mut Serials) -> Body {
    mkcube(s, 2.0, 2.0, 2.0).unwrap()
}

/// Asserts that `op` is refused with an error matching `want` and changes nothing.
fn refused(
    b: &mut Body,
    want: fn(&EulerError) -> bool,
    op: impl FnOnce(&mut Body) -> Result<(), EulerError>,
) {
    let before = dump(b);
    let err = op(b).expect_err("the operator should refuse");
    assert!(want(&err), "unexpected error: {err}");
    assert!(!err.to_string().is_empty());
    assert_eq!(dump(b), before, "refused with {err} but changed the body");
}

#[test]
fn dead_and_out_of_range_ids_are_refused() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    let far = 10_000usize;
    refused(
        &mut b,
        |e| matches!(e, EulerError::UnknownFace(_)),
        |b| {
            b.mkev(
                &mut Serials::new(),
                FaceId::from_index(far),
                VertexId::from_index(0),
                DVec3::ZERO,
            )
            .map(|_| ())
        },
    );
    refused(
        &mut b,
        |e| matches!(e, EulerError::UnknownEdge(_)),
        |b| {
            b.esplit(&mut Serials::new(), EdgeId::from_index(far), DVec3::ZERO)
                .map(|_| ())
        },
    );
    refused(
        &mut b,
        |e| matches!(e, EulerError::UnknownEdge(_)),
        |b| b.klfe(EdgeId::NONE).map(|_| ()),
    );
    refused(
        &mut b,
        |e| matches!(e, EulerError::UnknownVertex(_)),
        |b| b.klev(VertexId::from_index(far)).map(|_| ()),
    );
    // A killed vertex's slot id is dead.
    let e = b.edges().next().unwrap();
    let (_, v) = b.esplit(&mut s, e, DVec3::ZERO).unwrap();
    b.klev(v).unwrap();
    refused(
        &mut b,
        |e| matches!(e, EulerError::UnknownVertex(_)),
        |b| b.klev(v).map(|_| ()),
    );
}

#[test]
fn mkev_refuses_vertices_off_the_face_and_second_spurs() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    let top = face_towards(&b, DVec3::Z);
    let bottom_vertex = b.face_vertices(face_towards(&b, -DVec3::Z)).next().unwrap();
    refused(
        &mut b,
        |e| matches!(e, EulerError::VertexNotOnFace { .. }),
        |b| {
            b.mkev(&mut Serials::new(), top, bottom_vertex, DVec3::ZERO)
                .map(|_| ())
        },
    );
    let v = b.face_vertices(top).next().unwrap();
    let mut s2 = s.clone();
    b.mkev(&mut s2, top, v, DVec3::ZERO).unwrap();
    // Only one spur at a vertex on a face at a time.
    refused(
        &mut b,
        |e| matches!(e, EulerError::AmbiguousCorner { corners: 2, .. }),
        |b| b.mkev(&mut s2, top, v, DVec3::ZERO).map(|_| ()),
    );
}

#[test]
fn mkfe_refuses_one_vertex_twice_and_vertices_off_the_face() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    let top = face_towards(&b, DVec3::Z);
    let v = b.face_vertices(top).next().unwrap();
    refused(
        &mut b,
        |e| matches!(e, EulerError::SameVertex { .. }),
        |b| b.mkfe(&mut Serials::new(), v, top, v).map(|_| ()),
    );
    let below = b.face_vertices(face_towards(&b, -DVec3::Z)).next().unwrap();
    refused(
        &mut b,
        |e| matches!(e, EulerError::VertexNotOnFace { .. }),
        |b| b.mkfe(&mut Serials::new(), v, top, below).map(|_| ()),
    );
}

#[test]
fn klfe_refuses_a_spur_and_klev_a_corner() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    let top = face_towards(&b, DVec3::Z);
    let v = b.face_vertices(top).next().unwrap();
    let (spur, _) = b.mkev(&mut s, top, v, DVec3::ZERO).unwrap();
    refused(
        &mut b,
        |e| matches!(e, EulerError::SameFaceBothSides { .. }),
        |b| b.klfe(spur).map(|_| ()),
    );
    // v now has valence 4.
    refused(
        &mut b,
        |e| matches!(e, EulerError::Valence { valence: 4, .. }),
        |b| b.klev(v).map(|_| ()),
    );
    // A seminal vertex has no edge to kill.
    let (mut seed, _, sv) = Body::seminal(&mut s, DVec3::ZERO);
    refused(
        &mut seed,
        |e| matches!(e, EulerError::NoEdges { .. }),
        |b| b.klev(sv).map(|_| ()),
    );
}

#[test]
fn klve_and_klev_refuse_to_make_a_loop() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    let top = face_towards(&b, DVec3::Z);
    let vs: Vec<VertexId> = b.face_vertices(top).collect();
    // A diagonal across the top face, then split one side: contracting the side's half
    // whose ends are both joined by the diagonal would make a loop.
    let (diag, _) = b.mkfe(&mut s, vs[0], top, vs[2]).unwrap();
    let side = b.linked_vertices(vs[0], vs[1]).unwrap();
    let winged::model::Link::Edge(side) = side else {
        unreachable!()
    };
    let _ = diag;
    // Make vs[0]–vs[1] a digon partner: a second edge between vs[0] and vs[1].
    let f = b.edge(side).face[1];
    let on: Vec<VertexId> = b.face_vertices(f).collect();
    if on.contains(&vs[0]) && on.contains(&vs[1]) && b.mkfe(&mut s, vs[0], f, vs[1]).is_ok() {
        assert_valid(&b);
        refused(
            &mut b,
            |e| matches!(e, EulerError::WouldMakeLoop { .. }),
            |b| b.klve(side).map(|_| ()),
        );
    } else {
        let f = b.edge(side).face[0];
        b.mkfe(&mut s, vs[0], f, vs[1]).unwrap();
        assert_valid(&b);
        refused(
            &mut b,
            |e| matches!(e, EulerError::WouldMakeLoop { .. }),
            |b| b.klve(side).map(|_| ()),
        );
    }
}

#[test]
fn glue_refuses_mismatched_touching_or_equal_faces() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    let top = face_towards(&b, DVec3::Z);
    let east = face_towards(&b, DVec3::X);
    let v = b.face_vertices(top).next().unwrap();
    let w = b.face_vertices(east).find(|&x| x != v).unwrap();
    refused(
        &mut b,
        |e| matches!(e, EulerError::SameFace { .. }),
        |b| b.glue(top, v, top, v),
    );
    refused(
        &mut b,
        |e| matches!(e, EulerError::FacesTouch { .. }),
        |b| b.glue(top, v, east, w),
    );
    // A triangle against a square.
    let mut t = winged::model::solids::mktetra(&mut s, 1.0).unwrap();
    let tf = t.faces().next().unwrap();
    let tv = t.face_vertices(tf).next().unwrap();
    let before_t = dump(&t);
    refused(
        &mut b,
        |e| matches!(e, EulerError::DegreeMismatch { n1: 4, n2: 3, .. }),
        |b| b.glue_bodies(top, v, &mut t, tf, tv),
    );
    assert_eq!(dump(&t), before_t, "the other body is untouched too");
}

#[test]
fn unglue_refuses_a_broken_seam() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    let top = face_towards(&b, DVec3::Z);
    let ring: Vec<EdgeId> = b.face_edges(top).collect();
    refused(
        &mut b,
        |e| matches!(e, EulerError::BadSeam { .. }),
        |b| b.unglue(&mut Serials::new(), &ring[..2]).map(|_| ()),
    );
    refused(
        &mut b,
        |e| matches!(e, EulerError::BadSeam { .. }),
        |b| b.unglue(&mut Serials::new(), &ring[..3]).map(|_| ()),
    );
    let twice = [ring[0], ring[1], ring[2], ring[0]];
    refused(
        &mut b,
        |e| matches!(e, EulerError::BadSeam { .. }),
        |b| b.unglue(&mut Serials::new(), &twice).map(|_| ()),
    );
}

#[test]
fn unglue_undoes_glue_of_two_bodies() {
    unglue_after_glue(false);
    unglue_after_glue(true);
}

/// Glues two stacked cubes and cuts them apart again; `flip` inverts the seam's first
/// edge so that the other cube is the one split off.
fn unglue_after_glue(flip: bool) {
    let mut s = Serials::new();
    let mut a = cube(&mut s);
    let mut b = cube(&mut s);
    shift(&mut b, DVec3::Z * 2.0);
    let (a0, a_shape, b_shape) = (canon(&a), canon_by_locus(&a), canon_by_locus(&b));
    let top = face_towards(&a, DVec3::Z);
    let bottom = face_towards(&b, -DVec3::Z);
    let v1 = a.face_vertices(top).next().unwrap();
    let v2 = b
        .face_vertices(bottom)
        .find(|&v| b.position(v).distance(a.position(v1)) < 1e-9)
        .unwrap();
    let seam: Vec<EdgeId> = a.face_edges(top).collect();
    a.glue_bodies(top, v1, &mut b, bottom, v2).unwrap();
    assert_valid(&a);
    if flip {
        a.invert(seam[0]);
    }
    // The part on the NFACE side of the seam's first edge is the one split off.
    let nface_is_upper = a.face_center(a.edge(seam[0]).nface()).z > 1.0;
    let cut = a.unglue(&mut s, &seam).unwrap();
    assert_valid(&a);
    let part = cut.split_off.expect("the seam separates the two cubes");
    assert_valid(&part);
    assert_eq!(
        (a.face_count(), a.edge_count(), a.vertex_count()),
        (6, 12, 8)
    );
    assert_eq!(
        (part.face_count(), part.edge_count(), part.vertex_count()),
        (6, 12, 8)
    );
    assert!(a.has_face(cut.kept_face) && part.has_face(cut.new_face));
    if nface_is_upper {
        assert_eq!(canon(&a), a0, "the kept cube is the original lower one");
        assert_eq!(canon_by_locus(&part), b_shape);
    } else {
        assert_eq!(
            canon_by_locus(&a),
            b_shape,
            "the kept cube has the upper shape"
        );
        assert_eq!(canon_by_locus(&part), a_shape);
    }
    assert!(check_solid(&a, 1e-9).is_ok() && check_solid(&part, 1e-9).is_ok());
}

#[test]
fn unglue_of_a_handle_removes_it() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    let top = face_towards(&b, DVec3::Z);
    let bottom = face_towards(&b, -DVec3::Z);
    let made = b.glueff(&mut s, top, bottom).unwrap();
    assert_eq!(b.handles(), 1);
    // The tube's ring of edges at the old top face is a non-separating loop.
    let ring: Vec<EdgeId> = {
        let tops: Vec<VertexId> = b
            .vertices()
            .filter(|&v| (b.position(v).z - 1.0).abs() < 1e-9)
            .collect();
        b.edges()
            .filter(|&e| {
                let r = b.edge(e);
                tops.contains(&r.nvt()) && tops.contains(&r.pvt())
            })
            .collect()
    };
    assert_eq!(ring.len(), 4);
    let before = (b.face_count(), b.edge_count(), b.vertex_count());
    let cut = b.unglue(&mut s, &ring).unwrap();
    assert!(cut.split_off.is_none());
    assert_eq!(b.handles(), 0);
    assert_eq!(
        (b.face_count(), b.edge_count(), b.vertex_count()),
        (before.0 + 2, before.1 + 4, before.2 + 4)
    );
    assert_valid(&b);
    let _ = made;
}

#[test]
fn glue_then_unglue_of_one_body_restores_the_counts() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    let top = face_towards(&b, DVec3::Z);
    let bottom = face_towards(&b, -DVec3::Z);
    let seam: Vec<EdgeId> = b.face_edges(top).collect();
    let v1 = b.face_vertices(top).next().unwrap();
    let glued = b
        .face_vertices(bottom)
        .collect::<Vec<_>>()
        .into_iter()
        .any(|v2| b.glue(top, v1, bottom, v2).is_ok());
    assert!(glued);
    assert_eq!(b.handles(), 1);
    assert_valid(&b);
    let cut = b.unglue(&mut s, &seam).unwrap();
    assert!(cut.split_off.is_none());
    assert_eq!(
        (b.face_count(), b.edge_count(), b.vertex_count()),
        (6, 12, 8)
    );
    assert_eq!(b.handles(), 0);
    assert_valid(&b);
}
