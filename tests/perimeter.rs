//! Perimeter access against the winged-edge figure: ECW/ECCW, FCW/FCCW, VCW/VCCW,
//! OTHER, LINKED, WING, and the perimeter iterators.

#[path = "support/kernel.rs"]
mod common;

use common::{dump, face_towards};
use glam::DVec3;
use winged::model::solids::mkcube;
use winged::model::{Body, EdgeId, Link, Serials};

fn cube() -> Body {
    mkcube(&mut Serials::new(), 2.0, 2.0, 2.0).unwrap()
}

#[test]
fn the_fetches_agree_with_the_figure_on_every_edge() {
    let b = cube();
    for e in b.edges() {
        let r = *b.edge(e);
        // About its faces: ECCW and ECW are the CCW and CW wings of that side.
        assert_eq!(b.eccw(e, r.pface()), Some(r.pccw()));
        assert_eq!(b.eccw(e, r.nface()), Some(r.nccw()));
        assert_eq!(b.ecw(e, r.pface()), Some(r.pcw()));
        assert_eq!(b.ecw(e, r.nface()), Some(r.ncw()));
        // About its vertices (Baumgart's ECCW: PVT → PCW, NVT → NCW).
        assert_eq!(b.eccw(e, r.pvt()), Some(r.pcw()));
        assert_eq!(b.eccw(e, r.nvt()), Some(r.ncw()));
        assert_eq!(b.ecw(e, r.pvt()), Some(r.nccw()));
        assert_eq!(b.ecw(e, r.nvt()), Some(r.pccw()));
        // Upward from NVT to PVT, PFACE is on the right: counter-clockwise about PVT
        // from the edge comes PFACE, about NVT comes NFACE.
        assert_eq!(b.fccw(e, r.pvt()), Some(r.pface()));
        assert_eq!(b.fccw(e, r.nvt()), Some(r.nface()));
        assert_eq!(b.fcw(e, r.pvt()), Some(r.nface()));
        assert_eq!(b.fcw(e, r.nvt()), Some(r.pface()));
        // In PFACE the edge runs from PVT down to NVT.
        assert_eq!(b.vcw(e, r.pface()), Some(r.pvt()));
        assert_eq!(b.vccw(e, r.pface()), Some(r.nvt()));
        assert_eq!(b.vcw(e, r.nface()), Some(r.nvt()));
        assert_eq!(b.vccw(e, r.nface()), Some(r.pvt()));
        assert_eq!(b.other_face(e, r.pface()), Some(r.nface()));
        assert_eq!(b.other_vertex(e, r.nvt()), Some(r.pvt()));
        // Wings meet the edge where the figure says.
        for (w, v) in [
            (r.pcw(), r.pvt()),
            (r.nccw(), r.pvt()),
            (r.ncw(), r.nvt()),
            (r.pccw(), r.nvt()),
        ] {
            assert_eq!(b.linked_edges(e, w), Some(Link::Vertex(v)));
        }
    }
}

#[test]
fn clockwise_undoes_counter_clockwise() {
    let b = cube();
    for e in b.edges() {
        let r = *b.edge(e);
        for f in r.face {
            assert_eq!(b.ecw(b.eccw(e, f).unwrap(), f), Some(e));
        }
        for v in r.vt {
            assert_eq!(b.ecw(b.eccw(e, v).unwrap(), v), Some(e));
        }
    }
}

#[test]
fn face_perimeters_run_counter_clockwise_seen_from_outside() {
    let b = cube();
    for f in b.faces() {
        let n = b.face_plane(f).unwrap().normal;
        let c = b.face_center(f);
        let vs: Vec<DVec3> = b.face_vertices(f).map(|v| b.position(v)).collect();
        assert_eq!(vs.len(), 4);
        for k in 0..4 {
            let turn = (vs[k] - c).cross(vs[(k + 1) % 4] - c);
            assert!(
                turn.dot(n) > 0.0,
                "counter-clockwise about the outward normal"
            );
        }
        // The edge iterator follows ECCW.
        let es: Vec<EdgeId> = b.face_edges(f).collect();
        for k in 0..4 {
            assert_eq!(b.eccw(es[k], f), Some(es[(k + 1) % 4]));
        }
    }
}

#[test]
fn vertex_perimeters_run_counter_clockwise_and_list_the_faces_between() {
    let b = cube();
    for v in b.vertices() {
        let es: Vec<EdgeId> = b.vertex_edges(v).collect();
        let fs: Vec<_> = b.vertex_faces(v).collect();
        assert_eq!((es.len(), fs.len()), (3, 3));
        for k in 0..3 {
            assert_eq!(b.eccw(es[k], v), Some(es[(k + 1) % 3]));
            assert_eq!(b.fccw(es[k], v), Some(fs[k]));
            // The face after an edge lies between it and the next edge.
            assert_eq!(
                b.linked_face_edge(fs[k], es[(k + 1) % 3]),
                Some(Link::Incident)
            );
        }
        // Counter-clockwise about the outward direction of the corner.
        let p = b.position(v);
        let out = p.normalize();
        let d: Vec<DVec3> = es
            .iter()
            .map(|&e| b.position(b.other_vertex(e, v).unwrap()) - p)
            .collect();
        for k in 0..3 {
            assert!(d[k].cross(d[(k + 1) % 3]).dot(out) > 0.0);
        }
    }
}

#[test]
fn linked_finds_shared_entities_and_nothing_else() {
    let b = cube();
    let top = face_towards(&b, DVec3::Z);
    let bottom = face_towards(&b, -DVec3::Z);
    assert_eq!(b.linked_faces(top, bottom), None);
    let side = b.faces().find(|&f| f != top && f != bottom).unwrap();
    let Some(Link::Edge(e)) = b.linked_faces(top, side) else {
        panic!("top and a side share an edge")
    };
    assert!(b.edge(e).face.contains(&top) && b.edge(e).face.contains(&side));
    let r = *b.edge(e);
    assert_eq!(b.linked_vertices(r.nvt(), r.pvt()), Some(Link::Edge(e)));
    assert_eq!(b.linked_edge_vertex(e, r.nvt()), Some(Link::Incident));
    let far = b
        .vertices()
        .find(|v| !r.vt.contains(v) && b.linked_vertices(*v, r.nvt()).is_none())
        .unwrap();
    assert_eq!(b.linked_edge_vertex(e, far), None);
    assert_eq!(
        b.eccw(e, far),
        None,
        "a fetch about an entity not on the edge"
    );
}

#[test]
fn wing_of_wings_already_in_place_changes_nothing() {
    let mut b = cube();
    let before = dump(&b);
    for e in b.edges().collect::<Vec<_>>() {
        let r = *b.edge(e);
        for w in [r.pcw(), r.pccw(), r.ncw(), r.nccw()] {
            b.wing(e, w);
            b.wing(w, e);
        }
    }
    assert_eq!(dump(&b), before);
}

#[test]
fn evert_reverses_every_perimeter() {
    let mut b = cube();
    let cycles: Vec<Vec<_>> = b.faces().map(|f| b.face_vertices(f).collect()).collect();
    b.evert();
    for (f, c) in b.faces().zip(&cycles) {
        let mut now: Vec<_> = b.face_vertices(f).collect();
        now.reverse();
        let k = now.iter().position(|v| *v == c[0]).unwrap();
        now.rotate_left(k);
        assert_eq!(&now, c);
    }
    assert!((b.volume() + 8.0).abs() < 1e-12);
    b.evert();
    assert!((b.volume() - 8.0).abs() < 1e-12);
}
