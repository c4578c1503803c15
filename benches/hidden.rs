//! Hidden-line drawing benchmarks: the exact visible segments of block worlds of 30 and
//! 3,000 bodies at 1280 × 960, then drawing them (with PNG encoding) and writing SVG.
//!
//! ```text
//! cargo bench --bench hidden                 # everything (about a minute)
//! cargo bench --bench hidden -- hidden_lines # one group
//! ```
//!
//! Each world's [`Scene`] is built once, outside the timing. Successive iterations cycle
//! through a ring of 20 cameras around the world, so a figure is the mean over views
//! from every side (the goal: 3,000 bodies in at most 30 ms on two cores).

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use winged::camera::{DEFAULT_NEAR, View};
use winged::render::Scene;
use winged::render::hidden;
use winged::render::sample::{blocks, ring_cameras};

const WIDTH: u32 = 1280;
const HEIGHT: u32 = 960;
const CAMERAS: usize = 20;

fn world(n: usize) -> (Scene, Vec<View>) {
    let scene = Scene::build(&blocks(n, 1).expect("a block world"));
    let views = ring_cameras(n, CAMERAS, WIDTH, HEIGHT)
        .iter()
        .map(|c| View::new(c, DEFAULT_NEAR))
        .collect();
    (scene, views)
}

fn hidden_lines(c: &mut Criterion) {
    let mut g = c.benchmark_group("hidden_lines");
    for n in [30usize, 3000] {
        let (scene, views) = world(n);
        let mut k = 0;
        g.bench_function(format!("blocks_{n}"), |b| {
            b.iter(|| {
                let v = &views[k];
                k = (k + 1) % views.len();
                black_box(hidden::hidden_lines(&scene, v))
            })
        });
    }
    g.finish();
}

fn output(c: &mut Criterion) {
    let (scene, views) = world(3000);
    let segments: Vec<Vec<hidden::Segment>> = views
        .iter()
        .map(|v| hidden::hidden_lines(&scene, v))
        .collect();
    let mut g = c.benchmark_group("hidden_output");
    let mut k = 0;
    g.bench_function("draw_png_blocks_3000", |b| {
        b.iter(|| {
            let s = &segments[k];
            k = (k + 1) % segments.len();
            let img = hidden::draw(s, WIDTH, HEIGHT, [255; 3], [0; 3]);
            black_box(img.to_png())
        })
    });
    let mut k = 0;
    g.bench_function("svg_blocks_3000", |b| {
        b.iter(|| {
            let s = &segments[k];
            k = (k + 1) % segments.len();
            black_box(hidden::to_svg(s, WIDTH, HEIGHT))
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
    name = hidden_benches;
    config = config();
    targets = hidden_lines, output
}
criterion_main!(hidden_benches);
