//! Pixel renderer benchmarks: block worlds of 30, 3,000 and 100,000 bodies
//! ([`sample::blocks`], seed 1) seen by a ring of 20 cameras of 1280 × 960 pixels
//! ([`sample::ring_cameras`]); each iteration renders from the next camera of the ring.
//!
//! ```text
//! cargo bench --bench render                 # everything (a few minutes)
//! cargo bench --bench render -- blocks_3000  # one world
//! cargo bench --bench render -- shaded       # one mode, every world
//! ```
//!
//! Measured per world: `rasterize` (the z-buffer), `shaded` (z-buffer, shadow maps and
//! lighting), `shaded_png` (the same plus PNG encoding), `depth_png` (z-buffer, depth
//! image in millimetres and its PNG) and `wire` (every edge, anti-aliased). The world and
//! its scene are built once per size, outside the timing; the lights' shadow maps are
//! made by the warm-up and kept with the scene, and pictures give their buffers back,
//! as the server does.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use winged::camera::{DEFAULT_NEAR, View};
use winged::render::raster::{Shading, depth_image, rasterize, shaded, wire};
use winged::render::{Scene, sample};

const SIZES: [usize; 3] = [30, 3000, 100_000];
const CAMERAS: usize = 20;
const WIDTH: u32 = 1280;
const HEIGHT: u32 = 960;

fn render(c: &mut Criterion) {
    for n in SIZES {
        let world = sample::blocks(n, 1).expect("a block world");
        let scene = Scene::build(&world);
        let views: Vec<View> = sample::ring_cameras(n, CAMERAS, WIDTH, HEIGHT)
            .iter()
            .map(|cam| View::new(cam, DEFAULT_NEAR))
            .collect();
        let shading = Shading::default();
        let mut g = c.benchmark_group(format!("blocks_{n}"));
        g.sample_size(10)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(if n >= 100_000 { 6 } else { 3 }));
        // Each iteration takes the next camera of the ring.
        let mut next = {
            let mut k = 0;
            move || {
                k = (k + 1) % CAMERAS;
                k
            }
        };
        g.bench_function("rasterize", |b| {
            b.iter(|| black_box(rasterize(&scene, &views[next()])).recycle())
        });
        g.bench_function("shaded", |b| {
            b.iter(|| black_box(shaded(&scene, &views[next()], &shading)).recycle())
        });
        g.bench_function("shaded_png", |b| {
            b.iter(|| {
                let image = shaded(&scene, &views[next()], &shading);
                black_box(image.to_png());
                image.recycle();
            })
        });
        g.bench_function("depth_png", |b| {
            b.iter(|| {
                let frame = rasterize(&scene, &views[next()]);
                black_box(depth_image(&frame, 0.001).to_png());
                frame.recycle();
            })
        });
        g.bench_function("wire", |b| {
            b.iter(|| black_box(wire(&scene, &views[next()], [255; 3], [0; 3])))
        });
        g.finish();
    }
}

criterion_group!(benches, render);
criterion_main!(benches);
