//! Camera solution from a picture over real HTTP: the server draws the demo scene for a
//! stored camera (`GET /v1/cameras/{name}/image`), noise is added to the PNG, and a camera
//! 2° and 5 cm off is corrected from it (`POST /v1/camera-solution` with `image` and
//! `initial`). Broken, blank, foreign and mis-sized pictures get problem+json answers and
//! leave the world unchanged.

#[path = "support/http.rs"]
mod support;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as BASE64;
use glam::{DQuat, DVec3};
use serde_json::{Value, json};
use support::{Rng, TestServer, camera_json, demo_camera, png_rgb, pose_of};
use winged::model::Camera;

/// A camera 2 m from the blocks on the demo table, 640 × 480, f = 600.
fn truth() -> Camera {
    demo_camera()
}

/// `camera` turned 2° about a random axis and moved 5 cm in a random direction.
fn perturbed(camera: &Camera, rng: &mut Rng) -> Camera {
    let mut pose = camera.pose;
    pose.rotation =
        (DQuat::from_axis_angle(rng.unit_vector(), 2f64.to_radians()) * pose.rotation).normalize();
    pose.position += 0.05 * rng.unit_vector();
    Camera::new(pose, camera.intrinsics).expect("a camera")
}

/// The PNG with Gaussian noise of deviation `sigma` grey levels on every sample.
fn noisy(png_bytes: &[u8], sigma: f64, rng: &mut Rng) -> Vec<u8> {
    let decoder = png::Decoder::new(std::io::Cursor::new(png_bytes));
    let mut reader = decoder.read_info().expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size().expect("a size")];
    let info = reader.next_frame(&mut buf).expect("a frame");
    assert_eq!(info.color_type, png::ColorType::Rgb);
    for v in &mut buf[..info.buffer_size()] {
        *v = (*v as f64 + sigma * rng.normal()).round().clamp(0.0, 255.0) as u8;
    }
    png_rgb(info.width, info.height, &buf[..info.buffer_size()])
}

fn revision(s: &TestServer) -> u64 {
    s.get("/v1/world").ok()["revision"]
        .as_u64()
        .expect("a revision")
}

/// The answered camera's rotation (degrees) and position (meters) errors.
fn errors(a: &Value, truth: &Camera) -> (f64, f64) {
    let p = &a["camera"]["pose"];
    let (position, rotation) = pose_of(p);
    (
        rotation.angle_between(truth.pose.rotation).to_degrees(),
        position.distance(truth.pose.position),
    )
}

#[test]
fn a_drifted_camera_is_corrected_from_one_picture() {
    let world = winged::server::demo::demo_world().expect("the demo world");
    let s = TestServer::with_world(world);
    let truth = truth();
    s.put("/v1/cameras/truth", &camera_json(&truth)).ok();
    let picture = s.get("/v1/cameras/truth/image");
    assert_eq!(picture.status, 200);
    assert_eq!(picture.content_type, "image/png");
    let mut rng = Rng(17);
    let before = revision(&s);
    for k in 0..3 {
        let png = noisy(&picture.bytes, 8.0, &mut rng);
        let start = perturbed(&truth, &mut rng);
        let a0 = start
            .pose
            .rotation
            .angle_between(truth.pose.rotation)
            .to_degrees();
        let p0 = start.pose.position.distance(truth.pose.position);
        assert!(a0 > 1.99 && (p0 - 0.05).abs() < 1e-9, "{a0}° {p0} m");
        let mut body = json!({"image": BASE64.encode(&png), "initial": camera_json(&start)});
        if k == 2 {
            body["store_as"] = json!("corrected");
        }
        let a = s.post("/v1/camera-solution", &body).ok();
        let (angle, offset) = errors(&a, &truth);
        assert!(
            angle < 0.1 && offset < 0.005,
            "start {k}: {angle}° {offset} m: {a}"
        );
        assert!(
            a["edges"]["samples"].as_u64().expect("samples") >= 30,
            "{a}"
        );
        assert!(
            a["edges"]["inlier_fraction"].as_f64().expect("a fraction") >= 0.6,
            "{a}"
        );
        assert!(a["rms_px"].as_f64().expect("rms") < 2.0, "{a}");
        assert!(a.get("inliers").is_none() && a["iterations"].get("ransac").is_none());
        assert_eq!(a["camera"]["intrinsics"], camera_json(&truth)["intrinsics"]);
        if k == 2 {
            assert_eq!(a["revision"], before + 1);
            let stored = s.get("/v1/cameras/corrected").ok();
            assert_eq!(stored["pose"], a["camera"]["pose"]);
        } else {
            assert_eq!(a["revision"], before);
        }
    }
    // A stored camera may be the initial one.
    s.put(
        "/v1/cameras/drifted",
        &camera_json(&perturbed(&truth, &mut rng)),
    )
    .ok();
    let png = noisy(&picture.bytes, 8.0, &mut rng);
    let a = s
        .post(
            "/v1/camera-solution",
            &json!({"image": BASE64.encode(&png), "initial": "drifted"}),
        )
        .ok();
    let (angle, offset) = errors(&a, &truth);
    assert!(angle < 0.1 && offset < 0.005, "{angle}° {offset} m: {a}");
}

#[test]
fn bad_pictures_get_problems_and_change_nothing() {
    let world = winged::server::demo::demo_world().expect("the demo world");
    let s = TestServer::with_world(world);
    let truth = truth();
    s.put("/v1/cameras/truth", &camera_json(&truth)).ok();
    let picture = s.get("/v1/cameras/truth/image").bytes;
    let good = BASE64.encode(&picture);
    let before = revision(&s);
    let blank = BASE64.encode(png_rgb(640, 480, &vec![128; 640 * 480 * 3]));
    let small = BASE64.encode(png_rgb(320, 240, &vec![128; 320 * 240 * 3]));
    // Looking straight up, away from the table.
    let sky = Camera::look_at(
        DVec3::new(0.0, 0.0, 3.0),
        DVec3::new(0.0, 0.1, 10.0),
        DVec3::Y,
        truth.intrinsics,
    )
    .expect("a camera");
    // A picture of something else: dark and light stripes, slanted, 48 pixels wide.
    let stripes = {
        let mut rgb = vec![0u8; 640 * 480 * 3];
        for y in 0..480 {
            for x in 0..640 {
                let v = if ((x + y / 2) / 48) % 2 == 0 { 40 } else { 210 };
                rgb[3 * (y * 640 + x)..3 * (y * 640 + x) + 3].fill(v);
            }
        }
        BASE64.encode(png_rgb(640, 480, &rgb))
    };
    let cases: Vec<(&str, Value, u16, &str)> = vec![
        (
            "not base64",
            json!({"image": "%%%not base64%%%", "initial": "truth"}),
            400,
            "invalid-image",
        ),
        (
            "not a PNG",
            json!({"image": BASE64.encode(b"GIF89a, not a PNG at all"), "initial": "truth"}),
            400,
            "invalid-image",
        ),
        (
            "a broken PNG",
            json!({"image": BASE64.encode(&picture[..picture.len() / 2]), "initial": "truth"}),
            400,
            "invalid-image",
        ),
        (
            "a picture of another size",
            json!({"image": small, "initial": "truth"}),
            422,
            "invalid-image",
        ),
        (
            "a blank picture",
            json!({"image": blank, "initial": "truth"}),
            422,
            "no-image-edges",
        ),
        (
            "a camera that sees nothing of the model",
            json!({"image": good, "initial": camera_json(&sky)}),
            422,
            "model-not-in-view",
        ),
        (
            "a picture of something else",
            json!({"image": stripes, "initial": "truth"}),
            422,
            "",
        ),
        (
            "an unknown initial camera",
            json!({"image": good, "initial": "nobody"}),
            404,
            "not-found",
        ),
        (
            "an invalid initial camera",
            json!({"image": good, "initial": {"look_at": {"eye": [1, 1, 1], "target": [1, 1, 1]}, "intrinsics": camera_json(&truth)["intrinsics"]}}),
            422,
            "invalid-camera",
        ),
        (
            "an image without its camera",
            json!({"image": good}),
            400,
            "bad-request",
        ),
        (
            "both forms at once",
            json!({"image": good, "initial": "truth", "intrinsics": "truth", "correspondences": []}),
            400,
            "bad-request",
        ),
        (
            "a RANSAC option with an image",
            json!({"image": good, "initial": "truth", "threshold_px": 2}),
            400,
            "bad-request",
        ),
        (
            "an image that is not a string",
            json!({"image": [1, 2, 3], "initial": "truth"}),
            400,
            "bad-request",
        ),
    ];
    for (what, body, status, kind) in cases {
        let p = s.post("/v1/camera-solution", &body).problem(status);
        let t = p["type"].as_str().expect("a type");
        if kind.is_empty() {
            // Either the alignment finds too little of the model on the picture's
            // edges or it does not settle: never a camera.
            assert!(
                t == "urn:winged:problem:image-does-not-match"
                    || t == "urn:winged:problem:did-not-converge",
                "{what}: {p}"
            );
        } else {
            assert_eq!(t, format!("urn:winged:problem:{kind}"), "{what}: {p}");
        }
    }
    assert_eq!(revision(&s), before, "refused requests write nothing");
    // The server still corrects cameras.
    s.post(
        "/v1/camera-solution",
        &json!({"image": good, "initial": "truth"}),
    )
    .ok();
}
