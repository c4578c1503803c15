//! Bytes per edge of a million-triangle body, faces and vertices counted.
//!
//! Prints, for a genus-1 torus and a genus-0 UV sphere of 1,000,000 triangles each, the
//! body's own accounting ([`Body::heap_bytes`], the capacity of its arenas) and the
//! heap bytes a counting allocator sees the body holding, each divided by the edge
//! count; and the peak of extra heap while `from_polygons` runs (its working arrays).
//!
//! ```text
//! cargo run --release --example memory
//! ```

#[path = "../bench/mesh.rs"]
mod mesh;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use winged::model::{Body, Edge, Face, Serials, Vertex};

/// Tracks live and peak heap bytes.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn grew(n: usize) {
    let now = LIVE.fetch_add(n, Ordering::Relaxed) + n;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        grew(l.size());
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        LIVE.fetch_sub(l.size(), Ordering::Relaxed);
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, new: usize) -> *mut u8 {
        grew(new);
        LIVE.fetch_sub(l.size(), Ordering::Relaxed);
        unsafe { System.realloc(p, l, new) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn weigh<const N: usize>(name: &str, m: &mesh::Mesh<N>) {
    let mut s = Serials::new();
    let before = LIVE.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    let b = Body::from_polygons(&mut s, &m.positions, &m.faces).expect("closed mesh");
    let held = LIVE.load(Ordering::Relaxed) - before;
    let peak = PEAK.load(Ordering::Relaxed) - before;
    let e = b.edge_count() as f64;
    println!(
        "{name}: F {} E {} V {} genus {}",
        b.face_count(),
        b.edge_count(),
        b.vertex_count(),
        b.handles()
    );
    println!(
        "  heap_bytes {} ({:.2} B/edge); allocator: {} held ({:.2} B/edge), {} peak during build ({:.2} B/edge)",
        b.heap_bytes(),
        b.heap_bytes() as f64 / e,
        held,
        held as f64 / e,
        peak,
        peak as f64 / e
    );
}

fn main() {
    println!(
        "records: Edge {} B, Vertex {} B, Face {} B; per entity also a serial (8 B) and a serial-index entry (8 + 4 B)",
        size_of::<Edge>(),
        size_of::<Vertex>(),
        size_of::<Face>()
    );
    weigh(
        "torus 1000x500, 1M triangles",
        &mesh::torus_triangles(1000, 500),
    );
    weigh(
        "uv sphere 1000x501, 1M triangles",
        &mesh::uv_sphere(1000, 501),
    );
}
