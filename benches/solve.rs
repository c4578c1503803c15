//! Camera solution benchmarks (winged alone), on the protocol of the EPnP paper: f = 800,
//! a 640 × 480 image, points uniform in [-2,2] × [-2,2] × [4,8] in the camera frame, a
//! random camera; Gaussian pixel noise; outliers uniform over the image.
//!
//! ```text
//! cargo bench --bench solve                   # everything (about a minute)
//! cargo bench --bench solve -- sqpnp          # one solver
//! ```
//!
//! Measured: `sqpnp` on all points (no outliers), `solve_pnp` (LO-RANSAC around P3P,
//! SQPnP on the consensus, robust Levenberg–Marquardt) without outliers and with 70 %
//! of them. Before each group the median rotation and translation errors over 300
//! problems are printed, so that speed and accuracy are read from the same data.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DMat3, DQuat, DVec2, DVec3};
use winged::vision::solve::{CvPose, PixelIntrinsics, PnpOptions, solve_pnp, sqpnp};

const K: PixelIntrinsics = PixelIntrinsics {
    fx: 800.0,
    fy: 800.0,
    cx: 320.0,
    cy: 240.0,
};

#[path = "../bench/rng.rs"]
#[allow(dead_code)] // each bench uses some of its methods
mod rng;
use rng::Rng;

/// One problem: the true camera, world points and pixels.
struct Problem {
    truth: CvPose,
    world: Vec<DVec3>,
    pixels: Vec<DVec2>,
}

fn problem(rng: &mut Rng, n: usize, noise: f64, outlier_ratio: f64) -> Problem {
    let axis = DVec3::new(rng.normal(), rng.normal(), rng.normal()).normalize();
    let rotation = DMat3::from_quat(DQuat::from_axis_angle(axis, rng.range(0.0, 3.1)));
    let translation = DVec3::new(
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
    );
    let truth = CvPose::new(rotation, translation);
    let outliers = (outlier_ratio * n as f64).round() as usize;
    let mut world = Vec::with_capacity(n);
    let mut pixels = Vec::with_capacity(n);
    for i in 0..n {
        let cam = DVec3::new(
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
            rng.range(4.0, 8.0),
        );
        world.push(rotation.transpose() * (cam - translation));
        pixels.push(if i < outliers {
            DVec2::new(rng.range(0.0, 640.0), rng.range(0.0, 480.0))
        } else {
            K.pixel(DVec2::new(cam.x / cam.z, cam.y / cam.z))
                + DVec2::new(rng.normal(), rng.normal()) * noise
        });
    }
    Problem {
        truth,
        world,
        pixels,
    }
}

fn problems(seed: u64, n: usize, noise: f64, outlier_ratio: f64) -> Vec<Problem> {
    let mut rng = Rng(seed);
    (0..300)
        .map(|_| problem(&mut rng, n, noise, outlier_ratio))
        .collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Median rotation error (degrees), median relative translation error (%), and failures
/// (rotation error over 5° or no answer).
fn accuracy(ps: &[Problem], solve: impl Fn(&Problem) -> Option<CvPose>) -> (f64, f64, usize) {
    let mut rot = Vec::new();
    let mut trans = Vec::new();
    let mut failures = 0;
    for p in ps {
        match solve(p) {
            Some(pose) => {
                let e = pose.rotation_angle_to(&p.truth).to_degrees();
                failures += usize::from(e > 5.0);
                rot.push(e);
                trans.push(
                    100.0 * (pose.translation - p.truth.translation).length()
                        / p.truth.translation.length().max(1e-9),
                );
            }
            None => failures += 1,
        }
    }
    (median(rot), median(trans), failures)
}

fn sqpnp_pose(p: &Problem) -> Option<CvPose> {
    let m: Vec<DVec2> = p.pixels.iter().map(|&q| K.normalise(q)).collect();
    sqpnp(&p.world, &m, None).ok().map(|s| s.best.pose)
}

fn pipeline_pose(p: &Problem) -> Option<CvPose> {
    solve_pnp(&p.world, &p.pixels, &K, &PnpOptions::default())
        .ok()
        .map(|s| s.pose)
}

fn bench_sqpnp(c: &mut Criterion) {
    let mut g = c.benchmark_group("sqpnp");
    for n in [6usize, 10, 50, 200] {
        let ps = problems(n as u64, n, 2.0, 0.0);
        let (r, t, f) = accuracy(&ps, sqpnp_pose);
        println!(
            "sqpnp n={n} sigma=2px: median rotation {r:.4} deg, translation {t:.3} %, {f} failures of 300"
        );
        let mut k = 0;
        g.bench_function(format!("n{n}"), |b| {
            b.iter(|| {
                let p = &ps[k % ps.len()];
                k += 1;
                black_box(sqpnp_pose(p))
            })
        });
    }
    g.finish();
}

fn bench_pipeline(c: &mut Criterion) {
    let mut g = c.benchmark_group("solve_pnp");
    g.sample_size(20);
    for (n, outliers) in [(50usize, 0.0), (200, 0.0), (200, 0.7)] {
        let ps = problems(1000 + n as u64, n, 2.0, outliers);
        let (r, t, f) = accuracy(&ps, pipeline_pose);
        let pct = (outliers * 100.0) as u32;
        println!(
            "solve_pnp n={n} outliers={pct}% sigma=2px: median rotation {r:.4} deg, translation {t:.3} %, {f} failures of 300"
        );
        let mut k = 0;
        g.bench_function(format!("n{n}_outliers{pct}"), |b| {
            b.iter(|| {
                let p = &ps[k % ps.len()];
                k += 1;
                black_box(pipeline_pose(p))
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_sqpnp, bench_pipeline);
criterion_main!(benches);
