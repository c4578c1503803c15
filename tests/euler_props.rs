//! Property tests: random sequences of Euler operators on random bodies keep every
//! invariant; each operator followed by its inverse restores the body (up to serial
//! numbers); refused operators change nothing.

#[path = "support/kernel.rs"]
mod common;

use common::{assert_valid, canon, dump};
use glam::DVec3;
use proptest::prelude::*;
use winged::model::solids::{mkcube, mktetra};
use winged::model::{Body, EdgeId, FaceId, Serials, VertexId};

#[derive(Clone, Debug)]
enum Op {
    MkEv {
        f: usize,
        v: usize,
        d: [i8; 3],
    },
    MkFe {
        f: usize,
        a: usize,
        b: usize,
    },
    ESplit {
        e: usize,
        t: u8,
    },
    KlFe {
        e: usize,
    },
    KlEv {
        v: usize,
    },
    KlVe {
        e: usize,
    },
    Invert {
        e: usize,
    },
    /// An operator on raw slot ids that may be dead or out of range.
    Junk {
        kind: u8,
        raw: u32,
    },
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        3 => (any::<usize>(), any::<usize>(), any::<[i8; 3]>()).prop_map(|(f, v, d)| Op::MkEv { f, v, d }),
        4 => (any::<usize>(), any::<usize>(), any::<usize>()).prop_map(|(f, a, b)| Op::MkFe { f, a, b }),
        3 => (any::<usize>(), any::<u8>()).prop_map(|(e, t)| Op::ESplit { e, t }),
        2 => any::<usize>().prop_map(|e| Op::KlFe { e }),
        2 => any::<usize>().prop_map(|v| Op::KlEv { v }),
        1 => any::<usize>().prop_map(|e| Op::KlVe { e }),
        1 => any::<usize>().prop_map(|e| Op::Invert { e }),
        1 => (0u8..7, 0u32..64).prop_map(|(kind, raw)| Op::Junk { kind, raw }),
    ]
}

fn pick<T: Copy>(items: &[T], k: usize) -> Option<T> {
    (!items.is_empty()).then(|| items[k % items.len()])
}

fn start(kind: u8, s: &mut Serials) -> Body {
    match kind % 3 {
        0 => Body::seminal(s, DVec3::ZERO).0,
        1 => mkcube(s, 2.0, 2.0, 2.0).unwrap(),
        _ => mktetra(s, 1.0).unwrap(),
    }
}

fn counts(b: &Body) -> (i64, i64, i64) {
    (
        b.face_count() as i64,
        b.edge_count() as i64,
        b.vertex_count() as i64,
    )
}

/// Applies one operator, checking its postconditions, its inverse where it has a simple
/// one, and that a refusal changed nothing.
fn apply(b: &mut Body, s: &mut Serials, op: &Op) {
    let before = dump(b);
    let before_canon = canon(b);
    let before_body = b.clone();
    let (f0, e0, v0) = counts(b);
    let faces: Vec<FaceId> = b.faces().collect();
    let edges: Vec<EdgeId> = b.edges().collect();
    let verts: Vec<VertexId> = b.vertices().collect();
    let refused = match *op {
        Op::MkEv { f, v, d } => {
            let Some(f) = pick(&faces, f) else { return };
            let on: Vec<VertexId> = if b.face(f).ped.is_none() {
                verts.clone()
            } else {
                b.face_vertices(f).collect()
            };
            let Some(v) = pick(&on, v) else { return };
            let pos = b.position(v) + DVec3::new(d[0] as f64, d[1] as f64, d[2] as f64) * 0.01;
            match b.mkev(s, f, v, pos) {
                Ok((e, vnew)) => {
                    assert_eq!(counts(b), (f0, e0 + 1, v0 + 1));
                    assert_eq!(b.vertex(vnew).ped, e);
                    assert_eq!((b.edge(e).pvt(), b.edge(e).nvt()), (v, vnew));
                    assert_valid(b);
                    let mut undo = b.clone();
                    assert_eq!(undo.klev(vnew).unwrap(), v);
                    assert_eq!(dump(&undo), before, "KLEV(MKEV) restores exactly");
                    false
                }
                Err(_) => true,
            }
        }
        Op::MkFe { f, a, b: bsel } => {
            let Some(f) = pick(&faces, f) else { return };
            let on: Vec<VertexId> = b.face_vertices(f).collect();
            let (Some(v1), Some(v2)) = (pick(&on, a), pick(&on, bsel)) else {
                return;
            };
            match b.mkfe(s, v1, f, v2) {
                Ok((e, fnew)) => {
                    assert_eq!(counts(b), (f0 + 1, e0 + 1, v0));
                    let r = *b.edge(e);
                    assert_eq!((r.pvt(), r.nvt(), r.pface(), r.nface()), (v1, v2, f, fnew));
                    assert_valid(b);
                    let mut undo = b.clone();
                    assert_eq!(undo.klfe(e).unwrap(), f);
                    assert_eq!(canon(&undo), before_canon, "KLFE(MKFE) restores");
                    false
                }
                Err(_) => true,
            }
        }
        Op::ESplit { e, t } => {
            let Some(e) = pick(&edges, e) else { return };
            let r = *b.edge(e);
            let t = t as f64 / 255.0;
            let pos = b.position(r.nvt()).lerp(b.position(r.pvt()), t);
            let (enew, vnew) = b.esplit(s, e, pos).unwrap();
            assert_eq!(counts(b), (f0, e0 + 1, v0 + 1));
            assert_eq!(b.edge(enew).pvt(), r.pvt());
            assert_eq!(b.edge(e).pvt(), vnew);
            assert_valid(b);
            let mut undo = b.clone();
            undo.klev(vnew).unwrap();
            assert_eq!(dump(&undo), before, "KLEV(ESPLIT) restores exactly");
            false
        }
        Op::KlFe { e } => {
            let Some(e) = pick(&edges, e) else { return };
            let r = *b.edge(e);
            match b.klfe(e) {
                Ok(f) => {
                    assert_eq!(f, r.pface());
                    assert_eq!(counts(b), (f0 - 1, e0 - 1, v0));
                    assert_valid(b);
                    // MKFE(PVT, PFACE, NVT) makes the same face again, when its corners
                    // are unambiguous.
                    let mut redo = b.clone();
                    if redo.mkfe(s, r.pvt(), f, r.nvt()).is_ok() {
                        assert_eq!(canon(&redo), before_canon, "MKFE(KLFE) restores");
                    }
                    false
                }
                Err(_) => true,
            }
        }
        Op::KlEv { v } => {
            let Some(v) = pick(&verts, v) else { return };
            match b.klev(v) {
                Ok(_) => {
                    assert_eq!(counts(b), (f0, e0 - 1, v0 - 1));
                    assert!(!b.has_vertex(v));
                    assert_valid(b);
                    false
                }
                Err(_) => true,
            }
        }
        Op::KlVe { e } => {
            let Some(e) = pick(&edges, e) else { return };
            match b.klve(e) {
                Ok(_) => {
                    assert_eq!(counts(b), (f0, e0 - 1, v0 - 1));
                    assert_valid(b);
                    false
                }
                Err(_) => true,
            }
        }
        Op::Invert { e } => {
            let Some(e) = pick(&edges, e) else { return };
            b.invert(e);
            assert_valid(b);
            assert_eq!(canon(b), before_canon, "INVERT changes no perimeter");
            b.invert(e);
            assert_eq!(dump(b), before, "INVERT is its own inverse");
            false
        }
        Op::Junk { kind, raw } => {
            let (f, e, v) = (
                FaceId::from_index(raw as usize),
                EdgeId::from_index(raw as usize),
                VertexId::from_index(raw as usize),
            );
            let refused = match kind {
                0 => b.mkev(s, f, v, DVec3::ZERO).is_err(),
                1 => b
                    .mkfe(s, v, f, VertexId::from_index(raw as usize + 1))
                    .is_err(),
                2 => b.esplit(s, e, DVec3::ZERO).is_err(),
                3 => b.klfe(e).is_err(),
                4 => b.klev(v).is_err(),
                5 => b.klve(e).is_err(),
                _ => b
                    .glue(f, v, FaceId::from_index(raw as usize + 1), v)
                    .is_err(),
            };
            if !refused {
                assert_valid(b);
                return;
            }
            true
        }
    };
    if refused {
        assert_eq!(
            dump(b),
            before,
            "a refused operator leaves the body as it was"
        );
        *b = before_body;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn random_euler_sequences_keep_every_invariant(
        kind in any::<u8>(),
        ops in prop::collection::vec(op(), 1..80),
    ) {
        let mut s = Serials::new();
        let mut b = start(kind, &mut s);
        assert_valid(&b);
        for op in &ops {
            apply(&mut b, &mut s, op);
        }
    }
}
