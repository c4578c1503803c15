use glam::{DQuat, DVec3};

use super::*;
use crate::render::{Mode, Options, Picture, SHADED_BACKGROUND, render};
use crate::server::demo::demo_world;
use crate::solve::testing::Rng;

/// The camera of the tests: 640 × 480, f = 600, 2 m from the blocks on the demo table.
fn true_camera() -> Camera {
    let target = DVec3::new(0.0, 0.0, 0.8);
    let eye = target + DVec3::new(0.55, -0.65, 0.52).normalize() * 2.0;
    let k = Intrinsics::centered(640, 480, 600.0).unwrap();
    Camera::look_at(eye, target, DVec3::Z, k).unwrap()
}

/// The demo scene and its shaded picture through `camera`, with Gaussian noise of
/// deviation `sigma` grey levels added to every channel.
fn demo_picture(camera: &Camera, sigma: f64, seed: u64) -> (Scene, Luma) {
    let scene = Scene::build(&demo_world().unwrap());
    let Picture::Rgb(mut rgb) =
        render(&scene, camera, Mode::Shaded, &Options {
            background: SHADED_BACKGROUND,
            ..Options::default()
        }).unwrap()
    else {
        panic!("a shaded picture is RGB");
    };
    let mut rng = Rng(seed);
    for v in &mut rgb.data {
        *v = (*v as f64 + sigma * rng.normal()).round().clamp(0.0, 255.0) as u8;
    }
    let luma = Luma::from_samples(rgb.width, rgb.height, 3, &rgb.data).unwrap();
    (scene, luma)
}

/// `camera` turned by `angle` radians about a random axis through its lens centre and
/// moved `distance` meters in a random direction.
fn perturbed(camera: &Camera, rng: &mut Rng, angle: f64, distance: f64) -> Camera {
    let mut pose = camera.pose;
    pose.rotation = (DQuat::from_axis_angle(rng.unit_vector(), angle) * pose.rotation).normalize();
    pose.position += rng.unit_vector() * distance;
    Camera::new(pose, camera.intrinsics).unwrap()
}

/// Rotation (degrees) and position (meters) errors of `got` against `truth`.
fn errors(got: &Camera, truth: &Camera) -> (f64, f64) {
    (
        got.pose.angle_to(&truth.pose).to_degrees(),
        got.position().distance(truth.position()),
    )
}

#[test]
fn explore() {
    let truth = true_camera();
    let sigma: f64 = std::env::var("SIGMA").map(|s| s.parse().unwrap()).unwrap_or(6.0);
    let n: usize = std::env::var("STARTS").map(|s| s.parse().unwrap()).unwrap_or(4);
    let angle: f64 = std::env::var("ANGLE").map(|s| s.parse().unwrap()).unwrap_or(2.0);
    let dist: f64 = std::env::var("DIST").map(|s| s.parse().unwrap()).unwrap_or(0.05);
    let seed: u64 = std::env::var("SEED").map(|s| s.parse().unwrap()).unwrap_or(1);
    let (scene, luma) = demo_picture(&truth, sigma, seed);
    let mut rng = Rng(5 + seed);
    let quiet = std::env::var("QUIET").is_ok();
    let (mut worst_a, mut worst_p, mut fails, mut wrong) = (0.0f64, 0.0f64, 0, 0);
    let mut fractions = Vec::new();
    for _ in 0..n {
        let start = perturbed(&truth, &mut rng, angle.to_radians(), dist);
        let t0 = std::time::Instant::now();
        let got = align_to_image(&scene, &start, &luma, &AlignOptions::default());
        let el = t0.elapsed();
        match got {
            Ok(a) => {
                let (da, dp) = errors(&a.camera, &truth);
                if da > 0.1 || dp > 0.005 { wrong += 1; println!("WRONG {da} {dp} {}", a.inlier_fraction); } else { worst_a = worst_a.max(da); worst_p = worst_p.max(dp); fractions.push(a.inlier_fraction); }
                if !quiet { println!(
                    "{:.4}° {:.2} mm it {} rms {:.3} n {} in {:.3} ({el:?})",
                    da,
                    dp * 1000.0,
                    a.iterations,
                    a.rms_px,
                    a.samples,
                    a.inlier_fraction
                ); }
            }
            Err(e) => { fails += 1; println!("error {e} ({el:?})") }
        }
    }
    let lo = fractions.iter().cloned().fold(1.0, f64::min);
    println!("SUMMARY worst {worst_a:.4}° {:.2} mm fails {fails} wrong {wrong} min inlier fraction {lo:.3}", worst_p * 1000.0);
}

#[test]
fn dump() {
    let truth = true_camera();
    let (_scene, luma) = demo_picture(&truth, 6.0, 1);
    let map = EdgeMap::detect(&luma, &EdgeOptions::default()).unwrap();
    let mut rgb = crate::render::RgbImage::filled(640, 480, [0, 0, 0]);
    for y in 0..480 {
        for x in 0..640 {
            let g = luma.get(x, y).unwrap() / 2;
            rgb.set(x, y, [g, g, g]);
        }
    }
    for e in map.edgels() {
        rgb.set(e.position.x as u32, e.position.y as u32, [255, 0, 0]);
    }
    std::fs::write("/tmp/align_dump.png", rgb.to_png()).unwrap();
    println!("threshold {} edgels {}", map.threshold(), map.edgels().len());
}

#[test]
fn noise_stats() {
    let truth = true_camera();
    let (_scene, luma) = demo_picture(&truth, 6.0, 1);
    let (_scene, clean) = demo_picture(&truth, 0.0, 1);
    let mut s = 0.0;
    let mut n = 0.0;
    for y in 0..50 {
        for x in 0..100 {
            let d = luma.get(x, y).unwrap() as f64 - clean.get(x, y).unwrap() as f64;
            s += d * d;
            n += 1.0;
        }
    }
    println!("luma noise std {} clean value {}", (s / n).sqrt(), clean.get(5, 5).unwrap());
    let map = EdgeMap::detect(&clean, &EdgeOptions::default()).unwrap();
    println!("clean threshold {} edgels {}", map.threshold(), map.edgels().len());
}
