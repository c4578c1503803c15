//! Recovery time of a data directory:
//! `cargo run --release --example recovery -- [entries] [directory to keep it in]`.
//!
//! Builds a data directory in a temporary directory with `entries` (default 1,000,000)
//! journal entries of a server-like write mix: a few hundred boxes and cylinders made
//! up front (some attached to others), then pose patches, body transforms, ESPLIT/KLEV
//! and MKEV/KLEV pairs, and camera puts, appended 64 per transaction with
//! `Durability::Normal`. Then it times `Store::open` + `Store::recover`
//!
//! * (a) with no snapshot, replaying the whole journal, and
//! * (b) with a snapshot taken at about 99% of the entries,
//!
//! checks that both recovered worlds encode to the same bytes as the world that was
//! built, and prints entries, seconds, snapshot bytes and journal bytes. The journal is
//! in the page cache when it is timed (it was just written).

use std::path::Path;
use std::time::Instant;

use glam::{DQuat, DVec3};
use winged::edit::command::{
    CameraSpec, CreateBody, EulerOp, LookAt, Motion, Move, PatchBody, Shape,
};
use winged::edit::{Edit, apply};
use winged::model::{BodyId, Serial, World};
use winged::model::{Frame, Intrinsics, Pose};
use winged::store::{Durability, Entry, Store, StoreOptions, snapshot};

/// Bodies made before the mix of changes starts.
const BODIES: usize = 300;
/// Entries per append transaction, as a server batches concurrent writes.
const BATCH: usize = 64;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()),
        )
        .init();
    let entries: u64 = match std::env::args().nth(1) {
        Some(a) => a.parse()?,
        None => 1_000_000,
    };
    // A second argument keeps the data directory there (for profiling recovery alone).
    let tmp = tempfile::tempdir()?;
    let root = match std::env::args().nth(2) {
        Some(dir) => std::path::PathBuf::from(dir),
        None => tmp.path().to_owned(),
    };
    let data = root.join("data");
    let side = root.join("side");

    let started = Instant::now();
    let built = build(&data, &side, entries)?;
    println!(
        "built {} entries ({} bodies) in {:.2} s",
        built.revision(),
        built.body_count(),
        started.elapsed().as_secs_f64()
    );
    let expected = snapshot::encode(&built);

    // (a) The whole journal, no snapshot.
    let (secs, store, rec) = timed_recovery(&data)?;
    assert_eq!(rec.snapshot, None);
    if snapshot::encode(&rec.world) != expected {
        return Err("replaying the journal built a different world".into());
    }
    println!(
        "(a) no snapshot: replayed {} entries in {secs:.3} s; journal {} bytes ({} entries)",
        rec.replayed,
        store.journal_bytes(),
        store.journal_len()
    );
    drop(store);

    // (b) The snapshot taken at ~99%, then the journal's tail.
    let snap = snapshot::list(&side)?
        .pop()
        .ok_or("the side directory has no snapshot")?;
    let snap_bytes = std::fs::metadata(&snap.path)?.len();
    std::fs::copy(
        &snap.path,
        snapshot::snapshots_dir(&data).join(snapshot::file_name(snap.revision)),
    )?;
    let (secs, store, rec) = timed_recovery(&data)?;
    assert_eq!(rec.snapshot, Some(snap.revision));
    if snapshot::encode(&rec.world) != expected {
        return Err("the snapshot and the journal's tail built a different world".into());
    }
    println!(
        "(b) snapshot at revision {} ({snap_bytes} bytes) + {} entries replayed in {secs:.3} s; \
         journal {} bytes",
        snap.revision,
        rec.replayed,
        store.journal_bytes()
    );
    Ok(())
}

/// Opens `data` and recovers, timing both.
fn timed_recovery(
    data: &Path,
) -> Result<(f64, Store, winged::store::Recovered), winged::store::StoreError> {
    let t = Instant::now();
    let mut store = Store::open(data, StoreOptions::default())?;
    let rec = store.recover(|_, _, _, _| {})?;
    Ok((t.elapsed().as_secs_f64(), store, rec))
}

/// A small deterministic generator (xorshift64*), so every run builds the same journal.
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
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// Applies edits to a world and journals them in batches.
struct Builder {
    world: World,
    store: Store,
    pending: Vec<(u64, Edit)>,
}

impl Builder {
    /// Applies `edit` (it must be accepted) and queues it for the journal.
    fn push(&mut self, edit: Edit) -> Result<winged::edit::Outcome, Box<dyn std::error::Error>> {
        let outcome = apply(&mut self.world, &edit)?;
        self.pending.push((self.world.revision(), edit));
        if self.pending.len() == BATCH {
            self.flush()?;
        }
        Ok(outcome)
    }

    fn flush(&mut self) -> Result<(), winged::store::StoreError> {
        let batch: Vec<Entry<'_>> = self
            .pending
            .iter()
            .map(|(r, e)| Entry::new(*r, e))
            .collect();
        self.store.append(&batch, self.world.next_serial())?;
        self.pending.clear();
        Ok(())
    }
}

/// Builds the journal in `data` with `entries` entries; writes a snapshot of the world
/// at about 99% of them into `side`. Returns the final world.
fn build(data: &Path, side: &Path, entries: u64) -> Result<World, Box<dyn std::error::Error>> {
    let options = StoreOptions {
        durability: Durability::Normal,
        ..StoreOptions::default()
    };
    let mut b = Builder {
        world: World::new(),
        store: Store::open(data, options)?,
        pending: Vec::new(),
    };
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut bodies: Vec<u64> = Vec::new();
    let snapshot_at = entries * 99 / 100;
    let mut snapshotted = false;
    for i in 0..BODIES.min(entries as usize) {
        let shape = if i % 2 == 0 {
            Shape::Box {
                size: DVec3::new(
                    rng.range(0.1, 1.0),
                    rng.range(0.1, 1.0),
                    rng.range(0.1, 1.0),
                ),
            }
        } else {
            Shape::Cylinder {
                radius: rng.range(0.05, 0.5),
                height: rng.range(0.1, 1.0),
                segments: 16,
            }
        };
        // Every fourth body is a part of an earlier one.
        let parent = (i % 4 == 3).then(|| bodies[rng.below(bodies.len())]);
        let o = b.push(Edit::CreateBody(CreateBody {
            name: Some(format!("body{i}")),
            parent,
            pose: Some(random_pose(&mut rng)),
            color: None,
            shape,
        }))?;
        bodies.push(o.id.ok_or("a create answers with the id")?);
    }
    while b.world.revision() < entries {
        if !snapshotted && b.world.revision() >= snapshot_at && b.pending.is_empty() {
            winged::store::write_snapshot(side, &b.world)?;
            snapshotted = true;
        }
        let left = entries - b.world.revision();
        let body = bodies[rng.below(bodies.len())];
        let roll = rng.below(100);
        if roll < 40 {
            b.push(Edit::PatchBody {
                body,
                patch: PatchBody {
                    pose: Some(random_pose(&mut rng)),
                    ..PatchBody::default()
                },
            })?;
        } else if roll < 60 {
            let op = if rng.below(2) == 0 {
                Motion::Translate {
                    vector: DVec3::new(rng.range(-0.1, 0.1), rng.range(-0.1, 0.1), 0.0),
                }
            } else {
                Motion::Rotate {
                    axis: DVec3::Z,
                    angle_deg: rng.range(-10.0, 10.0),
                    center: DVec3::ZERO,
                }
            };
            b.push(Edit::Transform {
                body,
                motion: Move {
                    motion: op,
                    frame: Frame::World,
                    target: None,
                },
            })?;
        } else if roll < 75 && left >= 2 {
            // ESPLIT an edge, then KLEV the new vertex: the body is as before.
            let edge = nth_edge(&b.world, body, rng.below(12))?;
            let o = b.push(Edit::Euler {
                body,
                op: EulerOp::Esplit {
                    edge,
                    position: None,
                },
            })?;
            let vertex = o.vertex.ok_or("ESPLIT answers with the new vertex")?;
            b.push(Edit::Euler {
                body,
                op: EulerOp::Klev { vertex },
            })?;
        } else if roll < 85 && left >= 2 {
            // MKEV a spur into a face, then KLEV it.
            let (face, vertex) = face_and_vertex(&b.world, body, rng.below(6))?;
            let o = b.push(Edit::Euler {
                body,
                op: EulerOp::Mkev {
                    face,
                    vertex,
                    position: None,
                },
            })?;
            let vertex = o.vertex.ok_or("MKEV answers with the new vertex")?;
            b.push(Edit::Euler {
                body,
                op: EulerOp::Klev { vertex },
            })?;
        } else {
            let a = rng.range(0.0, std::f64::consts::TAU);
            b.push(Edit::PutCamera {
                name: format!("cam{}", rng.below(8)),
                camera: CameraSpec {
                    pose: None,
                    look_at: Some(LookAt {
                        eye: DVec3::new(3.0 * a.cos(), 3.0 * a.sin(), 1.5),
                        target: DVec3::new(0.0, 0.0, 0.5),
                        up: DVec3::Z,
                    }),
                    intrinsics: Some(Intrinsics {
                        width: 640,
                        height: 480,
                        fx: 600.0,
                        fy: 600.0,
                        cx: 320.0,
                        cy: 240.0,
                    }),
                    baumgart: None,
                },
            })?;
        }
    }
    b.flush()?;
    Ok(b.world)
}

fn random_pose(rng: &mut Rng) -> Pose {
    let half = rng.range(-1.5, 1.5);
    Pose {
        position: DVec3::new(
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
            rng.range(0.0, 1.0),
        ),
        rotation: DQuat::from_xyzw(0.0, 0.0, half.sin(), half.cos()),
    }
}

/// The serial of some edge of `body`.
fn nth_edge(world: &World, body: u64, n: usize) -> Result<u64, Box<dyn std::error::Error>> {
    let b = world.body(BodyId(Serial(body))).ok_or("a live body")?;
    let count = b.edge_count().max(1);
    let e = b.edges().nth(n % count).ok_or("a body with edges")?;
    Ok(b.edge_serial(e).get())
}

/// The serials of some face of `body` and a vertex on it.
fn face_and_vertex(
    world: &World,
    body: u64,
    n: usize,
) -> Result<(u64, u64), Box<dyn std::error::Error>> {
    let b = world.body(BodyId(Serial(body))).ok_or("a live body")?;
    let count = b.face_count().max(1);
    let f = b.faces().nth(n % count).ok_or("a body with faces")?;
    let v = b.face_vertices(f).next().ok_or("a face with vertices")?;
    Ok((b.face_serial(f).get(), b.vertex_serial(v).get()))
}
