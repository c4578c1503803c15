//! The winged side of the OpenMesh comparison (`bench/openmesh/run.sh`).
//!
//! Runs the same meshes, sizes and loops as `bench/openmesh/split_collapse.cpp` and
//! prints one line per measure, `name<TAB>value<TAB>unit`, timing each with
//! `std::time::Instant` and keeping the best of a few repetitions.
//!
//! ```text
//! cargo run --release --example kernel_peer
//! ```

#[path = "../bench/mesh.rs"]
mod mesh;

use std::hint::black_box;
use std::time::Instant;

use winged::model::{Body, EdgeId, FaceId, Serials, check_solid};

/// Repetitions of each timed loop; the best is reported. The perimeter walks are short
/// and noisy, so they run more often.
const REPS: usize = 3;
const WALK_REPS: usize = 10;
/// The small meshes: a 32 × 16 torus grid (1,024 triangles, or 512 quads).
const SMALL: (u32, u32) = (32, 16);
/// The big meshes: a 1000 × 500 torus grid (1,000,000 triangles, or 500,000 quads).
const BIG: (u32, u32) = (1000, 500);
/// Rounds over the small meshes, so that each timed loop runs about a million pairs.
const SMALL_ROUNDS_TRI: usize = 1000;
const SMALL_ROUNDS_QUAD: usize = 2000;

fn row(name: &str, value: f64, unit: &str) {
    println!("{name}\t{value:.2}\t{unit}");
}

/// Whether the measures named `names` should run: all of them without an argument, else
/// those whose name contains the first argument.
fn wanted(names: &[&str]) -> bool {
    match std::env::args().nth(1) {
        None => true,
        Some(filter) => names.iter().any(|n| n.contains(filter.as_str())),
    }
}

/// Best wall time of `reps` runs of `f`, in nanoseconds.
fn best_ns(reps: usize, mut f: impl FnMut()) -> f64 {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_nanos() as f64
        })
        .fold(f64::INFINITY, f64::min)
}

fn build<const N: usize>(s: &mut Serials, m: &mesh::Mesh<N>) -> Body {
    Body::from_polygons(s, &m.positions, &m.faces).expect("closed mesh")
}

/// ESPLIT each edge at its midpoint and KLEV the new vertex, `rounds` times over all
/// edges. Returns ns per pair.
fn esplit_klev(b: &mut Body, s: &mut Serials, rounds: usize) -> f64 {
    let edges: Vec<EdgeId> = b.edges().collect();
    let counts = (b.face_count(), b.edge_count(), b.vertex_count());
    let ns = best_ns(REPS, || {
        for _ in 0..rounds {
            for &e in &edges {
                let r = *b.edge(e);
                let pos = (b.position(r.vt[0]) + b.position(r.vt[1])) * 0.5;
                let (_, v) = b.esplit(s, e, pos).unwrap();
                black_box(b.klev(v).unwrap());
            }
        }
    });
    assert_eq!(counts, (b.face_count(), b.edge_count(), b.vertex_count()));
    ns / (rounds * edges.len()) as f64
}

/// Cut each quad by its diagonal (MKFE from its first vertex to its third) and KLFE the
/// new edge, `rounds` times over all faces. Returns ns per pair.
fn mkfe_klfe(b: &mut Body, s: &mut Serials, rounds: usize) -> f64 {
    let faces: Vec<FaceId> = b.faces().collect();
    let counts = (b.face_count(), b.edge_count(), b.vertex_count());
    let ns = best_ns(REPS, || {
        for _ in 0..rounds {
            for &f in &faces {
                let u0 = b.face_first_use(f).unwrap();
                let v0 = b.origin(u0);
                let v2 = b.origin(b.next(b.next(u0)));
                let (e, _) = b.mkfe(s, v0, f, v2).unwrap();
                black_box(b.klfe(e).unwrap());
            }
        }
    });
    assert_eq!(counts, (b.face_count(), b.edge_count(), b.vertex_count()));
    ns / (rounds * faces.len()) as f64
}

fn main() {
    let mut s = Serials::new();
    let big_tri = mesh::torus_triangles(BIG.0, BIG.1);

    // Edge split and its inverse.
    if wanted(&["esplit_klev_small"]) {
        let mut b = build(&mut s, &mesh::torus_triangles(SMALL.0, SMALL.1));
        let ns = esplit_klev(&mut b, &mut s, SMALL_ROUNDS_TRI);
        row("esplit_klev_small", ns, "ns/pair");
        assert!(check_solid(&b, 1e-9).is_ok());
    }
    if wanted(&["esplit_klev_1m"]) {
        let mut b = build(&mut s, &big_tri);
        row("esplit_klev_1m", esplit_klev(&mut b, &mut s, 1), "ns/pair");
    }

    // Face split by a diagonal and its inverse.
    if wanted(&["mkfe_klfe_small"]) {
        let mut b = build(&mut s, &mesh::torus_quads(SMALL.0, SMALL.1));
        let ns = mkfe_klfe(&mut b, &mut s, SMALL_ROUNDS_QUAD);
        row("mkfe_klfe_small", ns, "ns/pair");
        assert!(check_solid(&b, 1e-9).is_ok());
    }
    if wanted(&["mkfe_klfe_500k"]) {
        let mut b = build(&mut s, &mesh::torus_quads(BIG.0, BIG.1));
        row("mkfe_klfe_500k", mkfe_klfe(&mut b, &mut s, 1), "ns/pair");
    }

    // Building the million-triangle body.
    if wanted(&["build_1m"]) {
        let ns = best_ns(REPS, || {
            let mut s = Serials::new();
            black_box(build(&mut s, &big_tri));
        });
        row("build_1m", ns / 1e6, "ms");
    }

    if !wanted(&[
        "bytes_per_edge_1m",
        "face_vertices_1m",
        "vertex_vertices_1m",
    ]) {
        return;
    }
    // Its weight: heap bytes held by the body's arenas (`examples/memory.rs` checks
    // this figure against a counting allocator).
    let b = build(&mut s, &big_tri);
    if wanted(&["bytes_per_edge_1m"]) {
        let per_edge = b.heap_bytes() as f64 / b.edge_count() as f64;
        row("bytes_per_edge_1m", per_edge, "B/edge");
    }

    // Perimeter circulation.
    let mut uses = 0usize;
    if wanted(&["face_vertices_1m"]) {
        let ns = best_ns(WALK_REPS, || {
            let (mut n, mut acc) = (0usize, 0usize);
            for f in b.faces() {
                for v in b.face_vertices(f) {
                    n += 1;
                    acc = acc.wrapping_add(v.index());
                }
            }
            black_box(acc);
            uses = n;
        });
        row("face_vertices_1m", ns / uses as f64, "ns/use");
    }
    if wanted(&["vertex_vertices_1m"]) {
        let ns = best_ns(WALK_REPS, || {
            let (mut n, mut acc) = (0usize, 0usize);
            for v in b.vertices() {
                for u in b.vertex_uses(v) {
                    n += 1;
                    acc = acc.wrapping_add(b.dest(u).index());
                }
            }
            black_box(acc);
            uses = n;
        });
        row("vertex_vertices_1m", ns / uses as f64, "ns/use");
    }
}
