//! Kernel benchmarks: Euler operator pairs, building a million-triangle body, and
//! perimeter circulation. See BENCHMARKS.md for the figures and the goals.
//!
//! ```text
//! cargo bench --bench kernel                 # everything (about two minutes)
//! cargo bench --bench kernel -- esplit_klev  # one group
//! ```
//!
//! Every loop undoes what it does, so the body is the same (up to serial numbers and
//! slot reuse) after each iteration and iterations can run any number of times.

#[path = "../bench/mesh.rs"]
mod mesh;

use std::hint::black_box;
use std::time::Duration;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use winged::model::solids::mkcube;
use winged::model::{Body, EdgeId, FaceId, Serials};

/// The small meshes: a 32 × 16 torus grid (1,024 triangles, or 512 quads).
const SMALL: (u32, u32) = (32, 16);
/// The big meshes: a 1000 × 500 torus grid (1,000,000 triangles, or 500,000 quads).
const BIG: (u32, u32) = (1000, 500);

fn build<const N: usize>(s: &mut Serials, m: &mesh::Mesh<N>) -> Body {
    Body::from_polygons(s, &m.positions, &m.faces).expect("closed mesh")
}

/// One ESPLIT at the midpoint of each edge in turn, then KLEV of the new vertex.
fn esplit_klev_on(c: &mut Criterion, name: &str, mut b: Body, mut s: Serials) {
    let edges: Vec<EdgeId> = b.edges().collect();
    let mut k = 0;
    c.bench_function(name, |bench| {
        bench.iter(|| {
            let e = edges[k];
            k = if k + 1 == edges.len() { 0 } else { k + 1 };
            let r = *b.edge(e);
            let pos = (b.position(r.vt[0]) + b.position(r.vt[1])) * 0.5;
            let (_, v) = b.esplit(&mut s, e, pos).unwrap();
            black_box(b.klev(v).unwrap())
        })
    });
}

fn esplit_klev(c: &mut Criterion) {
    let mut s = Serials::new();
    let cube = mkcube(&mut s, 2.0, 2.0, 2.0).unwrap();
    esplit_klev_on(c, "esplit_klev/cube", cube, s);
    let mut s = Serials::new();
    let small = build(&mut s, &mesh::torus_triangles(SMALL.0, SMALL.1));
    esplit_klev_on(c, "esplit_klev/torus_1k_triangles", small, s);
    let mut s = Serials::new();
    let big = build(&mut s, &mesh::torus_triangles(BIG.0, BIG.1));
    esplit_klev_on(c, "esplit_klev/torus_1m_triangles", big, s);
}

/// MKFE across each quad in turn (first vertex to third), then KLFE of the new edge.
fn mkfe_klfe_on(c: &mut Criterion, name: &str, mut b: Body, mut s: Serials) {
    let faces: Vec<FaceId> = b.faces().collect();
    let mut k = 0;
    c.bench_function(name, |bench| {
        bench.iter(|| {
            let f = faces[k];
            k = if k + 1 == faces.len() { 0 } else { k + 1 };
            let u0 = b.face_first_use(f).unwrap();
            let v0 = b.origin(u0);
            let v2 = b.origin(b.next(b.next(u0)));
            let (e, _) = b.mkfe(&mut s, v0, f, v2).unwrap();
            black_box(b.klfe(e).unwrap())
        })
    });
}

fn mkfe_klfe(c: &mut Criterion) {
    let mut s = Serials::new();
    let cube = mkcube(&mut s, 2.0, 2.0, 2.0).unwrap();
    mkfe_klfe_on(c, "mkfe_klfe/cube", cube, s);
    let mut s = Serials::new();
    let small = build(&mut s, &mesh::torus_quads(SMALL.0, SMALL.1));
    mkfe_klfe_on(c, "mkfe_klfe/torus_512_quads", small, s);
    let mut s = Serials::new();
    let big = build(&mut s, &mesh::torus_quads(BIG.0, BIG.1));
    mkfe_klfe_on(c, "mkfe_klfe/torus_500k_quads", big, s);
}

fn from_polygons(c: &mut Criterion) {
    let torus = mesh::torus_triangles(BIG.0, BIG.1);
    let sphere = mesh::uv_sphere(1000, 501);
    let mut g = c.benchmark_group("from_polygons");
    g.sample_size(10);
    g.throughput(Throughput::Elements(torus.faces.len() as u64));
    g.bench_function("torus_1m_triangles", |bench| {
        bench.iter_batched(
            Serials::new,
            |mut s| build(&mut s, &torus),
            BatchSize::PerIteration,
        )
    });
    g.throughput(Throughput::Elements(sphere.faces.len() as u64));
    g.bench_function("sphere_1m_triangles", |bench| {
        bench.iter_batched(
            Serials::new,
            |mut s| build(&mut s, &sphere),
            BatchSize::PerIteration,
        )
    });
    g.finish();
}

fn perimeter(c: &mut Criterion) {
    let mut s = Serials::new();
    let b = build(&mut s, &mesh::torus_triangles(BIG.0, BIG.1));
    // Uses around faces and around vertices: both are twice the edge count.
    let uses = 2 * b.edge_count() as u64;
    let mut g = c.benchmark_group("perimeter");
    g.sample_size(10);
    g.throughput(Throughput::Elements(uses));
    g.bench_function("face_uses_1m_triangles", |bench| {
        bench.iter(|| {
            let mut acc = 0usize;
            for f in b.faces() {
                for u in b.face_uses(f) {
                    acc = acc.wrapping_add(b.origin(u).index());
                }
            }
            acc
        })
    });
    g.bench_function("vertex_uses_1m_triangles", |bench| {
        bench.iter(|| {
            let mut acc = 0usize;
            for v in b.vertices() {
                for u in b.vertex_uses(v) {
                    acc = acc.wrapping_add(b.dest(u).index());
                }
            }
            acc
        })
    });
    g.finish();
}

fn config() -> Criterion {
    Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
}

criterion_group! {
    name = kernel;
    config = config();
    targets = esplit_klev, mkfe_klfe, from_polygons, perimeter
}
criterion_main!(kernel);
