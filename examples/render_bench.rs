//! Appearance benchmark: block worlds of 30, 3,000 and 100,000 bodies drawn at
//! 1280×960 from 20 fixed cameras, in every mode; p50 and p99 per step.
//!
//! ```sh
//! cargo run --release --example render_bench                 # our figures
//! cargo run --release --example render_bench -- --dump DIR   # and the scenes for peers
//! ```
//!
//! With `--dump DIR` each world's triangles (world coordinates, f32), their colours, its
//! suns and the cameras are written to `DIR/blocks_N.bin` for `bench/render/peer.py` to
//! draw the same triangles with Mesa's llvmpipe (see `bench/render/run.sh`).
//! `--sizes 30,3000` picks the world sizes.

use std::io::Write;
use std::time::Instant;

use winged::camera::{DEFAULT_NEAR, View};
use winged::model::{Camera, Light};
use winged::render::{Options, Scene, hidden, raster, sample};

const WIDTH: u32 = 1280;
const HEIGHT: u32 = 960;
const CAMERAS: usize = 20;

fn percentile(samples: &mut [f64], p: f64) -> f64 {
    samples.sort_by(f64::total_cmp);
    let i = ((samples.len() as f64 - 1.0) * p).round() as usize;
    samples[i]
}

/// Times `f` once per camera, after one warm-up pass; p50 and p99 in milliseconds.
fn time(cameras: &[Camera], mut f: impl FnMut(&Camera)) -> (f64, f64) {
    for c in cameras.iter().take(2) {
        f(c);
    }
    let mut ms: Vec<f64> = cameras
        .iter()
        .map(|c| {
            let t = Instant::now();
            f(c);
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    (percentile(&mut ms, 0.5), percentile(&mut ms, 0.99))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dump = args
        .iter()
        .position(|a| a == "--dump")
        .and_then(|i| args.get(i + 1))
        .map(std::path::PathBuf::from);
    let sizes: Vec<usize> = args
        .iter()
        .position(|a| a == "--sizes")
        .and_then(|i| args.get(i + 1))
        .map(|s| s.split(',').filter_map(|n| n.parse().ok()).collect())
        .unwrap_or_else(|| vec![30, 3_000, 100_000]);
    println!(
        "{} threads; {WIDTH}×{HEIGHT}; {CAMERAS} cameras; p50 / p99 in ms",
        rayon::current_num_threads()
    );
    println!(
        "| bodies | triangles | scene build | z-buffer | shaded, first of a revision | shaded | shaded + PNG | no shadows | depth + PNG | ids + PNG | wire | hidden lines | hidden + PNG |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for n in sizes {
        let world = sample::blocks(n, 1)?;
        let t = Instant::now();
        let mut scene = Scene::build(&world);
        let build_ms = t.elapsed().as_secs_f64() * 1e3;
        let cameras = sample::ring_cameras(n, CAMERAS, WIDTH, HEIGHT);
        if let Some(dir) = &dump {
            std::fs::create_dir_all(dir)?;
            write_dump(&dir.join(format!("blocks_{n}.bin")), &scene, &cameras)?;
        }
        let opts = Options::default();
        let shading = raster::Shading {
            background: opts.background,
            ambient: opts.ambient,
            shadows: true,
            ..raster::Shading::default()
        };
        let flat = raster::Shading {
            shadows: false,
            ..shading
        };
        let view = |c: &Camera| View::new(c, DEFAULT_NEAR);
        let zbuf = time(&cameras, |c| {
            std::hint::black_box(raster::rasterize(&scene, &view(c))).recycle();
        });
        // The first picture of a revision makes the lights' shadow maps; later ones reuse
        // them.
        let first = time(&cameras, |c| {
            scene.shadows.clear();
            std::hint::black_box(raster::shaded(&scene, &view(c), &shading)).recycle();
        });
        let shaded = time(&cameras, |c| {
            std::hint::black_box(raster::shaded(&scene, &view(c), &shading)).recycle();
        });
        let shaded_png = time(&cameras, |c| {
            let image = raster::shaded(&scene, &view(c), &shading);
            std::hint::black_box(image.to_png());
            image.recycle();
        });
        let unshadowed = time(&cameras, |c| {
            std::hint::black_box(raster::shaded(&scene, &view(c), &flat)).recycle();
        });
        let depth = time(&cameras, |c| {
            let f = raster::rasterize(&scene, &view(c));
            std::hint::black_box(raster::depth_image(&f, 0.001).to_png());
            f.recycle();
        });
        let ids = time(&cameras, |c| {
            let f = raster::rasterize(&scene, &view(c));
            if let Ok((img, _)) = raster::ids_image(&scene, &f) {
                std::hint::black_box(img.to_png());
            }
            f.recycle();
        });
        let wire = time(&cameras, |c| {
            std::hint::black_box(raster::wire(&scene, &view(c), [255; 3], [0; 3]));
        });
        let lines = time(&cameras, |c| {
            std::hint::black_box(hidden::hidden_lines(&scene, &view(c)));
        });
        let lines_png = time(&cameras, |c| {
            let s = hidden::hidden_lines(&scene, &view(c));
            std::hint::black_box(hidden::draw(&s, WIDTH, HEIGHT, [255; 3], [0; 3]).to_png());
        });
        let f = |(a, b): (f64, f64)| format!("{a:.2} / {b:.2}");
        println!(
            "| {n} | {} | {build_ms:.1} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            scene.triangles.len(),
            f(zbuf),
            f(first),
            f(shaded),
            f(shaded_png),
            f(unshadowed),
            f(depth),
            f(ids),
            f(wire),
            f(lines),
            f(lines_png),
        );
        std::io::stdout().flush()?;
    }
    Ok(())
}

/// Writes a scene for the peer renderer, little-endian:
/// `u32 points, u32 triangles, f32 xyz × points, u32 abc × triangles, u8 rgb × triangles,
/// u32 suns, (f32 direction xyz, f32 intensity) × suns, u32 cameras,
/// (f64 i, j, k, eye as 12 numbers; f64 fx, fy, cx, cy; u32 width, height) × cameras`.
fn write_dump(path: &std::path::Path, scene: &Scene, cameras: &[Camera]) -> std::io::Result<()> {
    let mut out = Vec::new();
    let u32s = |out: &mut Vec<u8>, v: u32| out.extend_from_slice(&v.to_le_bytes());
    u32s(&mut out, scene.points.len() as u32);
    u32s(&mut out, scene.triangles.len() as u32);
    for p in &scene.points {
        for c in p.to_array() {
            out.extend_from_slice(&(c as f32).to_le_bytes());
        }
    }
    for t in &scene.triangles {
        for i in t {
            u32s(&mut out, *i);
        }
    }
    for &f in &scene.triangle_faces {
        let body = scene.faces[f as usize].body as usize;
        out.extend_from_slice(&scene.bodies[body].color.0);
    }
    let suns: Vec<_> = scene
        .lights
        .iter()
        .filter_map(|(_, l)| match *l {
            Light::Sun {
                direction,
                intensity,
            } => Some((direction, intensity)),
            Light::Point { .. } => None,
        })
        .collect();
    u32s(&mut out, suns.len() as u32);
    for (d, i) in suns {
        for c in d.to_array() {
            out.extend_from_slice(&(c as f32).to_le_bytes());
        }
        out.extend_from_slice(&(i as f32).to_le_bytes());
    }
    u32s(&mut out, cameras.len() as u32);
    for c in cameras {
        for v in [c.i(), c.j(), c.k(), c.position()] {
            for x in v.to_array() {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
        let k = c.intrinsics;
        for x in [k.fx, k.fy, k.cx, k.cy] {
            out.extend_from_slice(&x.to_le_bytes());
        }
        u32s(&mut out, k.width);
        u32s(&mut out, k.height);
    }
    std::fs::write(path, out)
}
