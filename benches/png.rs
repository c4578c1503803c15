//! PNG encoding of rendered pictures: the 1280 × 960 shaded picture of the 3,000-block
//! world ([`sample::blocks`], seed 1) seen from the first camera of
//! [`sample::ring_cameras`], and its 16-bit depth image in millimetres. The pictures are
//! rendered once, outside the timing; each iteration encodes one.
//!
//! ```text
//! cargo bench --bench png
//! ```

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use winged::camera::{DEFAULT_NEAR, View};
use winged::render::raster::{Shading, depth_image, rasterize, shaded};
use winged::render::{Scene, sample};

fn png(c: &mut Criterion) {
    let world = sample::blocks(3000, 1).expect("a block world");
    let scene = Scene::build(&world);
    let camera = &sample::ring_cameras(3000, 20, 1280, 960)[0];
    let view = View::new(camera, DEFAULT_NEAR);
    let picture = shaded(&scene, &view, &Shading::default());
    let depth = depth_image(&rasterize(&scene, &view), 0.001);
    eprintln!(
        "PNG sizes: shaded {} bytes, depth {} bytes",
        picture.to_png().len(),
        depth.to_png().len()
    );

    let mut g = c.benchmark_group("png_1280x960");
    g.sample_size(50)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    g.bench_function("shaded_rgb", |b| b.iter(|| black_box(picture.to_png())));
    g.bench_function("depth_gray16", |b| b.iter(|| black_box(depth.to_png())));
    g.finish();
}

criterion_group!(benches, png);
criterion_main!(benches);
