//! winged's side of the mesh side-by-side with trimesh (see bench/mesh/README.md).
//!
//! `mesh_side write --dir D` writes the test files: binary STLs of about a million
//! triangles (a UV sphere, whose faces are all in different planes, and a box whose six
//! sides are fine grids that merge back to six faces) and a 100,000-triangle one.
//! `mesh_side run --dir D --repeat N` times, on each: the import (read, weld, check
//! edges and crossings, merge coplanar faces, build and validate the body, as
//! `POST /v1/bodies/import` does off the world's owner), the same without the crossing
//! test, and the export of the body as binary STL, OBJ and GLB; best of N, one line of
//! JSON per case.

#[path = "../side_cli.rs"]
mod side_cli;

use std::f64::consts::{PI, TAU};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::{Parser, Subcommand};
use glam::DVec3;
use serde_json::json;
use winged::mesh::write::Solid;
use winged::mesh::{Format, ImportOptions, import};
use winged::model::{Color, Pose};

#[derive(Parser)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Writes the test files into DIR.
    Write {
        #[arg(long)]
        dir: PathBuf,
    },
    /// Times winged on the files in DIR.
    Run {
        #[arg(long)]
        dir: PathBuf,
        #[arg(long, default_value_t = 5)]
        repeat: usize,
    },
}

/// Makes a case's triangles.
type Triangles = fn() -> Vec<[DVec3; 3]>;

/// The cases: file name, and how the triangles are made.
const CASES: [(&str, Triangles); 3] = [
    ("sphere-1m.stl", || sphere(1000, 501)),
    ("grid-box-1m.stl", || grid_box(289)),
    ("sphere-100k.stl", || sphere(316, 159)),
];

fn main() -> ExitCode {
    side_cli::start();
    let cli = Cli::parse();
    side_cli::exit(match cli.command {
        Command::Write { dir } => write_all(&dir),
        Command::Run { dir, repeat } => run_all(&dir, repeat.max(1)),
    })
}

fn write_all(dir: &Path) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    for (name, make) in CASES {
        let tris = make();
        let path = dir.join(name);
        std::fs::write(&path, stl(&tris)).map_err(|e| format!("{}: {e}", path.display()))?;
        eprintln!("{}: {} triangles", path.display(), tris.len());
    }
    Ok(())
}

fn run_all(dir: &Path, repeat: usize) -> Result<(), String> {
    for (name, _) in CASES {
        let path = dir.join(name);
        let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        side_cli::caught(|| run(name, &bytes, repeat))?;
    }
    Ok(())
}

/// Best of `repeat` runs of `f`, in milliseconds, and its last result.
fn best<T>(repeat: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..repeat {
        let t = Instant::now();
        let out = f();
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
        last = Some(out);
    }
    (best, last.expect("at least one run"))
}

fn run(name: &str, bytes: &[u8], repeat: usize) -> Result<(), String> {
    let options = ImportOptions::default();
    let unchecked = ImportOptions {
        check_crossings: false,
        ..ImportOptions::default()
    };
    // The import as the server does it: the file to bodies built and checked, ready
    // for the world's owner to insert.
    let import_and_build =
        |options: &ImportOptions| import(Format::Stl, bytes, options).map_err(|e| e.to_string());
    let (read_ms, scene) = best(repeat, || winged::mesh::read(Format::Stl, bytes, &options));
    let triangles = scene.map_err(|e| e.to_string())?.face_count();
    let (import_ms, bodies) = best(repeat, || import_and_build(&options));
    let bodies = bodies?;
    let (unchecked_ms, _) = best(repeat, || import_and_build(&unchecked));
    let body = bodies.built.first().ok_or("no body")?.body();
    let solid = Solid::from_body(1, None, Color([200, 200, 200]), body, &Pose::IDENTITY);
    let (stl_ms, stl_bytes) = best(repeat, || {
        winged::mesh::write::stl::write(std::slice::from_ref(&solid))
    });
    let (obj_ms, obj_bytes) = best(repeat, || {
        winged::mesh::write::obj::write(std::slice::from_ref(&solid))
    });
    let (glb_ms, glb_bytes) = best(repeat, || winged::mesh::gltf::write_solid(&solid));
    let (solid_ms, _) = best(repeat, || {
        Solid::from_body(1, None, Color([200, 200, 200]), body, &Pose::IDENTITY)
    });
    println!(
        "{}",
        json!({
            "case": name,
            "bytes": bytes.len(),
            "triangles": triangles,
            "faces": body.face_count(),
            "vertices": body.vertex_count(),
            "volume": body.volume(),
            "read_ms": read_ms,
            "import_ms": import_ms,
            "import_unchecked_ms": unchecked_ms,
            "export_stl_ms": stl_ms + solid_ms,
            "export_obj_ms": obj_ms + solid_ms,
            "export_glb_ms": glb_ms + solid_ms,
            "stl_bytes": stl_bytes.map_err(|e| e.to_string())?.len(),
            "obj_bytes": obj_bytes.len(),
            "glb_bytes": glb_bytes.map_err(|e| e.to_string())?.len(),
        })
    );
    Ok(())
}

/// A UV sphere of radius 1: `segments` meridians, `rings` bands, triangles only
/// (each quad of a band cut in two), counter-clockwise seen from outside.
fn sphere(segments: usize, rings: usize) -> Vec<[DVec3; 3]> {
    let at = |i: usize, j: usize| {
        if j == 0 || j == rings {
            return DVec3::new(0.0, 0.0, if j == 0 { 1.0 } else { -1.0 });
        }
        let theta = PI * j as f64 / rings as f64;
        let phi = TAU * (i % segments) as f64 / segments as f64;
        DVec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    };
    let mut out = Vec::with_capacity(2 * segments * rings);
    for j in 0..rings {
        for i in 0..segments {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
            if j == 0 {
                out.push([a, b, c]);
            } else if j == rings - 1 {
                out.push([a, b, d]);
            } else {
                out.push([a, b, c]);
                out.push([a, c, d]);
            }
        }
    }
    out
}

/// A 2 m box whose every side is an `n × n` grid of squares cut into triangles.
fn grid_box(n: usize) -> Vec<[DVec3; 3]> {
    let mut out = Vec::with_capacity(12 * n * n);
    // Each side: its normal axis, sign, and two in-plane axes (u × v = outward).
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let p = |a: usize, b: usize| {
                let mut x = [0.0; 3];
                x[axis] = sign;
                x[u] = -1.0 + 2.0 * a as f64 / n as f64;
                x[v] = -1.0 + 2.0 * b as f64 / n as f64;
                DVec3::from_array(x)
            };
            for a in 0..n {
                for b in 0..n {
                    let (p00, p10, p11, p01) = (p(a, b), p(a + 1, b), p(a + 1, b + 1), p(a, b + 1));
                    if sign > 0.0 {
                        out.push([p00, p10, p11]);
                        out.push([p00, p11, p01]);
                    } else {
                        out.push([p00, p11, p10]);
                        out.push([p00, p01, p11]);
                    }
                }
            }
        }
    }
    out
}

/// A binary STL of the triangles (f32 coordinates, unit normals).
fn stl(tris: &[[DVec3; 3]]) -> Vec<u8> {
    let mut out = Vec::with_capacity(84 + 50 * tris.len());
    out.extend_from_slice(&[0u8; 80]);
    out.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in tris {
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
        for c in n
            .to_array()
            .into_iter()
            .chain(t.iter().flat_map(|p| p.to_array()))
        {
            out.extend_from_slice(&(c as f32).to_le_bytes());
        }
        out.extend_from_slice(&[0, 0]);
    }
    out
}
