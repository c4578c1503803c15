//! Closed test meshes shared by the kernel benchmarks (`benches/kernel.rs`) and the
//! examples (`examples/kernel_peer.rs`, `examples/memory.rs`).
//!
//! `bench/openmesh/split_collapse.cpp` generates the same meshes, vertex for vertex and
//! face for face, so that both kernels run on identical input.

#![allow(dead_code)]

use std::f64::consts::{PI, TAU};

use glam::DVec3;

/// Vertex loci and faces (vertex indices counter-clockwise seen from outside).
pub struct Mesh<const N: usize> {
    /// Vertex loci.
    pub positions: Vec<DVec3>,
    /// Faces, each `N` vertex indices.
    pub faces: Vec<[u32; N]>,
}

/// Major and minor radii of the test torus.
const MAJOR: f64 = 3.0;
const MINOR: f64 = 1.0;

/// Torus grid vertices: `n` steps around the axis (i), `m` around the tube (j); vertex
/// (i, j) has index `i * m + j`.
fn torus_positions(n: u32, m: u32) -> Vec<DVec3> {
    let mut p = Vec::with_capacity((n * m) as usize);
    for i in 0..n {
        let u = TAU * f64::from(i) / f64::from(n);
        for j in 0..m {
            let v = TAU * f64::from(j) / f64::from(m);
            let r = MAJOR + MINOR * v.cos();
            p.push(DVec3::new(r * u.cos(), r * u.sin(), MINOR * v.sin()));
        }
    }
    p
}

/// The four corners of torus quad (i, j), counter-clockwise seen from outside.
fn torus_quad(n: u32, m: u32, i: u32, j: u32) -> [u32; 4] {
    let at = |i: u32, j: u32| (i % n) * m + (j % m);
    [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]
}

/// A closed torus (genus 1) of `n * m` quads: F = n·m, E = 2·n·m, V = n·m.
pub fn torus_quads(n: u32, m: u32) -> Mesh<4> {
    let mut faces = Vec::with_capacity((n * m) as usize);
    for i in 0..n {
        for j in 0..m {
            faces.push(torus_quad(n, m, i, j));
        }
    }
    Mesh {
        positions: torus_positions(n, m),
        faces,
    }
}

/// A closed torus (genus 1) of `2 * n * m` triangles (each quad of [`torus_quads`] cut
/// by its diagonal from corner 0 to corner 2): F = 2·n·m, E = 3·n·m, V = n·m.
pub fn torus_triangles(n: u32, m: u32) -> Mesh<3> {
    let mut faces = Vec::with_capacity((2 * n * m) as usize);
    for i in 0..n {
        for j in 0..m {
            let [a, b, c, d] = torus_quad(n, m, i, j);
            faces.push([a, b, c]);
            faces.push([a, c, d]);
        }
    }
    Mesh {
        positions: torus_positions(n, m),
        faces,
    }
}

/// A closed UV sphere (genus 0) of `2 * n * (m - 1)` triangles: `n` meridians, `m - 1`
/// rings of latitude (ring j = 1..m-1 has index `(j - 1) * n + i`), then the north and
/// the south pole. F = 2·n·(m−1), E = 3·n·(m−1), V = n·(m−1) + 2.
pub fn uv_sphere(n: u32, m: u32) -> Mesh<3> {
    assert!(n >= 3 && m >= 2);
    let mut positions = Vec::with_capacity((n * (m - 1) + 2) as usize);
    for j in 1..m {
        let t = PI * f64::from(j) / f64::from(m);
        for i in 0..n {
            let u = TAU * f64::from(i) / f64::from(n);
            positions.push(DVec3::new(t.sin() * u.cos(), t.sin() * u.sin(), t.cos()));
        }
    }
    let north = n * (m - 1);
    let south = north + 1;
    positions.push(DVec3::Z);
    positions.push(-DVec3::Z);
    let at = |i: u32, j: u32| (j - 1) * n + (i % n);
    let mut faces = Vec::with_capacity((2 * n * (m - 1)) as usize);
    for i in 0..n {
        faces.push([at(i, 1), at(i + 1, 1), north]);
    }
    for j in 1..m - 1 {
        for i in 0..n {
            let (a, b, c, d) = (at(i, j + 1), at(i + 1, j + 1), at(i + 1, j), at(i, j));
            faces.push([a, b, c]);
            faces.push([a, c, d]);
        }
    }
    for i in 0..n {
        faces.push([south, at(i + 1, m - 1), at(i, m - 1)]);
    }
    Mesh { positions, faces }
}
