//! Durability: the journal and snapshots rebuild the same world, entity by entity, and
//! damage on disk gives a fallback or a clear error, never a different world.
//!
//! Real SQLite and real files in temporary directories.

#[path = "support/kernel.rs"]
mod common;

use std::path::Path;

use glam::DVec3;
use serde_json::{Value, json};
use tempfile::TempDir;
use winged::edit::{Edit, EditError, Outcome, apply};
use winged::model::{Body, BodyId, Serial, World, check_solid, check_topology};
use winged::store::{
    Durability, Entry, SnapshotError, Store, StoreError, StoreOptions, check_world, read_snapshot,
    snapshot, write_snapshot,
};

use common::dump;

// ------------------------------------------------------------------ harness

/// A world being edited, with every accepted edit journaled in batches of varying size
/// and every outcome kept to compare with the replay.
struct Run {
    dir: TempDir,
    /// The open store (closed, releasing its lock, while a test opens the directory
    /// itself).
    store: Option<Store>,
    world: World,
    pending: Vec<(u64, Edit)>,
    log: Vec<(u64, Edit, Outcome)>,
    batches: usize,
    refused: usize,
}

/// Journal entries without change descriptions, from `(revision, edit)` pairs.
fn as_entries<'a>(list: &[(u64, &'a Edit)]) -> Vec<Entry<'a>> {
    list.iter().map(|&(r, e)| Entry::new(r, e)).collect()
}

/// Batch sizes cycled through, as a server groups concurrent writes.
const BATCHES: [usize; 6] = [1, 3, 7, 16, 2, 64];

fn options() -> StoreOptions {
    StoreOptions {
        durability: Durability::Normal,
        ..StoreOptions::default()
    }
}

impl Run {
    /// The open store, opened again if closed.
    fn store(&mut self) -> &mut Store {
        let dir = self.dir.path();
        self.store
            .get_or_insert_with(|| Store::open(dir, options()).unwrap())
    }

    /// Closes the store, so that the directory can be opened elsewhere.
    fn close(&mut self) {
        self.store = None;
    }

    fn new() -> Run {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path(), options()).unwrap();
        assert!(store.is_fresh().unwrap());
        Run {
            dir,
            store: Some(store),
            world: World::new(),
            pending: Vec::new(),
            log: Vec::new(),
            batches: 0,
            refused: 0,
        }
    }

    /// Applies the edit `e` (JSON, as journaled). Accepted: queued for the journal.
    /// Refused: the world must be exactly as before and nothing is queued.
    fn try_edit(&mut self, e: Value) -> Result<Outcome, EditError> {
        let edit: Edit =
            serde_json::from_value(e.clone()).unwrap_or_else(|err| panic!("{e}: {err}"));
        let back: Edit = serde_json::from_str(&serde_json::to_string(&edit).unwrap()).unwrap();
        assert_eq!(back, edit, "the edit reads back as written");
        let before = self.world.revision();
        let bytes = snapshot::encode(&self.world);
        match apply(&mut self.world, &edit) {
            Ok(o) if self.world.revision() == before => {
                // A write that changed nothing (a patch to the values the body has) is
                // not a revision and is not journaled.
                assert_eq!(
                    snapshot::encode(&self.world),
                    bytes,
                    "{e}: an edit that kept the revision changed the world"
                );
                Ok(o)
            }
            Ok(o) => {
                assert_eq!(self.world.revision(), before + 1);
                self.pending.push((self.world.revision(), edit.clone()));
                self.log.push((self.world.revision(), edit, o.clone()));
                if self.pending.len() >= BATCHES[self.batches % BATCHES.len()] {
                    self.flush();
                }
                Ok(o)
            }
            Err(err) => {
                assert_eq!(
                    snapshot::encode(&self.world),
                    bytes,
                    "{e}: a refused edit changed the world"
                );
                self.refused += 1;
                Err(err)
            }
        }
    }

    fn ok(&mut self, e: Value) -> Outcome {
        let shown = e.to_string();
        self.try_edit(e)
            .unwrap_or_else(|err| panic!("{shown} was refused: {err}"))
    }

    fn refused(&mut self, e: Value) {
        let shown = e.to_string();
        assert!(self.try_edit(e).is_err(), "{shown} was accepted");
    }

    fn flush(&mut self) {
        let dir = self.dir.path();
        let store = self
            .store
            .get_or_insert_with(|| Store::open(dir, options()).unwrap());
        let batch: Vec<(u64, &Edit)> = self.pending.iter().map(|(r, e)| (*r, e)).collect();
        store
            .append(&as_entries(&batch), self.world.next_serial())
            .unwrap();
        self.pending.clear();
        self.batches += 1;
        if self.world.revision() > 0 {
            assert_eq!(self.store().last_revision(), Some(self.world.revision()));
        }
    }

    /// Reopens the data directory and recovers, checking each replayed outcome against
    /// the one the edit had when first applied.
    fn recover(&mut self) -> (Store, winged::store::Recovered) {
        self.flush();
        self.close();
        let mut store = Store::open(self.dir.path(), options()).unwrap();
        let log = &self.log;
        let rec = store
            .recover(|revision, edit, outcome, world| {
                let (r, e, o) = &log[revision as usize - 1];
                assert_eq!((revision, edit, outcome), (*r, e, o));
                assert_eq!(world.revision(), revision);
            })
            .unwrap();
        (store, rec)
    }

    fn body(&self, id: u64) -> &Body {
        self.world.body(BodyId(Serial(id))).expect("a live body")
    }

    /// The face of body `id` whose outward normal (body frame) points along `n`.
    fn face_towards(&self, id: u64, n: [f64; 3]) -> u64 {
        let b = self.body(id);
        b.face_serial(common::face_towards(b, DVec3::from_array(n)))
            .get()
    }

    fn face_vertices(&self, id: u64, face: u64) -> Vec<u64> {
        let b = self.body(id);
        let f = b.face_by_serial(Serial(face)).expect("a live face");
        b.face_vertices(f)
            .map(|v| b.vertex_serial(v).get())
            .collect()
    }

    fn face_edges(&self, id: u64, face: u64) -> Vec<u64> {
        let b = self.body(id);
        let f = b.face_by_serial(Serial(face)).expect("a live face");
        b.face_edges(f).map(|e| b.edge_serial(e).get()).collect()
    }

    fn edges(&self, id: u64) -> Vec<u64> {
        let b = self.body(id);
        b.edges().map(|e| b.edge_serial(e).get()).collect()
    }
}

fn create(name: &str, shape: Value) -> Value {
    json!({"edit": "create_body", "name": name, "shape": shape})
}

fn create_at(name: &str, at: [f64; 3], shape: Value) -> Value {
    json!({"edit": "create_body", "name": name, "shape": shape,
           "pose": {"position": at, "rotation": [0.0, 0.0, 0.0, 1.0]}})
}

fn euler(body: u64, op: Value) -> Value {
    json!({"edit": "euler", "body": body, "op": op})
}

fn transform(body: u64, req: Value) -> Value {
    json!({"edit": "transform", "body": body, "req": req})
}

fn patch(body: u64, patch: Value) -> Value {
    json!({"edit": "patch_body", "body": body, "patch": patch})
}

fn id(o: &Outcome) -> u64 {
    o.id.expect("an id")
}

/// A small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    fn f(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// Every observable part of two worlds is the same: revision, serial counter, each body
/// (name, supart, parts, pose bits, and every face, edge and vertex by serial with all
/// links and exact loci), cameras and lights.
fn assert_same_world(a: &World, b: &World) {
    assert_eq!(a.revision(), b.revision(), "revision");
    assert_eq!(a.next_serial(), b.next_serial(), "next serial");
    assert_eq!(a.root(), b.root(), "root");
    let ids = |w: &World| w.tree().iter().map(|(id, _)| id).collect::<Vec<_>>();
    assert_eq!(ids(a), ids(b), "body ids");
    let bits = |p: winged::model::Pose| {
        let mut v: Vec<u64> = p.position.to_array().iter().map(|x| x.to_bits()).collect();
        v.extend(p.rotation.to_array().iter().map(|x| x.to_bits()));
        v
    };
    for (id, na) in a.tree().iter() {
        let nb = b.node(id).unwrap();
        assert_eq!(na.name, nb.name, "body {id}: name");
        assert_eq!(na.supart, nb.supart, "body {id}: supart");
        assert_eq!(na.parts, nb.parts, "body {id}: parts");
        assert_eq!(bits(na.pose), bits(nb.pose), "body {id}: pose");
        assert_eq!(dump(&na.body), dump(&nb.body), "body {id}: geometry");
        assert_eq!(
            a.find_by_name(na.name.as_deref().unwrap_or("")),
            b.find_by_name(na.name.as_deref().unwrap_or(""))
        );
    }
    let cams = |w: &World| {
        w.cameras()
            .map(|(n, c)| (n.to_owned(), bits(c.pose), format!("{:?}", c.intrinsics)))
            .collect::<Vec<_>>()
    };
    assert_eq!(cams(a), cams(b), "cameras");
    let lights = |w: &World| {
        w.lights()
            .map(|(n, l)| format!("{n}: {l:?}"))
            .collect::<Vec<_>>()
    };
    assert_eq!(lights(a), lights(b), "lights");
    // Everything, down to free lists and serial indexes.
    assert_eq!(snapshot::encode(a), snapshot::encode(b), "encoded worlds");
}

/// The validator passes on every body, and each body that was a solid still is.
fn assert_valid_like(recovered: &World, original: &World) {
    for (id, n) in recovered.bodies() {
        let r = check_topology(&n.body);
        assert!(r.is_ok(), "body {id}: {r}");
        let was_solid = check_solid(original.body(id).unwrap(), 1e-9).is_ok();
        if was_solid {
            let r = check_solid(&n.body, 1e-9);
            assert!(r.is_ok(), "body {id}: {r}");
        }
    }
    assert!(recovered.tree().check().is_empty());
    check_world(recovered).unwrap();
}

/// Random server-like writes on the bodies in `bodies`: poses, transforms, ESPLIT/KLEV
/// and MKEV/KLEV pairs, cameras, and now and then a refused edit.
fn random_writes(run: &mut Run, bodies: &[u64], n: usize, seed: u64) {
    let mut rng = Rng(seed);
    for _ in 0..n {
        let b = bodies[rng.below(bodies.len())];
        match rng.below(10) {
            0..=2 => {
                let h = rng.f(-1.5, 1.5);
                run.ok(patch(b, json!({"pose": {"position": [rng.f(-2.0, 2.0), rng.f(-2.0, 2.0), rng.f(0.0, 1.0)],
                                                 "rotation": [0.0, h.sin(), 0.0, h.cos()]}})));
            }
            3 => {
                run.ok(transform(
                    b,
                    json!({"op": "rotate", "axis": [rng.f(-1.0, 1.0), 1.0, 0.5],
                                           "angle_deg": rng.f(-30.0, 30.0), "frame": "body"}),
                ));
            }
            4 | 5 => {
                let edges = run.edges(b);
                let e = edges[rng.below(edges.len())];
                let pos = [rng.f(-1.0, 1.0), rng.f(-1.0, 1.0), rng.f(-1.0, 1.0)];
                let o = run.ok(euler(
                    b,
                    json!({"op": "esplit", "edge": e, "position": pos}),
                ));
                run.ok(euler(b, json!({"op": "klev", "vertex": o.vertex.unwrap()})));
            }
            6 => {
                let b_ = run.body(b);
                let f = b_.faces().nth(rng.below(b_.face_count())).unwrap();
                let face = b_.face_serial(f).get();
                let vertex = run.face_vertices(b, face)[0];
                let o = run.ok(euler(
                    b,
                    json!({"op": "mkev", "face": face, "vertex": vertex}),
                ));
                run.ok(euler(b, json!({"op": "klev", "vertex": o.vertex.unwrap()})));
            }
            7 => {
                let a = rng.f(0.0, std::f64::consts::TAU);
                run.ok(json!({"edit": "put_camera", "name": format!("cam{}", rng.below(3)),
                              "camera": {"look_at": {"eye": [3.0 * a.cos(), 3.0 * a.sin(), 1.5], "target": [0.0, 0.0, 0.5]},
                                         "intrinsics": {"width": 640, "height": 480, "fx": 600.0, "fy": 600.0, "cx": 320.0, "cy": 240.0}}}));
            }
            8 => {
                run.ok(transform(
                    b,
                    json!({"op": "translate", "vector": [rng.f(-0.1, 0.1), 0.0, rng.f(-0.1, 0.1)]}),
                ));
            }
            _ => {
                // A vertex of a box corner has three edges: KLEV refuses it.
                let b_ = run.body(b);
                let v = b_.vertices().find(|&v| b_.valence(v) > 2).unwrap();
                let vertex = b_.vertex_serial(v).get();
                run.refused(euler(b, json!({"op": "klev", "vertex": vertex})));
            }
        }
    }
}

/// A world built by every kind of edit, accepted and refused.
fn varied_run() -> Run {
    let mut run = Run::new();
    // Every shape kind.
    let bx = id(&run.ok(create(
        "box",
        json!({"type": "box", "size": [2.0, 2.0, 2.0]}),
    )));
    let tet = id(&run.ok(create("tet", json!({"type": "tetrahedron", "radius": 1.0}))));
    run.ok(create_at(
        "prism",
        [0.0, 3.0, 0.0],
        json!({"type": "prism", "polygon": [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], "height": 0.5}),
    ));
    run.ok(create("pyramid", json!({"type": "pyramid", "polygon": [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]], "height": 1.5})));
    let cyl = id(&run.ok(create(
        "cyl",
        json!({"type": "cylinder", "radius": 0.5, "height": 1.0, "segments": 12}),
    )));
    run.ok(create(
        "cone",
        json!({"type": "cone", "radius": 0.5, "height": 1.0, "segments": 9}),
    ));
    run.ok(create(
        "sphere",
        json!({"type": "sphere", "radius": 1.0, "segments": 8, "rings": 5}),
    ));
    run.ok(create("torus", json!({"type": "torus", "major_radius": 2.0, "minor_radius": 0.5, "segments": 8, "rings": 6})));
    let poly = id(&run.ok(create(
        "poly",
        json!({"type": "polyhedron",
        "vertices": [[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]],
        "faces": [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]]}),
    )));
    // Perception's geometry: a provisional tetrahedron, carved again, and refusals.
    let wall =
        |view: u32, edge: u32| json!({"kind": "wall", "view": view, "ring": 0, "edge": edge});
    let tetra = |scale: f64| {
        json!([
            [scale, scale, scale + 8.0],
            [scale, -scale, -scale + 8.0],
            [-scale, scale, -scale + 8.0],
            [-scale, -scale, scale + 8.0]
        ])
    };
    let faces = json!([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]]);
    let seen = run.ok(
        json!({"edit": "perception", "pieces": [{"name": "seen", "views": 2,
        "outline_px": 2.25, "positions": tetra(1.0), "faces": faces,
        "makers": [wall(0, 1), wall(0, 2), wall(1, 0), {"kind": "near", "view": 1}]}]}),
    );
    let seen = seen.pieces.as_ref().expect("pieces")[0].id;
    run.ok(
        json!({"edit": "perception", "pieces": [{"body": seen, "views": 3,
        "outline_px": 2.25, "positions": tetra(0.5), "faces": faces,
        "makers": [wall(2, 1), wall(0, 2), wall(1, 0), wall(2, 3)]}]}),
    );
    run.refused(
        json!({"edit": "perception", "pieces": [{"body": poly, "views": 1,
        "positions": tetra(0.5), "faces": faces,
        "makers": [wall(0, 0), wall(0, 1), wall(0, 2), wall(0, 3)]}]}),
    );
    run.refused(
        json!({"edit": "perception", "pieces": [{"name": "open", "views": 1,
        "positions": tetra(0.5), "faces": [[0, 1, 2], [0, 3, 1]],
        "makers": [wall(0, 0), wall(0, 1)]}]}),
    );
    let sem = run.ok(
        json!({"edit": "create_body", "shape": {"type": "seminal", "position": [0.0, 0.0, 5.0]}}),
    );
    // Refused creates.
    run.refused(create(
        "box",
        json!({"type": "box", "size": [1.0, 1.0, 1.0]}),
    ));
    run.refused(create("bad", json!({"type": "sphere", "radius": -1.0})));
    run.refused(create(
        "bad",
        json!({"type": "polyhedron", "vertices": [[0.0, 0.0, 0.0]], "faces": [[0, 0, 0]]}),
    ));
    run.refused(json!({"edit": "create_body", "parent": 999_999, "shape": {"type": "box", "size": [1.0, 1.0, 1.0]}}));

    // MKEV, MKFE, KLFE, KLEV from the seminal body: a wire, a lamina, and back.
    let (s, f0, v0) = (id(&sem), sem.face.unwrap(), sem.vertex.unwrap());
    let a = run.ok(euler(
        s,
        json!({"op": "mkev", "face": f0, "vertex": v0, "position": [1.0, 0.0, 5.0]}),
    ));
    let b = run.ok(euler(
        s,
        json!({"op": "mkev", "face": f0, "vertex": a.vertex.unwrap(), "position": [1.0, 1.0, 5.0]}),
    ));
    let c = run.ok(euler(
        s,
        json!({"op": "mkfe", "v1": b.vertex.unwrap(), "face": f0, "v2": v0}),
    ));
    run.ok(euler(s, json!({"op": "klfe", "edge": c.edge.unwrap()})));
    run.ok(euler(s, json!({"op": "klev", "vertex": b.vertex.unwrap()})));
    run.refused(euler(s, json!({"op": "klfe", "edge": c.edge.unwrap()})));

    // ESPLIT, MKFE, KLFE, KLEV, MKEV, KLVE, INVERT on the box.
    let top = run.face_towards(bx, [0.0, 0.0, 1.0]);
    let e0 = run.face_edges(bx, top)[0];
    let split = run.ok(euler(bx, json!({"op": "esplit", "edge": e0})));
    let vn = split.vertex.unwrap();
    let ring = run.face_vertices(bx, top);
    let at = ring.iter().position(|&v| v == vn).unwrap();
    let across = ring[(at + 2) % ring.len()];
    let cut = run.ok(euler(
        bx,
        json!({"op": "mkfe", "v1": vn, "face": top, "v2": across}),
    ));
    // KLFE reports the face that survives.
    let top = run
        .ok(euler(bx, json!({"op": "klfe", "edge": cut.edge.unwrap()})))
        .face
        .unwrap();
    run.ok(euler(bx, json!({"op": "klev", "vertex": vn})));
    let ring = run.face_vertices(bx, top);
    let spur = run.ok(euler(
        bx,
        json!({"op": "mkev", "face": top, "vertex": ring[0], "position": [0.1, 0.1, 1.0]}),
    ));
    run.ok(euler(bx, json!({"op": "klve", "edge": spur.edge.unwrap()})));
    let e1 = run.edges(bx)[3];
    run.ok(euler(bx, json!({"op": "invert", "edge": e1})));
    run.ok(euler(bx, json!({"op": "invert", "edge": e1})));
    run.refused(euler(bx, json!({"op": "esplit", "edge": 999_999})));
    run.refused(euler(
        bx,
        json!({"op": "mkfe", "v1": ring[0], "face": top, "v2": ring[0]}),
    ));

    // GLUE two boxes into one, then UNGLUE them along the seam.
    let ga = id(&run.ok(create(
        "glue a",
        json!({"type": "box", "size": [2.0, 2.0, 2.0]}),
    )));
    let gb = id(&run.ok(create_at(
        "glue b",
        [2.0, 0.0, 0.0],
        json!({"type": "box", "size": [2.0, 2.0, 2.0]}),
    )));
    let fa = run.face_towards(ga, [1.0, 0.0, 0.0]);
    let fb = run.face_towards(gb, [-1.0, 0.0, 0.0]);
    let seam = run.face_edges(ga, fa);
    let glued = run.ok(euler(ga, json!({"op": "glue", "face1": fa, "face2": fb})));
    assert_eq!(glued.killed, vec![gb]);
    let cut = run.ok(euler(ga, json!({"op": "unglue", "edges": seam})));
    assert!(cut.split_off.is_some());
    // GLUEFF: a tube between two boxes.
    let ta = id(&run.ok(create_at(
        "tube a",
        [0.0, 6.0, 0.0],
        json!({"type": "box", "size": [1.0, 1.0, 1.0]}),
    )));
    let tb = id(&run.ok(create_at(
        "tube b",
        [0.0, 9.0, 0.0],
        json!({"type": "box", "size": [1.0, 1.0, 1.0]}),
    )));
    let (f1, f2) = (
        run.face_towards(ta, [0.0, 1.0, 0.0]),
        run.face_towards(tb, [0.0, -1.0, 0.0]),
    );
    let tube = run.ok(euler(ta, json!({"op": "glueff", "face1": f1, "face2": f2})));
    assert!(!tube.new_edges.is_empty());
    assert_eq!(tube.killed, vec![tb]);

    // Patches: rename, unname, re-parent, pose; cycles, duplicates and the root refused.
    let p = id(&run.ok(create_at(
        "P",
        [5.0, 0.0, 0.0],
        json!({"type": "box", "size": [1.0, 1.0, 1.0]}),
    )));
    let q = id(&run.ok(json!({"edit": "create_body", "name": "Q", "parent": p, "shape": {"type": "box", "size": [0.5, 0.5, 0.5]},
                              "pose": {"position": [0.0, 0.0, 1.0]}})));
    let r = id(&run.ok(json!({"edit": "create_body", "name": "R", "parent": q, "shape": {"type": "tetrahedron", "radius": 0.3}})));
    run.ok(patch(r, json!({"parent": p})));
    run.ok(patch(r, json!({"parent": q, "name": "R2", "pose": {"position": [0.0, 0.5, 0.0], "rotation": [0.0, 0.0, 0.6, 0.8]}})));
    run.ok(patch(q, json!({"name": null})));
    run.ok(patch(cyl, json!({"parent": bx})));
    run.refused(patch(p, json!({"parent": r})));
    run.refused(patch(r, json!({"name": "P"})));
    run.refused(patch(1, json!({"name": "root"})));
    run.refused(patch(
        q,
        json!({"pose": {"rotation": [0.0, 0.0, 0.0, 0.0]}}),
    ));
    run.refused(patch(q, json!({"name": "ok", "parent": 999_999})));

    // Transforms of bodies, faces and vertices, in both frames.
    run.ok(transform(
        tet,
        json!({"op": "translate", "vector": [0.0, 0.0, 2.0]}),
    ));
    run.ok(transform(tet, json!({"op": "rotate", "axis": [0.0, 0.0, 1.0], "angle_deg": 30.0, "center": [1.0, 0.0, 0.0], "frame": "body"})));
    run.ok(transform(poly, json!({"op": "dilate", "factor": 1.5})));
    run.ok(transform(
        poly,
        json!({"op": "reflect", "normal": [1.0, 0.0, 0.0]}),
    ));
    let pf = run
        .body(poly)
        .faces()
        .next()
        .map(|f| run.body(poly).face_serial(f).get())
        .unwrap();
    run.ok(transform(
        poly,
        json!({"op": "translate", "vector": [0.01, 0.02, 0.03], "target": pf}),
    ));
    let pv = run.face_vertices(poly, pf)[0];
    run.ok(transform(poly, json!({"op": "rotate", "axis": [0.0, 1.0, 0.0], "angle_deg": 5.0, "target": pv, "frame": "body"})));
    run.refused(transform(poly, json!({"op": "dilate", "factor": 0.0})));
    run.refused(transform(
        poly,
        json!({"op": "translate", "vector": [1.0, 0.0, 0.0], "target": e0}),
    ));

    // Sweeps, dual, evert, copy.
    let sw = id(&run.ok(create_at(
        "sweep",
        [0.0, -5.0, 0.0],
        json!({"type": "box", "size": [1.0, 1.0, 1.0]}),
    )));
    let up = run.face_towards(sw, [0.0, 0.0, 1.0]);
    let cap = run.ok(json!({"edit": "sweep", "body": sw, "req": {"face": up, "kind": "prism", "distance": 0.5}})).face.unwrap();
    run.ok(json!({"edit": "sweep", "body": sw, "req": {"face": cap, "kind": "cw_prismoid", "distance": 0.3, "scale": 0.5}}));
    let side = run.face_towards(sw, [1.0, 0.0, 0.0]);
    run.ok(json!({"edit": "sweep", "body": sw, "req": {"face": side, "kind": "ccw_prismoid", "distance": 0.2, "scale": 0.8}}));
    let back = run.face_towards(sw, [-1.0, 0.0, 0.0]);
    run.ok(json!({"edit": "sweep", "body": sw, "req": {"face": back, "kind": "pyramid", "distance": 0.4}}));
    let du = id(&run.ok(create_at(
        "dual",
        [0.0, 0.0, -5.0],
        json!({"type": "box", "size": [1.0, 1.0, 1.0]}),
    )));
    run.ok(json!({"edit": "dual", "body": du}));
    run.ok(json!({"edit": "evert", "body": tet}));
    run.ok(json!({"edit": "evert", "body": tet}));
    run.ok(json!({"edit": "copy", "body": bx, "name": "box copy"}));
    run.ok(json!({"edit": "copy", "body": poly}));
    run.refused(json!({"edit": "copy", "body": bx, "name": "box copy"}));
    run.refused(json!({"edit": "copy", "body": 1}));

    // A boolean's result as the journal keeps it: polygons in the kept body's frame,
    // placed (the first replacing that body, the others beside it) without the kernel.
    let ba = id(&run.ok(create_at(
        "boolean a",
        [0.0, 12.0, 0.0],
        json!({"type": "box", "size": [2.0, 2.0, 2.0]}),
    )));
    let bb = id(&run.ok(create_at(
        "boolean b",
        [1.0, 12.0, 0.5],
        json!({"type": "box", "size": [2.0, 2.0, 2.0]}),
    )));
    let piece = |x0: f64| {
        let corner = |i: u32| {
            json!([
                x0 + f64::from(i & 1),
                f64::from((i >> 1) & 1) - 0.5,
                f64::from((i >> 2) & 1) - 0.5
            ])
        };
        json!({
            "positions": (0..8).map(corner).collect::<Vec<_>>(),
            "faces": [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
        })
    };
    let boolean = |body: u64, with: u64, pieces: Vec<Value>| {
        json!({"edit": "boolean", "body": body, "with": with, "keep_with": false,
               "op": "difference", "pieces": pieces})
    };
    run.refused(boolean(ba, ba, vec![piece(0.0)]));
    run.refused(boolean(ba, 999_999, vec![piece(0.0)]));
    let mut open = piece(0.0);
    open["faces"].as_array_mut().unwrap().pop();
    run.refused(boolean(ba, bb, vec![open]));
    let o = run.ok(boolean(ba, bb, vec![piece(-1.0), piece(0.5)]));
    assert_eq!(o.killed, vec![bb]);
    assert_eq!(o.pieces.as_ref().map(Vec::len), Some(2));

    // Cameras and lights.
    let intr =
        json!({"width": 640, "height": 480, "fx": 600.0, "fy": 600.0, "cx": 320.0, "cy": 240.0});
    run.ok(json!({"edit": "put_camera", "name": "eye", "camera": {"pose": {"position": [0.0, -3.0, 1.0], "rotation": [0.6, 0.0, 0.0, 0.8]}, "intrinsics": intr}}));
    run.ok(json!({"edit": "put_camera", "name": "eye2", "camera": {"look_at": {"eye": [2.0, 2.0, 2.0], "target": [0.0, 0.0, 0.0]},
                  "baumgart": {"focal": 35.0, "ldx": 640, "ldy": 480, "pdx": 36.0, "pdy": 27.0}}}));
    run.ok(json!({"edit": "put_camera", "name": "eye", "camera": {"look_at": {"eye": [1.0, -4.0, 2.0], "target": [0.0, 0.0, 0.5]}, "intrinsics": intr}}));
    run.refused(json!({"edit": "put_camera", "name": "both", "camera": {"pose": {}, "look_at": {"eye": [1.0, 0.0, 0.0], "target": [0.0, 0.0, 0.0]}, "intrinsics": intr}}));
    run.refused(json!({"edit": "put_camera", "name": " spaced ", "camera": {"pose": {}, "intrinsics": intr}}));
    run.ok(json!({"edit": "delete_camera", "name": "eye2"}));
    run.refused(json!({"edit": "delete_camera", "name": "eye2"}));
    run.ok(json!({"edit": "put_light", "name": "sun", "light": {"type": "sun", "direction": [-0.3, 0.5, -1.0]}}));
    run.ok(json!({"edit": "put_light", "name": "lamp", "light": {"type": "point", "position": [0.0, 0.0, 3.0], "intensity": 0.7}}));
    run.ok(json!({"edit": "put_light", "name": "lamp", "light": {"type": "point", "position": [1.0, 0.0, 3.0], "intensity": 0.5}}));
    run.refused(json!({"edit": "put_light", "name": "dark", "light": {"type": "sun", "direction": [0.0, 0.0, 0.0]}}));
    run.ok(json!({"edit": "delete_light", "name": "sun"}));
    run.refused(json!({"edit": "delete_light", "name": "sun"}));

    // A long stretch of server-like writes, then deletes (a body with its parts, too).
    random_writes(&mut run, &[bx, tet, cyl, p, q, r, sw], 1500, 7);
    let o = run.ok(json!({"edit": "delete_body", "body": p}));
    assert_eq!(o.killed.len(), 3, "P with Q and R");
    run.refused(json!({"edit": "delete_body", "body": tb}));
    run.ok(json!({"edit": "delete_body", "body": ta}));
    run.refused(json!({"edit": "delete_body", "body": p}));
    run.refused(json!({"edit": "delete_body", "body": 1}));
    random_writes(&mut run, &[bx, tet, cyl], 300, 11);
    run
}

// ------------------------------------------------------------------ determinism

#[test]
fn a_journaled_edit_sequence_replays_to_the_same_world_entity_by_entity() {
    let mut run = varied_run();
    assert!(
        run.refused > 100,
        "refused edits were tried: {}",
        run.refused
    );
    let (mut store, rec) = run.recover();
    assert_eq!(rec.snapshot, None);
    assert_eq!(rec.replayed, run.world.revision());
    let conn = rusqlite::Connection::open(store.journal_path()).unwrap();
    let rows: i64 = conn
        .query_row("SELECT count(*) FROM journal", [], |r| r.get(0))
        .unwrap();
    assert_eq!(
        rows as u64,
        run.world.revision(),
        "refused edits are not journaled"
    );
    assert_eq!(store.journal_len(), run.world.revision());
    assert_same_world(&run.world, &rec.world);
    assert_valid_like(&rec.world, &run.world);

    // One more edit on each world makes the same ids.
    let mut recovered = rec.world;
    let next = [
        create(
            "after",
            json!({"type": "cylinder", "radius": 0.2, "height": 0.4, "segments": 5}),
        ),
        euler(
            run.log[0].2.id.unwrap(),
            json!({"op": "esplit", "edge": run.edges(run.log[0].2.id.unwrap())[0]}),
        ),
    ];
    for e in next {
        let edit: Edit = serde_json::from_value(e).unwrap();
        let a = apply(&mut run.world, &edit).unwrap();
        let b = apply(&mut recovered, &edit).unwrap();
        assert_eq!(a, b);
        assert!(a.id.is_some());
        store
            .append(
                &[Entry::new(recovered.revision(), &edit)],
                recovered.next_serial(),
            )
            .unwrap();
    }
    assert_same_world(&run.world, &recovered);
}

// ------------------------------------------------------------------ snapshots

/// A run with a few bodies and `n` random writes.
fn plain_run(n: usize, seed: u64) -> (Run, Vec<u64>) {
    let mut run = Run::new();
    let mut bodies = Vec::new();
    for i in 0..6 {
        let shape = if i % 2 == 0 {
            json!({"type": "box", "size": [1.0, 0.5, 0.25]})
        } else {
            json!({"type": "cylinder", "radius": 0.3, "height": 0.5, "segments": 7})
        };
        bodies.push(id(&run.ok(create(&format!("b{i}"), shape))));
    }
    random_writes(&mut run, &bodies, n, seed);
    run.flush();
    (run, bodies)
}

#[test]
fn a_snapshot_plus_the_journal_tail_recovers_the_same_world() {
    let (mut run, bodies) = plain_run(300, 1);
    let snap = write_snapshot(run.dir.path(), &run.world).unwrap();
    assert_eq!(snap.revision, run.world.revision());
    assert_eq!(
        snap.path.file_name().unwrap().to_str().unwrap(),
        format!("{:012}.snap", snap.revision)
    );
    assert_eq!(snap.bytes, std::fs::metadata(&snap.path).unwrap().len());
    random_writes(&mut run, &bodies, 200, 2);
    let (_, rec) = run.recover();
    assert_eq!(rec.snapshot, Some(snap.revision));
    assert_eq!(rec.replayed, run.world.revision() - snap.revision);
    assert_same_world(&run.world, &rec.world);
    assert_valid_like(&rec.world, &run.world);
}

#[test]
fn a_snapshot_round_trip_is_bit_exact() {
    let run = varied_run();
    let bytes = snapshot::encode(&run.world);
    let back = snapshot::decode(&bytes).unwrap();
    assert_eq!(snapshot::encode(&back), bytes);
    assert_same_world(&run.world, &back);
    let written = write_snapshot(run.dir.path(), &run.world).unwrap();
    assert_eq!(std::fs::read(&written.path).unwrap(), bytes);
    assert_same_world(&run.world, &read_snapshot(&written.path).unwrap());
}

#[test]
fn only_the_newest_two_snapshots_are_kept() {
    let (mut run, bodies) = plain_run(20, 3);
    let mut revisions = Vec::new();
    for k in 0..4 {
        let s = write_snapshot(run.dir.path(), &run.world).unwrap();
        revisions.push(s.revision);
        if k > 0 {
            assert_eq!(s.oldest_kept, revisions[k - 1]);
        }
        random_writes(&mut run, &bodies, 5, 10 + k as u64);
    }
    let kept: Vec<u64> = run
        .store()
        .snapshots()
        .unwrap()
        .iter()
        .map(|s| s.revision)
        .collect();
    assert_eq!(kept, revisions[2..].to_vec());
}

/// Flips one payload byte of the snapshot file at `path`.
fn flip_a_byte(path: &Path) {
    let mut bytes = std::fs::read(path).unwrap();
    let at = bytes.len() / 2;
    bytes[at] ^= 0x10;
    std::fs::write(path, bytes).unwrap();
}

fn truncate(path: &Path) {
    let bytes = std::fs::read(path).unwrap();
    std::fs::write(path, &bytes[..bytes.len() - 100]).unwrap();
}

#[test]
fn a_damaged_newest_snapshot_falls_back_to_the_older_one() {
    for damage in [flip_a_byte as fn(&Path), truncate] {
        let (mut run, bodies) = plain_run(100, 4);
        let older = write_snapshot(run.dir.path(), &run.world).unwrap();
        random_writes(&mut run, &bodies, 50, 5);
        let newer = write_snapshot(run.dir.path(), &run.world).unwrap();
        random_writes(&mut run, &bodies, 50, 6);
        damage(&newer.path);
        assert!(read_snapshot(&newer.path).is_err());
        let (_, rec) = run.recover();
        assert_eq!(rec.snapshot, Some(older.revision));
        assert_eq!(rec.skipped_snapshots, 1);
        assert_same_world(&run.world, &rec.world);
    }
}

#[test]
fn a_damaged_snapshot_whose_journal_was_pruned_is_a_clear_error() {
    let (mut run, bodies) = plain_run(100, 8);
    let older = write_snapshot(run.dir.path(), &run.world).unwrap();
    random_writes(&mut run, &bodies, 50, 9);
    let newer = write_snapshot(run.dir.path(), &run.world).unwrap();
    assert_eq!(newer.oldest_kept, older.revision);
    random_writes(&mut run, &bodies, 50, 10);
    run.flush();
    // Pruning through the newest snapshot (instead of `oldest_kept`) leaves nothing to
    // bridge from the older one.
    let deleted = run.store().prune_through(newer.revision).unwrap();
    assert_eq!(deleted, newer.revision);
    assert_eq!(run.store().first_revision(), Some(newer.revision + 1));
    let (_, rec) = run.recover();
    assert_eq!(rec.snapshot, Some(newer.revision));
    assert_same_world(&run.world, &rec.world);

    flip_a_byte(&newer.path);
    run.close();
    let mut store = Store::open(run.dir.path(), options()).unwrap();
    match store.recover(|_, _, _, _| {}) {
        Err(StoreError::Gap {
            snapshot,
            expected,
            found,
            skipped_snapshots,
            ..
        }) => {
            assert_eq!(snapshot, Some(older.revision));
            assert_eq!(expected, older.revision + 1);
            assert_eq!(found, newer.revision + 1);
            assert_eq!(skipped_snapshots, 1);
        }
        other => panic!("expected a gap, got {other:?}"),
    }
    let msg = store.recover(|_, _, _, _| {}).unwrap_err().to_string();
    assert!(
        msg.contains("is missing") && msg.contains("unreadable snapshot"),
        "{msg}"
    );
}

#[test]
fn a_damaged_snapshot_newer_than_everything_else_is_not_silently_lost() {
    let (mut run, bodies) = plain_run(60, 12);
    let older = write_snapshot(run.dir.path(), &run.world).unwrap();
    random_writes(&mut run, &bodies, 30, 13);
    run.flush();
    let newer = write_snapshot(run.dir.path(), &run.world).unwrap();
    run.store().prune_through(newer.revision).unwrap();
    assert_eq!(run.store().journal_len(), 0);
    truncate(&newer.path);
    run.close();
    let mut store = Store::open(run.dir.path(), options()).unwrap();
    match store.recover(|_, _, _, _| {}) {
        Err(StoreError::Unrecoverable {
            newest, recovered, ..
        }) => {
            assert_eq!((newest, recovered), (newer.revision, older.revision));
        }
        other => panic!("expected an unrecoverable directory, got {other:?}"),
    }
}

#[test]
fn a_snapshot_with_a_valid_checksum_but_an_unsound_world_is_refused() {
    let (run, _) = plain_run(10, 14);
    // Break one edge link (a wing naming a slot that does not exist) in a world that
    // otherwise decodes.
    let mut v = serde_json::to_value(&run.world).unwrap();
    let nodes = v["tree"]["nodes"].as_object_mut().unwrap();
    let (_, node) = nodes.iter_mut().find(|(k, _)| k.as_str() != "1").unwrap();
    node["body"]["edges"]["items"][0]["cw"][0] = json!(4000);
    let broken: World = serde_json::from_value(v).unwrap();
    assert!(check_world(&broken).is_err());
    let bytes = snapshot::encode(&broken);
    assert!(matches!(
        snapshot::decode(&bytes),
        Err(SnapshotError::Invalid(_))
    ));

    // An arena whose free list names a live slot does not even decode.
    let mut v = serde_json::to_value(&run.world).unwrap();
    let nodes = v["tree"]["nodes"].as_object_mut().unwrap();
    let (_, node) = nodes.iter_mut().find(|(k, _)| k.as_str() != "1").unwrap();
    node["body"]["faces"]["free"] = json!([0]);
    assert!(serde_json::from_value::<World>(v).is_err());
}

#[test]
fn a_snapshot_whose_root_is_posed_is_refused() {
    // The world never poses its root, and world poses are composed below it on that
    // understanding: a snapshot with a posed root is unsound.
    let (run, _) = plain_run(5, 16);
    let root = run.world.root().get().to_string();
    let mut v = serde_json::to_value(&run.world).unwrap();
    v["tree"]["nodes"][root.as_str()]["pose"]["position"] = json!([1.0, 0.0, 0.0]);
    let broken: World = serde_json::from_value(v).unwrap();
    let problem = check_world(&broken).unwrap_err();
    assert!(problem.contains("root's pose"), "{problem}");
    assert!(matches!(
        snapshot::decode(&snapshot::encode(&broken)),
        Err(SnapshotError::Invalid(_))
    ));
}

#[test]
fn snapshot_header_checks() {
    let (run, _) = plain_run(5, 15);
    let good = snapshot::encode(&run.world);
    let mut bad_magic = good.clone();
    bad_magic[0] = b'X';
    assert!(matches!(
        snapshot::decode(&bad_magic),
        Err(SnapshotError::BadMagic)
    ));
    let mut newer = good.clone();
    newer[8] = 9;
    assert!(matches!(
        snapshot::decode(&newer),
        Err(SnapshotError::UnsupportedVersion { found: 9 })
    ));
    let mut revision = good.clone();
    revision[12] ^= 1;
    assert!(matches!(
        snapshot::decode(&revision),
        Err(SnapshotError::Checksum { .. })
    ));
    assert!(matches!(
        snapshot::decode(&good[..good.len() - 1]),
        Err(SnapshotError::Length { .. })
    ));
    assert!(matches!(
        snapshot::decode(&good[..10]),
        Err(SnapshotError::Length { .. })
    ));
    // A file renamed to another revision's name is not taken for it.
    let snaps = snapshot::snapshots_dir(run.dir.path());
    let wrong = snaps.join(snapshot::file_name(run.world.revision() + 5));
    std::fs::write(&wrong, &good).unwrap();
    assert!(matches!(
        read_snapshot(&wrong),
        Err(SnapshotError::Revision(_))
    ));
}

// ------------------------------------------------------------------ the journal

#[test]
fn a_hole_in_the_journal_is_refused() {
    let (mut run, _) = plain_run(30, 16);
    let conn = rusqlite::Connection::open(run.store().journal_path()).unwrap();
    conn.execute("DELETE FROM journal WHERE revision = 17", [])
        .unwrap();
    run.close();
    let mut store = Store::open(run.dir.path(), options()).unwrap();
    let err = store.recover(|_, _, _, _| {}).unwrap_err();
    assert!(
        matches!(
            err,
            StoreError::Gap {
                expected: 17,
                found: 18,
                snapshot: None,
                ..
            }
        ),
        "{err:?}"
    );
    // A journal that starts after revision 1 with no snapshot before it.
    conn.execute("DELETE FROM journal WHERE revision < 17", [])
        .unwrap();
    drop(store);
    let mut store = Store::open(run.dir.path(), options()).unwrap();
    let err = store.recover(|_, _, _, _| {}).unwrap_err();
    assert!(
        matches!(
            err,
            StoreError::Gap {
                expected: 1,
                found: 18,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("revision 1 is missing"), "{err}");
}

#[test]
fn an_unreadable_or_refused_entry_stops_recovery_with_its_revision() {
    let (mut run, _) = plain_run(10, 17);
    let conn = rusqlite::Connection::open(run.store().journal_path()).unwrap();
    conn.execute(
        "UPDATE journal SET edit = '{\"edit\": \"nonsense\"}' WHERE revision = 9",
        [],
    )
    .unwrap();
    run.close();
    let mut store = Store::open(run.dir.path(), options()).unwrap();
    let err = store.recover(|_, _, _, _| {}).unwrap_err();
    assert!(
        matches!(err, StoreError::Decode { revision: 9, .. }),
        "{err:?}"
    );
    conn.execute(
        "UPDATE journal SET edit = '{\"edit\": \"delete_body\", \"body\": 424242}' WHERE revision = 9",
        [],
    )
    .unwrap();
    let err = store.recover(|_, _, _, _| {}).unwrap_err();
    assert!(
        matches!(err, StoreError::Refused { revision: 9, .. }),
        "{err:?}"
    );
}

#[test]
fn a_failed_append_leaves_none_of_its_batch() {
    let (mut run, bodies) = plain_run(10, 18);
    let last = run.world.revision();
    // Make SQLite fail on the third entry of the next batch.
    let conn = rusqlite::Connection::open(run.store().journal_path()).unwrap();
    conn.execute_batch(&format!(
        "CREATE TRIGGER fail BEFORE INSERT ON journal WHEN NEW.revision = {}
         BEGIN SELECT RAISE(ABORT, 'refused by test'); END;",
        last + 3
    ))
    .unwrap();
    let mut world = run.world.clone();
    let mut batch = Vec::new();
    for (k, &body) in bodies.iter().enumerate().take(5) {
        let edit: Edit = serde_json::from_value(patch(
            body,
            json!({"pose": {"position": [k as f64, 0.0, 0.0]}}),
        ))
        .unwrap();
        apply(&mut world, &edit).unwrap();
        batch.push((world.revision(), edit));
    }
    let entries: Vec<(u64, &Edit)> = batch.iter().map(|(r, e)| (*r, e)).collect();
    let err = run
        .store()
        .append(&as_entries(&entries), world.next_serial())
        .unwrap_err();
    assert!(matches!(err, StoreError::Sqlite { .. }), "{err:?}");
    assert!(err.to_string().contains("refused by test"), "{err}");
    let count: i64 = conn
        .query_row(
            "SELECT count(*) FROM journal WHERE revision > ?1",
            [last as i64],
            |r| r.get(0),
        )
        .unwrap();
    assert_eq!(count, 0, "none of the batch is in the journal");
    assert_eq!(run.store().last_revision(), Some(last));
    // Once the cause is gone the same batch goes in.
    conn.execute_batch("DROP TRIGGER fail").unwrap();
    run.store()
        .append(&as_entries(&entries), world.next_serial())
        .unwrap();
    assert_eq!(run.store().last_revision(), Some(last + 5));
    run.close();
    run.close();
    let mut store = Store::open(run.dir.path(), options()).unwrap();
    let rec = store.recover(|_, _, _, _| {}).unwrap();
    assert_same_world(&world, &rec.world);
}

#[test]
fn appends_must_continue_the_journal() {
    let (mut run, bodies) = plain_run(5, 19);
    let last = run.world.revision();
    let edit: Edit = serde_json::from_value(patch(
        bodies[0],
        json!({"pose": {"position": [1.0, 2.0, 3.0]}}),
    ))
    .unwrap();
    for (entries, expected, found) in [
        (vec![(last + 2, &edit)], last + 1, last + 2),
        (vec![(last, &edit)], last + 1, last),
        (
            vec![(last + 1, &edit), (last + 3, &edit)],
            last + 2,
            last + 3,
        ),
    ] {
        let next_serial = run.world.next_serial();
        match run.store().append(&as_entries(&entries), next_serial) {
            Err(StoreError::OutOfOrder {
                expected: e,
                found: f,
            }) => {
                assert_eq!((e, f), (expected, found));
            }
            other => panic!("expected out of order, got {other:?}"),
        }
    }
    assert_eq!(run.store().last_revision(), Some(last));
}

#[test]
fn a_newer_journal_format_or_a_foreign_file_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    drop(Store::open(dir.path(), options()).unwrap());
    let path = dir.path().join("journal.db");
    let conn = rusqlite::Connection::open(&path).unwrap();
    conn.execute(
        "UPDATE meta SET value = 99 WHERE key = 'format_version'",
        [],
    )
    .unwrap();
    drop(conn);
    match Store::open(dir.path(), options()) {
        Err(StoreError::UnsupportedVersion {
            found, supported, ..
        }) => assert_eq!((found, supported), (99, 2)),
        other => panic!("expected an unsupported version, got {:?}", other.err()),
    }
    let other = tempfile::tempdir().unwrap();
    std::fs::write(other.path().join("journal.db"), vec![7u8; 8192]).unwrap();
    let err = Store::open(other.path(), options()).err().unwrap();
    assert!(matches!(err, StoreError::NotAJournal { .. }), "{err:?}");
    let foreign = tempfile::tempdir().unwrap();
    let conn = rusqlite::Connection::open(foreign.path().join("journal.db")).unwrap();
    conn.execute_batch("CREATE TABLE t(x)").unwrap();
    drop(conn);
    let err = Store::open(foreign.path(), options()).err().unwrap();
    assert!(matches!(err, StoreError::NotAJournal { .. }), "{err:?}");
}

#[test]
fn a_fresh_directory_is_seeded_by_a_snapshot_and_journaling_continues_from_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut store = Store::open(
        &dir.path().join("new").join("data"),
        StoreOptions::default(),
    )
    .unwrap();
    assert!(store.is_fresh().unwrap());
    let demo = winged::server::demo::demo_world().unwrap();
    store.write_snapshot(&demo).unwrap();
    assert!(!store.is_fresh().unwrap());
    let rec = store
        .recover(|_, _, _, _| panic!("nothing to replay"))
        .unwrap();
    assert_eq!(rec.snapshot, Some(demo.revision()));
    assert_same_world(&demo, &rec.world);
    let mut world = rec.world;
    let edit: Edit = serde_json::from_value(create(
        "new",
        json!({"type": "box", "size": [1.0, 1.0, 1.0]}),
    ))
    .unwrap();
    apply(&mut world, &edit).unwrap();
    store
        .append(&[Entry::new(world.revision(), &edit)], world.next_serial())
        .unwrap();
    assert_eq!(store.journal_len(), 1);
    drop(store);
    let mut store = Store::open(
        &dir.path().join("new").join("data"),
        StoreOptions::default(),
    )
    .unwrap();
    let rec = store.recover(|_, _, _, _| {}).unwrap();
    assert_eq!(rec.replayed, 1);
    assert_same_world(&world, &rec.world);
}

#[test]
fn a_copied_snapshot_file_alone_restores_the_world() {
    let (run, _) = plain_run(40, 20);
    let snap = write_snapshot(run.dir.path(), &run.world).unwrap();
    let restore = tempfile::tempdir().unwrap();
    let snaps = snapshot::snapshots_dir(restore.path());
    std::fs::create_dir_all(&snaps).unwrap();
    std::fs::copy(&snap.path, snaps.join(snap.path.file_name().unwrap())).unwrap();
    let mut store = Store::open(restore.path(), options()).unwrap();
    let rec = store.recover(|_, _, _, _| {}).unwrap();
    assert_same_world(&run.world, &rec.world);
    assert_eq!(rec.replayed, 0);
}

#[test]
fn pruning_keeps_recovery_exact_and_shrinks_the_journal() {
    let (mut run, bodies) = plain_run(200, 21);
    let first = write_snapshot(run.dir.path(), &run.world).unwrap();
    random_writes(&mut run, &bodies, 100, 22);
    run.flush();
    let second = write_snapshot(run.dir.path(), &run.world).unwrap();
    random_writes(&mut run, &bodies, 100, 23);
    run.flush();
    let before = run.store().journal_len();
    let deleted = run.store().prune_through(second.oldest_kept).unwrap();
    assert_eq!(deleted, first.revision);
    assert_eq!(run.store().journal_len(), before - deleted);
    assert_eq!(run.store().first_revision(), Some(first.revision + 1));
    // Even with the newest snapshot damaged, the older one and the journal suffice.
    flip_a_byte(&second.path);
    let (_, rec) = run.recover();
    assert_eq!(rec.snapshot, Some(first.revision));
    assert_same_world(&run.world, &rec.world);
}

#[test]
fn a_journal_that_ends_before_the_snapshot_is_dropped_and_appends_continue() {
    let (mut run, bodies) = plain_run(30, 24);
    // The snapshot is ahead of the journal: its last writes were never journaled.
    let mut ahead = run.world.clone();
    // Each a move to another place: a patch that changes nothing is no revision.
    let lift = |z: f64| -> Edit {
        serde_json::from_value(patch(
            bodies[1],
            json!({"pose": {"position": [0.0, 0.0, z]}}),
        ))
        .unwrap()
    };
    for z in [9.0, 10.0, 11.0] {
        apply(&mut ahead, &lift(z)).unwrap();
    }
    let edit = lift(12.0);
    write_snapshot(run.dir.path(), &ahead).unwrap();
    run.close();
    let mut store = Store::open(run.dir.path(), options()).unwrap();
    let rec = store.recover(|_, _, _, _| {}).unwrap();
    assert_same_world(&ahead, &rec.world);
    assert_eq!(store.journal_len(), 0);
    let mut world = rec.world;
    apply(&mut world, &edit).unwrap();
    store
        .append(&[Entry::new(world.revision(), &edit)], world.next_serial())
        .unwrap();
    drop(store);
    let mut store = Store::open(run.dir.path(), options()).unwrap();
    let rec = store.recover(|_, _, _, _| {}).unwrap();
    assert_same_world(&world, &rec.world);
}

#[test]
fn errors_name_the_file_and_the_cause() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a file");
    std::fs::write(&file, b"not a directory").unwrap();
    let err = Store::open(&file.join("data"), options()).err().unwrap();
    let msg = err.to_string();
    assert!(matches!(err, StoreError::Io { .. }), "{err:?}");
    assert!(
        msg.contains("a file") && msg.contains("creating data directory"),
        "{msg}"
    );
    let err = write_snapshot(&file, &World::new()).unwrap_err();
    assert!(err.to_string().contains("snapshot"), "{err}");
}

#[test]
fn a_store_can_move_to_the_thread_that_owns_the_world() {
    fn send<T: Send>() {}
    send::<Store>();
    send::<StoreError>();
}

#[test]
fn the_journal_is_not_pruned_past_the_newest_snapshot() {
    let (mut run, bodies) = plain_run(20, 25);
    let last = run.world.revision();
    let err = run.store().prune_through(5).unwrap_err();
    assert!(
        matches!(
            err,
            StoreError::PruneBeyondSnapshot {
                revision: 5,
                newest: None
            }
        ),
        "{err:?}"
    );
    let snap = write_snapshot(run.dir.path(), &run.world).unwrap();
    random_writes(&mut run, &bodies, 5, 26);
    run.flush();
    let err = run.store().prune_through(snap.revision + 1).unwrap_err();
    assert!(
        err.to_string()
            .contains(&format!("newest snapshot is at {last}")),
        "{err}"
    );
    assert_eq!(run.store().first_revision(), Some(1));
    assert_eq!(
        run.store().prune_through(snap.revision).unwrap(),
        snap.revision
    );
}

// ------------------------------------------------------------------ range property

/// A number `sign · 10^exponent`: magnitudes from far below the world's smallest length
/// to far beyond its range.
fn magnitude(sign: bool, exponent: f64) -> f64 {
    let m = 10f64.powf(exponent);
    if sign { m } else { -m }
}

/// One random edit of the range property, drawn with its numbers across the whole range
/// and beyond: `(kind, which body, exponent, direction)`.
fn far_edit() -> impl proptest::strategy::Strategy<Value = (u8, usize, f64, [f64; 3], bool)> {
    use proptest::prelude::*;
    (
        0u8..11,
        0usize..8,
        prop_oneof![-14.0..14.0f64, -320.0..308.0f64],
        [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        any::<bool>(),
    )
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 32, ..Default::default() })]

    /// Random edits with numbers across the range and beyond it (reflections about far
    /// points, dilations by huge and tiny factors, rotations about axes of huge or tiny
    /// components, duals, copies, moves), journaled, snapshotted and recovered: every
    /// accepted sequence reloads to the same world, which passes the snapshot loader's
    /// checks; every refused edit changed nothing (the harness compares the encoded world).
    #[test]
    fn edits_across_and_beyond_the_range_always_reload(
        edits in proptest::collection::vec(far_edit(), 1..40),
    ) {
        let mut run = Run::new();
        run.ok(create("seed", json!({"type": "box", "size": [1.0, 2.0, 0.5]})));
        for (step, (kind, which, exponent, dir, sign)) in edits.into_iter().enumerate() {
            let x = magnitude(sign, exponent);
            let v = [dir[0] * x, dir[1] * x, dir[2] * x];
            let bodies: Vec<u64> = run.world.bodies().map(|(id, _)| id.get()).collect();
            if bodies.is_empty() {
                run.ok(create("again", json!({"type": "box", "size": [1.0, 1.0, 1.0]})));
                continue;
            }
            let b = bodies[which % bodies.len()];
            let edit = match kind {
                0 => create_at(&format!("c{step}"), v,
                               json!({"type": "box", "size": [x.abs(), 1.0, x.abs().sqrt()]})),
                1 => transform(b, json!({"op": "translate", "vector": v})),
                2 => transform(b, json!({"op": "reflect", "normal": dir, "point": v})),
                3 => transform(b, json!({"op": "dilate", "factor": x.abs(), "center": dir})),
                4 => transform(b, json!({"op": "rotate", "axis": v, "angle_deg": dir[0] * 180.0,
                                         "center": [dir[1] * 1e9, 0.0, 0.0]})),
                5 => json!({"edit": "dual", "body": b}),
                6 => json!({"edit": "copy", "body": b, "name": format!("k{step}")}),
                7 => patch(b, json!({"pose": {"position": v, "rotation": [0.0, 0.0, 0.0, 1.0]}})),
                8 => transform(b, json!({"op": "dilate", "factor": 10f64.powf(dir[0] * 3.0),
                                         "center": v})),
                9 => {
                    run.flush();
                    write_snapshot(run.dir.path(), &run.world).unwrap();
                    continue;
                }
                _ => {
                    let (store, rec) = run.recover();
                    assert_same_world(&run.world, &rec.world);
                    run.store = Some(store);
                    continue;
                }
            };
            if run.try_edit(edit).is_ok() {
                check_world(&run.world).unwrap_or_else(|e| panic!("step {step}: {e}"));
            }
        }
        let (_, rec) = run.recover();
        assert_same_world(&run.world, &rec.world);
        check_world(&rec.world).unwrap();
        // The bodies' figures are numbers, never overflowed.
        for (id, n) in rec.world.bodies() {
            let (a, v) = (n.body.surface_area(), n.body.volume());
            assert!(a.is_finite() && v.is_finite(), "body {id}: area {a}, volume {v}");
        }
    }
}

// ------------------------------------------------------------------ a journal of an older format

/// Where the fixture journal lives: a data directory written by the journal format of
/// 2026-11 (format version 1, written when the HTTP request types were the journal's
/// entries, tagged by `edit`), with the world it must recover to.
const FIXTURE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/fixtures/journal-2026-11"
);

/// The world as plain data, spelled with nothing but the kernel's accessors: every body
/// (name, supart, parts, pose and colour; each vertex's serial and exact locus; each
/// edge's serial, ends, faces and wings; each face's serial and vertex cycle), every
/// camera and light, the revision and the next serial. Two worlds with the same
/// fixture form are the same world to every reader.
fn fixture_form(w: &World) -> Value {
    let bits = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{:016x}", x.to_bits()))
            .collect::<Vec<_>>()
    };
    let bodies: Vec<Value> = w
        .tree()
        .iter()
        .map(|(id, n)| {
            let b = &n.body;
            let vs = |v| b.vertex_serial(v).get();
            let es = |e| b.edge_serial(e).get();
            let fs = |f| b.face_serial(f).get();
            let mut vertices: Vec<Value> = b
                .vertices()
                .map(|v| json!([vs(v), bits(&b.position(v).to_array())]))
                .collect();
            let mut edges: Vec<Value> = b
                .edges()
                .map(|e| {
                    let d = b.edge(e);
                    json!([
                        es(e),
                        vs(d.nvt()),
                        vs(d.pvt()),
                        fs(d.nface()),
                        fs(d.pface()),
                        es(d.ncw()),
                        es(d.pcw()),
                        es(d.nccw()),
                        es(d.pccw())
                    ])
                })
                .collect();
            let mut faces: Vec<Value> = b
                .faces()
                .map(|f| json!([fs(f), b.face_vertices(f).map(vs).collect::<Vec<_>>()]))
                .collect();
            let key = |v: &Value| v[0].as_u64().unwrap_or(0);
            vertices.sort_by_key(key);
            edges.sort_by_key(key);
            faces.sort_by_key(key);
            json!({
                "id": id.get(),
                "name": n.name,
                "supart": n.supart.get(),
                "parts": n.parts.iter().map(|p| p.get()).collect::<Vec<_>>(),
                "pose": [bits(&n.pose.position.to_array()), bits(&n.pose.rotation.to_array())],
                "color": n.color.map(|c| c.0),
                "vertices": vertices,
                "edges": edges,
                "faces": faces,
            })
        })
        .collect();
    let cameras: Vec<Value> = w
        .cameras()
        .map(|(name, c)| {
            let k = c.intrinsics;
            json!({"name": name,
                   "pose": [bits(&c.pose.position.to_array()), bits(&c.pose.rotation.to_array())],
                   "intrinsics": [k.width, k.height, bits(&[k.fx, k.fy, k.cx, k.cy])]})
        })
        .collect();
    let lights: Vec<Value> = w
        .lights()
        .map(|(name, l)| match l {
            winged::model::camera::Light::Sun {
                direction,
                intensity,
            } => json!({"name": name, "sun": bits(&direction.to_array()), "intensity": bits(&[*intensity])}),
            winged::model::camera::Light::Point {
                position,
                intensity,
            } => json!({"name": name, "point": bits(&position.to_array()), "intensity": bits(&[*intensity])}),
        })
        .collect();
    json!({
        "revision": w.revision(),
        "next_serial": w.next_serial().get(),
        "bodies": bodies,
        "cameras": cameras,
        "lights": lights,
    })
}

/// The fixture's edits, journaled now, recover to the world they made; with
/// `WINGED_WRITE_FIXTURE=1` the journal and its world are also written to
/// `tests/fixtures` (only to make a fixture for a new journal format: the committed one
/// must stay as it was written).
#[test]
fn the_fixture_edits_journal_and_recover_to_their_world() {
    let mut run = varied_run();
    run.flush();
    run.close();
    let mut store = Store::open(run.dir.path(), options()).unwrap();
    let rec = store.recover(|_, _, _, _| {}).unwrap();
    assert_eq!(fixture_form(&rec.world), fixture_form(&run.world));
    drop(store);
    if std::env::var_os("WINGED_WRITE_FIXTURE").is_some() {
        let out = Path::new(FIXTURE);
        std::fs::create_dir_all(out).unwrap();
        for name in ["journal.db", "reached"] {
            std::fs::copy(run.dir.path().join(name), out.join(name)).unwrap();
        }
        let form = serde_json::to_string_pretty(&fixture_form(&run.world)).unwrap();
        std::fs::write(out.join("world.json"), form + "\n").unwrap();
    }
}

#[test]
fn a_journal_of_the_2026_11_format_recovers_to_the_world_it_recorded() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["journal.db", "reached"] {
        std::fs::copy(Path::new(FIXTURE).join(name), dir.path().join(name)).unwrap();
    }
    let want: Value = serde_json::from_str(
        &std::fs::read_to_string(Path::new(FIXTURE).join("world.json")).unwrap(),
    )
    .unwrap();
    let mut store = Store::open(dir.path(), options()).unwrap();
    let rec = store.recover(|_, _, _, _| {}).unwrap();
    assert_eq!(rec.snapshot, None, "the fixture is a journal alone");
    assert!(rec.replayed > 100, "{} entries", rec.replayed);
    assert_eq!(fixture_form(&rec.world), want);
    check_world(&rec.world).unwrap();
}

/// A journal of version 1 takes an entry of version 2 (an import, whose polygons are
/// packed) with its version raised in the same commit, and recovers through both.
#[test]
fn a_version_one_journal_is_raised_to_version_two_by_its_first_append() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["journal.db", "reached"] {
        std::fs::copy(Path::new(FIXTURE).join(name), dir.path().join(name)).unwrap();
    }
    let version = |dir: &Path| -> i64 {
        rusqlite::Connection::open(dir.join("journal.db"))
            .unwrap()
            .query_row(
                "SELECT value FROM meta WHERE key = 'format_version'",
                [],
                |r| r.get(0),
            )
            .unwrap()
    };
    let mut store = Store::open(dir.path(), options()).unwrap();
    let mut world = store.recover(|_, _, _, _| {}).unwrap().world;
    assert_eq!(
        version(dir.path()),
        1,
        "opening and recovering write nothing"
    );
    let import: Edit = serde_json::from_value(json!({
        "edit": "import_bodies",
        "bodies": [{
            "name": "imported tetrahedron",
            "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
            "faces": [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        }],
    }))
    .unwrap();
    apply(&mut world, &import).unwrap();
    store
        .append(
            &as_entries(&[(world.revision(), &import)]),
            world.next_serial(),
        )
        .unwrap();
    drop(store);
    assert_eq!(version(dir.path()), 2);
    let stored: String = rusqlite::Connection::open(dir.path().join("journal.db"))
        .unwrap()
        .query_row(
            "SELECT edit FROM journal ORDER BY revision DESC LIMIT 1",
            [],
            |r| r.get(0),
        )
        .unwrap();
    let stored: Value = serde_json::from_str(&stored).unwrap();
    let body = &stored["bodies"][0];
    assert!(
        body["vertices"].is_string() && body["faces"].is_string(),
        "packed: {stored}"
    );
    let mut store = Store::open(dir.path(), options()).unwrap();
    let rec = store.recover(|_, _, _, _| {}).unwrap();
    assert_eq!(fixture_form(&rec.world), fixture_form(&world));
    check_world(&rec.world).unwrap();
}

/// Every entry of the 2026-11 fixture reads as an edit of today's command language and
/// writes back as the same JSON: the commands' serde form is still format version 1.
#[test]
fn every_fixture_entry_reads_as_a_command_and_writes_back_the_same() {
    let conn = rusqlite::Connection::open_with_flags(
        Path::new(FIXTURE).join("journal.db"),
        rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY,
    )
    .unwrap();
    let mut query = conn.prepare("SELECT revision, edit FROM journal").unwrap();
    let entries: Vec<(i64, String)> = query
        .query_map([], |r| Ok((r.get(0)?, r.get(1)?)))
        .unwrap()
        .map(Result::unwrap)
        .collect();
    let mut kinds = std::collections::BTreeSet::new();
    for (revision, text) in &entries {
        let edit: Edit = serde_json::from_str(text)
            .unwrap_or_else(|e| panic!("entry {revision} does not read ({e}): {text}"));
        kinds.insert(edit.kind());
        let written = serde_json::to_value(&edit).unwrap();
        let stored: Value = serde_json::from_str(text).unwrap();
        assert_eq!(written, stored, "entry {revision} writes back otherwise");
    }
    assert_eq!(
        kinds.len(),
        13,
        "every kind of edit is in the fixture: {kinds:?}"
    );
}
