//! Image-based camera refinement (winged alone): the demo scene rendered shaded at
//! 640 × 480 (f = 600) from a camera 2 m from the blocks, Gaussian noise of deviation 6
//! grey levels on every channel, and starts 2° (random axis) and 5 cm (random direction)
//! off the true camera.
//!
//! ```text
//! cargo bench --bench align                   # everything (under a minute)
//! cargo bench --bench align -- align_to_image # the whole refinement only
//! ```
//!
//! Measured: `edges` (the image side alone: Sobel, suppression, threshold and distance
//! transform of the 640 × 480 picture, as `align_to_image` does for its finest level) and
//! `align_to_image` (the whole refinement: the three-level pyramid and its edges, the
//! hidden-line drawings and the alignment), cycling through 20 starts. Before timing, the
//! median and worst final errors over those starts are printed.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DQuat, DVec3};
use winged::camera::{Camera, Intrinsics};
use winged::render::{Mode, Options, Picture, SHADED_BACKGROUND, Scene, render};
use winged::server::demo::demo_world;
use winged::vision::image::{EdgeMap, EdgeOptions, Luma};
use winged::vision::solve::align::{AlignOptions, align_to_image};

#[path = "../bench/rng.rs"]
#[allow(dead_code)] // each bench uses some of its methods
mod rng;
use rng::Rng;

/// The true camera, the scene and its noisy picture.
fn setup() -> (Camera, Scene, Luma) {
    let target = DVec3::new(0.0, 0.0, 0.8);
    let eye = target + DVec3::new(0.55, -0.65, 0.52).normalize() * 2.0;
    let k = Intrinsics::centered(640, 480, 600.0).expect("intrinsics");
    let truth = Camera::look_at(eye, target, DVec3::Z, k).expect("camera");
    let scene = Scene::build(&demo_world().expect("demo world"));
    let options = Options {
        background: SHADED_BACKGROUND,
        ..Options::default()
    };
    let Ok(Picture::Rgb(mut rgb)) = render(&scene, &truth, Mode::Shaded, &options) else {
        panic!("a shaded picture is RGB");
    };
    let mut rng = Rng(1);
    for v in &mut rgb.data {
        *v = (*v as f64 + 6.0 * rng.normal()).round().clamp(0.0, 255.0) as u8;
    }
    let image = Luma::from_samples(rgb.width, rgb.height, 3, &rgb.data).expect("luma");
    (truth, scene, image)
}

fn starts(truth: &Camera, n: usize) -> Vec<Camera> {
    let mut rng = Rng(2);
    (0..n)
        .map(|_| {
            let mut pose = truth.pose;
            let turn = DQuat::from_axis_angle(rng.unit_vector(), 2f64.to_radians());
            pose.rotation = (turn * pose.rotation).normalize();
            pose.position += rng.unit_vector() * 0.05;
            Camera::new(pose, truth.intrinsics).expect("start")
        })
        .collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn bench_align(c: &mut Criterion) {
    let (truth, scene, image) = setup();
    let starts = starts(&truth, 20);
    let options = AlignOptions::default();
    let (mut angles, mut distances, mut failures) = (Vec::new(), Vec::new(), 0);
    for start in &starts {
        match align_to_image(&scene, start, &image, &options) {
            Ok(a) => {
                angles.push(a.camera.pose.angle_to(&truth.pose).to_degrees());
                distances.push(a.camera.position().distance(truth.position()) * 1e3);
            }
            Err(_) => failures += 1,
        }
    }
    let worst = |v: &[f64]| v.iter().cloned().fold(0.0, f64::max);
    println!(
        "align_to_image 640x480 noise 6, starts 2 deg / 5 cm off: median error {:.4} deg, \
         {:.2} mm; worst {:.4} deg, {:.2} mm; {failures} failures of {}",
        median(angles.clone()),
        median(distances.clone()),
        worst(&angles),
        worst(&distances),
        starts.len()
    );

    let mut g = c.benchmark_group("align");
    g.sample_size(10);
    g.warm_up_time(std::time::Duration::from_secs(1));
    g.measurement_time(std::time::Duration::from_secs(4));
    g.bench_function("edges_640x480", |b| {
        b.iter(|| black_box(EdgeMap::detect(&image, &EdgeOptions::default())))
    });
    let mut k = 0;
    g.bench_function("align_to_image_640x480", |b| {
        b.iter(|| {
            let start = &starts[k % starts.len()];
            k += 1;
            black_box(align_to_image(&scene, start, &image, &options))
        })
    });
    g.finish();
}

criterion_group!(benches, bench_align);
criterion_main!(benches);
