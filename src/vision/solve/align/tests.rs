use glam::{DQuat, DVec3};

use super::*;
use crate::render::{Mode, Options, Picture, SHADED_BACKGROUND, render};
use crate::server::demo::demo_world;
use crate::vision::testing::Rng;

/// The camera of the tests: 640 × 480, f = 600, 2 m from the blocks on the demo table.
fn true_camera() -> Camera {
    camera_from(FRONT)
}

/// Directions from the blocks to the cameras of the tests: in front of the table's long
/// side and to the right, behind it, and at its short end.
const FRONT: DVec3 = DVec3::new(0.55, -0.65, 0.52);
const BEHIND: DVec3 = DVec3::new(-0.6, 0.7, 0.5);
const END: DVec3 = DVec3::new(-0.9, -0.3, 0.6);

/// Two degrees, in radians.
const TWO_DEGREES: f64 = 2.0 * std::f64::consts::PI / 180.0;

/// A camera 2 m from the blocks, in direction `from` (640 × 480, f = 600).
fn camera_from(from: DVec3) -> Camera {
    let target = DVec3::new(0.0, 0.0, 0.8);
    let eye = target + from.normalize() * 2.0;
    let k = Intrinsics::centered(640, 480, 600.0).unwrap();
    Camera::look_at(eye, target, DVec3::Z, k).unwrap()
}

/// The demo scene and its shaded picture through `camera`, with Gaussian noise of
/// deviation `sigma` grey levels added to every channel.
fn demo_picture(camera: &Camera, sigma: f64, seed: u64) -> (Scene, Luma) {
    let scene = Scene::build(&demo_world().unwrap());
    let Picture::Rgb(mut rgb) = render(
        &scene,
        camera,
        Mode::Shaded,
        &Options {
            background: SHADED_BACKGROUND,
            ..Options::default()
        },
    )
    .unwrap() else {
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

/// Aligns from `starts` random starts `angle` radians and `distance` meters off `truth`
/// and checks each answer is within 0.1° and 5 mm of it. Returns the worst errors.
fn assert_recovered(
    truth: &Camera,
    (scene, image): &(Scene, Luma),
    rng: &mut Rng,
    starts: usize,
    (angle, distance): (f64, f64),
) -> (f64, f64) {
    let mut worst = (0.0f64, 0.0f64);
    for i in 0..starts {
        let start = perturbed(truth, rng, angle, distance);
        let (a0, p0) = errors(&start, truth);
        assert!((a0 - angle.to_degrees()).abs() < 1e-6 && (p0 - distance).abs() < 1e-9);
        let aligned = align_to_image(scene, &start, image, &AlignOptions::default())
            .unwrap_or_else(|e| panic!("start {i}: {e}"));
        let (da, dp) = errors(&aligned.camera, truth);
        println!(
            "start {i}: {da:.4}° and {:.2} mm off after {} iterations; {} samples, \
             {:.1} % inliers, rms {:.3} px",
            dp * 1e3,
            aligned.iterations,
            aligned.samples,
            aligned.inlier_fraction * 100.0,
            aligned.rms_px
        );
        assert!(
            da <= 0.1 && dp <= 0.005,
            "start {i}: {da}° and {dp} m from the true camera"
        );
        assert!(aligned.converged);
        assert_eq!(aligned.camera.intrinsics, truth.intrinsics);
        assert!(aligned.inlier_fraction >= AlignOptions::default().min_inlier_fraction);
        assert!(aligned.rms_px < 1.0, "rms {} px", aligned.rms_px);
        worst = (worst.0.max(da), worst.1.max(dp));
    }
    worst
}

/// The acceptance test: on the shaded demo scene at 640 × 480 with pixel noise
/// of deviation 6 grey levels, starts 2° (random axis) and 5 cm (random direction) off a
/// camera 2 m from the blocks converge to within 0.1° and 5 mm.
#[test]
fn starts_two_degrees_and_five_centimetres_off_converge_to_the_true_camera() {
    let truth = true_camera();
    let picture = demo_picture(&truth, 6.0, 1);
    let mut rng = Rng(2);
    let (angle, position) = assert_recovered(&truth, &picture, &mut rng, 8, (TWO_DEGREES, 0.05));
    println!("worst: {angle:.4}°, {:.2} mm", position * 1e3);
}

/// The same from behind the table and from its end, with twice the noise.
#[test]
fn other_views_with_stronger_noise_converge_too() {
    for (i, from) in [BEHIND, END].into_iter().enumerate() {
        let truth = camera_from(from);
        let picture = demo_picture(&truth, 12.0, 10 + i as u64);
        let mut rng = Rng(20 + i as u64);
        assert_recovered(&truth, &picture, &mut rng, 4, (TWO_DEGREES, 0.05));
    }
}

/// Starts 8° and 20 cm off are beyond the capture range of the default three levels for
/// most directions: each either converges to the true camera or gives a typed error.
#[test]
fn starts_beyond_the_capture_range_give_errors_not_wrong_cameras() {
    let truth = true_camera();
    let (scene, image) = demo_picture(&truth, 6.0, 3);
    let mut rng = Rng(4);
    let mut refused = 0;
    for i in 0..8 {
        let start = perturbed(&truth, &mut rng, 4.0 * TWO_DEGREES, 0.2);
        match align_to_image(&scene, &start, &image, &AlignOptions::default()) {
            Ok(aligned) => {
                let (da, dp) = errors(&aligned.camera, &truth);
                assert!(
                    da <= 0.1 && dp <= 0.005,
                    "start {i}: a wrong camera, {da}° and {dp} m off"
                );
            }
            Err(e) => {
                assert!(
                    matches!(
                        e,
                        SolveError::DidNotConverge { .. } | SolveError::TooFewInliers { .. }
                    ),
                    "start {i}: {e}"
                );
                refused += 1;
            }
        }
    }
    println!("{refused} of 8 starts refused");
}

#[test]
fn an_image_of_another_size_is_refused() {
    let truth = true_camera();
    let scene = Scene::build(&demo_world().unwrap());
    let image = Luma::from_samples(320, 240, 1, &[128; 320 * 240]).unwrap();
    assert_eq!(
        align_to_image(&scene, &truth, &image, &AlignOptions::default()),
        Err(SolveError::ImageSizeMismatch {
            image_width: 320,
            image_height: 240,
            camera_width: 640,
            camera_height: 480
        })
    );
}

#[test]
fn a_blank_image_is_refused() {
    let truth = true_camera();
    let scene = Scene::build(&demo_world().unwrap());
    let image = Luma::from_samples(640, 480, 1, &vec![128; 640 * 480]).unwrap();
    assert_eq!(
        align_to_image(&scene, &truth, &image, &AlignOptions::default()),
        Err(SolveError::NoImageEdges)
    );
}

/// A picture of noise alone has a few edge pixels but nothing like the model: an error,
/// not a camera, even from the true camera.
#[test]
fn an_image_of_noise_alone_gives_an_error_not_a_camera() {
    let truth = true_camera();
    let scene = Scene::build(&demo_world().unwrap());
    let mut rng = Rng(9);
    let samples: Vec<u8> = (0..640 * 480)
        .map(|_| (128.0 + 8.0 * rng.normal()).round().clamp(0.0, 255.0) as u8)
        .collect();
    let image = Luma::from_samples(640, 480, 1, &samples).unwrap();
    let got = align_to_image(&scene, &truth, &image, &AlignOptions::default());
    assert!(
        matches!(
            got,
            Err(SolveError::DidNotConverge { .. } | SolveError::TooFewInliers { .. })
        ),
        "{got:?}"
    );
}

#[test]
fn a_camera_that_sees_none_of_the_model_is_refused() {
    let truth = true_camera();
    let (scene, image) = demo_picture(&truth, 0.0, 1);
    // Looking up and away from the table.
    let away = Camera::look_at(
        truth.position(),
        truth.position() + DVec3::new(1.0, -1.0, 1.0),
        DVec3::Z,
        truth.intrinsics,
    )
    .unwrap();
    assert_eq!(
        align_to_image(&scene, &away, &image, &AlignOptions::default()),
        Err(SolveError::NoEdgesVisible {
            samples: 0,
            needed: AlignOptions::default().min_samples
        })
    );
}

#[test]
fn bad_cameras_and_options_are_refused() {
    let truth = true_camera();
    let (scene, image) = demo_picture(&truth, 0.0, 1);
    let mut broken = truth;
    broken.pose.position.x = f64::NAN;
    assert!(matches!(
        align_to_image(&scene, &broken, &image, &AlignOptions::default()),
        Err(SolveError::BadCamera(_))
    ));
    let bad = [
        AlignOptions {
            levels: 0,
            ..AlignOptions::default()
        },
        AlignOptions {
            levels: MAX_LEVELS + 1,
            ..AlignOptions::default()
        },
        AlignOptions {
            sample_spacing_px: 0.1,
            ..AlignOptions::default()
        },
        AlignOptions {
            max_angle_deg: 95.0,
            ..AlignOptions::default()
        },
        AlignOptions {
            min_inlier_fraction: 1.5,
            ..AlignOptions::default()
        },
        AlignOptions {
            loss: Loss::Huber { scale: -1.0 },
            ..AlignOptions::default()
        },
        AlignOptions {
            tolerance_px: f64::NAN,
            ..AlignOptions::default()
        },
    ];
    for options in bad {
        assert!(
            matches!(
                align_to_image(&scene, &truth, &image, &options),
                Err(SolveError::BadParameter { .. })
            ),
            "{options:?}"
        );
    }
}

/// Every sample is a point of the edge it was drawn from, and projects onto the drawing.
#[test]
fn samples_are_points_of_the_drawn_edges() {
    let camera = true_camera();
    let scene = Scene::build(&demo_world().unwrap());
    let view = View::new(&camera, DEFAULT_NEAR);
    let drawing = hidden_lines(&scene, &view);
    let every_edge = AlignOptions {
        grazing_cosine: 0.0,
        ..AlignOptions::default()
    };
    let samples = sample_edges(&scene, &EdgeFaces::of(&scene), &camera, &every_edge, 4.0);
    let expected: usize = drawing
        .iter()
        .map(|s| (s.a.distance(s.b) / 4.0).floor() as usize)
        .sum();
    assert_eq!(samples.len(), expected);
    assert!(samples.len() > 300, "{} samples", samples.len());
    // The 3D edges of the scene, to find each sample's own.
    let edges: Vec<(DVec3, DVec3)> = scene
        .edges
        .iter()
        .map(|e| {
            (
                scene.points[e.ends[0] as usize],
                scene.points[e.ends[1] as usize],
            )
        })
        .collect();
    for sample in &samples {
        let on_edge = edges.iter().any(|&(a, b)| {
            let d = b - a;
            let t = ((sample.point - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
            let parallel = d.normalize().cross(sample.direction).length() < 1e-9;
            sample.point.distance(a + d * t) < 1e-9 && parallel
        });
        assert!(on_edge, "{sample:?} is on no edge of the model");
        let pixel = camera.project(sample.point).unwrap();
        let to_drawing = drawing
            .iter()
            .map(|s| {
                let d = s.b - s.a;
                let t = ((pixel - s.a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
                pixel.distance(s.a + d * t)
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            to_drawing < 1e-6,
            "{sample:?} projects {to_drawing} px off the drawing"
        );
    }
}

/// From the table's end, the end of its top is seen nearly edge-on: its edges are not
/// sampled, and every other drawn edge is.
#[test]
fn edges_of_faces_seen_edge_on_are_not_sampled() {
    let camera = camera_from(END);
    let scene = Scene::build(&demo_world().unwrap());
    let edge_faces = EdgeFaces::of(&scene);
    let options = AlignOptions::default();
    let every_edge = AlignOptions {
        grazing_cosine: 0.0,
        ..options
    };
    let all = sample_edges(&scene, &edge_faces, &camera, &every_edge, 4.0);
    let kept = sample_edges(&scene, &edge_faces, &camera, &options, 4.0);
    assert!(kept.len() < all.len());
    // The cosine of the viewing angle of each face at a point.
    let cosines = |point: DVec3| -> Vec<f64> {
        let e = scene
            .edges
            .iter()
            .find(|e| {
                let (a, b) = (
                    scene.points[e.ends[0] as usize],
                    scene.points[e.ends[1] as usize],
                );
                let d = b - a;
                let t = ((point - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
                point.distance(a + d * t) < 1e-9
            })
            .unwrap();
        let to_eye = (camera.position() - point).normalize();
        e.faces
            .iter()
            .map(|&f| scene.faces[f as usize].normal.dot(to_eye))
            .collect()
    };
    for dropped in all.iter().filter(|s| !kept.contains(s)) {
        let c = cosines(dropped.point);
        assert!(
            c.iter().any(|&c| c > 0.0 && c < 0.06),
            "{dropped:?} was left out, but its faces are seen at cosines {c:?}"
        );
    }
    for sample in &kept {
        let c = cosines(sample.point);
        assert!(
            c.iter().all(|&c| c <= 0.0 || c > 0.04),
            "{sample:?} was kept, but its faces are seen at cosines {c:?}"
        );
    }
}

/// The priors' cost at `pose`, with their normal equations.
fn prior_fit(priors: &Priors, pose: PoseEstimate) -> Fit {
    let mut fit = Fit {
        cost: 0.0,
        inliers: 0,
        inlier_squares: 0.0,
        equations: NormalEquations::zeros(),
    };
    priors.add_to(&mut fit, pose, true);
    fit
}

#[test]
fn the_priors_gradients_are_the_derivatives_of_their_costs() {
    let mut rng = Rng(7);
    for _ in 0..50 {
        let camera = perturbed(&true_camera(), &mut rng, 0.3, 0.3);
        let (r, t) = camera.to_opencv();
        let rest = PoseEstimate::new(r, t);
        // A body turned and pushed a little from where the prior holds it.
        let turn = DQuat::from_axis_angle(rng.unit_vector(), rng.range(0.0, 3.0).to_radians());
        let pose = PoseEstimate {
            rotation: (rest.rotation * turn).normalize(),
            translation: rest.translation + DVec3::new(0.02, -0.01, 0.03),
        };
        let priors = Priors {
            plane: Some(PlanePrior {
                point: DVec3::new(0.1, -0.2, 0.8),
                normal: r * DVec3::Z,
                offset: 0.5,
                deviation: 0.01,
            }),
            turn: Some(TurnPrior {
                rotation: rest.rotation,
                deviation: DVec3::new(0.02, 0.02, 0.2),
            }),
        };
        let fit = prior_fit(&priors, pose);
        let h = 1e-6;
        for i in 0..6 {
            let mut step = PoseStep::zeros();
            step[i] = h;
            let up = prior_fit(&priors, pose.stepped(&step)).cost;
            let down = prior_fit(&priors, pose.stepped(&(-step))).cost;
            let numeric = (up - down) / (2.0 * h);
            let analytic = fit.equations.gradient[i];
            // The turn prior's step is exact to first order in the turn: a few percent
            // at 3°.
            assert!(
                (numeric - analytic).abs() <= 0.05 * numeric.abs().max(analytic.abs()) + 1e-6,
                "component {i}: numeric {numeric}, analytic {analytic}"
            );
        }
    }
}
