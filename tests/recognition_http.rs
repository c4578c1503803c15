//! Recognition over real HTTP (`POST /v1/recognition`), on pictures that winged did not
//! draw: a ray caster in the test draws the world as it really is (the cube pushed 5 cm
//! and turned 8°, the wedge taken away, a box the model lacks put on the table), with
//! its own shading, anti-aliasing and noise, and its depth. The server holds the model
//! (the demo scene) and must tell which bodies are there, where the pushed one is, and
//! where the stranger shows. Bad input gets problem+json answers and leaves the world
//! unchanged; only `update` writes.

#[path = "support/raycast.rs"]
mod raycast;
#[path = "support/http.rs"]
mod support;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as BASE64;
use glam::{DQuat, DVec3};
use serde_json::{Value, json};
use support::{TestServer, camera_json, demo_camera, png_rgb, pose_of};
use winged::model::solids::box_solid;
use winged::model::{Camera, Pose, World};
use winged::render::Scene;

/// The cube's push: 5 cm along x, −3 cm along y, 8° about its own vertical axis.
fn push(model: &World) -> Pose {
    let cube = model.find_by_name("cube").expect("the cube");
    let centre = model.world_pose(cube).expect("a pose").position;
    let turn = DQuat::from_rotation_z(8f64.to_radians());
    Pose {
        position: DVec3::new(0.05, -0.03, 0.0) + centre - turn * centre,
        rotation: turn,
    }
}

const STRANGER_AT: DVec3 = DVec3::new(-0.05, 0.3, 0.75 + 0.075);
const STRANGER_SIZE: DVec3 = DVec3::new(0.14, 0.1, 0.15);

/// The world as it is: the cube pushed, the wedge gone, a stranger on the table.
fn truth(model: &World) -> World {
    let mut world = model.clone();
    let cube = world.find_by_name("cube").expect("the cube");
    let placed = push(model).compose(&world.world_pose(cube).expect("a pose"));
    let table = world.find_by_name("table").expect("the table");
    let under = world.world_pose(table).expect("a pose");
    world
        .update(
            cube,
            None,
            None,
            Some(under.inverse().compose(&placed)),
            None,
        )
        .expect("pushed");
    let wedge = world.find_by_name("wedge").expect("the wedge");
    world.kill(wedge).expect("taken away");
    put_stranger(&mut world);
    world
}

/// Puts a box the model lacks on the table.
fn put_stranger(world: &mut World) {
    let root = world.root();
    world
        .insert_with(
            Some("stranger"),
            root,
            Pose::from_translation(STRANGER_AT),
            |s| box_solid(s, STRANGER_SIZE),
        )
        .expect("a box");
}

/// Pixels (row-major) where the stranger is the nearest surface in the truth.
fn stranger_pixels(truth: &World, camera: &Camera) -> Vec<bool> {
    let whole = raycast::draw(&Scene::build(truth), camera, &raycast::Look::default());
    let mut alone = World::new();
    put_stranger(&mut alone);
    let only = raycast::draw(&Scene::build(&alone), camera, &raycast::Look::default());
    whole
        .depth
        .iter()
        .zip(&only.depth)
        .map(|(&d, &s)| s.is_finite() && (d - s).abs() < 1e-9)
        .collect()
}

fn png_depth(width: u32, height: u32, units: &[u16]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Sixteen);
    let bytes: Vec<u8> = units.iter().flat_map(|u| u.to_be_bytes()).collect();
    encoder
        .write_header()
        .expect("a header")
        .write_image_data(&bytes)
        .expect("samples");
    out
}

/// The pictures of the truth: noisy RGB PNG, and a 16-bit depth PNG in millimetres.
struct Pictures {
    image: Vec<u8>,
    depth: Vec<u8>,
    stranger: Vec<bool>,
}

fn pictures(model: &World, camera: &Camera) -> Pictures {
    let truth = truth(model);
    let drawn = raycast::draw(&Scene::build(&truth), camera, &raycast::Look::default());
    let noisy = raycast::with_noise(&drawn.rgb, 8.0, 3);
    let units = raycast::depth_units(&drawn.depth, 0.001);
    Pictures {
        image: png_rgb(drawn.width, drawn.height, &noisy),
        depth: png_depth(drawn.width, drawn.height, &units),
        stranger: stranger_pixels(&truth, camera),
    }
}

fn by_name<'a>(answer: &'a Value, name: &str) -> &'a Value {
    answer["bodies"]
        .as_array()
        .expect("bodies")
        .iter()
        .find(|b| b["name"] == name)
        .unwrap_or_else(|| panic!("no {name} in {answer}"))
}

fn revision(s: &TestServer) -> u64 {
    s.get("/v1/world").ok()["revision"]
        .as_u64()
        .expect("a revision")
}

/// The pixel mask of a base64 PNG answered as `unexplained_mask`.
fn mask_of(answer: &Value) -> Vec<bool> {
    let png = BASE64
        .decode(answer["unexplained_mask"].as_str().expect("a mask"))
        .expect("base64");
    let decoder = png::Decoder::new(std::io::Cursor::new(png));
    let mut reader = decoder.read_info().expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size().expect("a size")];
    let info = reader.next_frame(&mut buf).expect("a frame");
    assert_eq!((info.width, info.height), (640, 480));
    buf[..info.buffer_size()].iter().map(|&v| v > 0).collect()
}

fn iou(a: &[bool], b: &[bool]) -> f64 {
    let both = a.iter().zip(b).filter(|(x, y)| **x && **y).count();
    let either = a.iter().zip(b).filter(|(x, y)| **x || **y).count();
    both as f64 / either.max(1) as f64
}

/// The checks both forms of evidence must pass.
fn check_statuses(a: &Value, model: &World) {
    for name in ["table", "pyramid", "drum"] {
        let b = by_name(a, name);
        assert_eq!(b["status"], "seen", "{name}: {b}");
        assert!(b["score"].as_f64().expect("a score") > 0.5, "{name}: {b}");
    }
    let wedge = by_name(a, "wedge");
    assert_eq!(wedge["status"], "absent", "{wedge}");
    let cube = by_name(a, "cube");
    assert_eq!(cube["status"], "moved", "{cube}");
    let truth = push(model).compose(
        &model
            .world_pose(model.find_by_name("cube").expect("the cube"))
            .expect("a pose"),
    );
    let p = &cube["pose"];
    let (position, rotation) = pose_of(p);
    let offset = position.distance(truth.position);
    let angle = rotation.angle_between(truth.rotation).to_degrees();
    assert!(offset < 0.01 && angle < 1.0, "{offset} m, {angle}°: {cube}");
    for b in a["bodies"].as_array().expect("bodies") {
        let f = b["visible_fraction"].as_f64().expect("a fraction");
        assert!((0.0..=1.0).contains(&f), "{b}");
    }
}

/// The demo model served with the camera stored as `robot`, and pictures of the truth.
fn served() -> (World, TestServer, Camera, Pictures) {
    let model = winged::server::demo::demo_world().expect("the demo world");
    let s = TestServer::with_world(model.clone());
    let camera = demo_camera();
    s.put("/v1/cameras/robot", &camera_json(&camera)).ok();
    let pics = pictures(&model, &camera);
    (model, s, camera, pics)
}

#[test]
fn a_pushed_block_a_missing_one_and_a_stranger_over_http() {
    let (model, s, camera, pics) = served();
    let before = revision(&s);

    // From the picture alone, the camera stored.
    let a = s
        .post(
            "/v1/recognition",
            &json!({"camera": "robot", "image": BASE64.encode(&pics.image), "unexplained_mask": true}),
        )
        .ok();
    assert_eq!(a["revision"], before);
    check_statuses(&a, &model);
    let regions = a["unexplained"].as_array().expect("regions");
    assert!(!regions.is_empty(), "{a}");
    let from_image = iou(&mask_of(&a), &pics.stranger);
    eprintln!(
        "from the image: IoU {from_image:.3}, {} ms",
        a["elapsed_ms"]
    );
    assert!(
        from_image >= 0.6,
        "IoU with the stranger from the image: {from_image}"
    );

    // With depth, the camera inline.
    let a = s
        .post(
            "/v1/recognition",
            &json!({
                "camera": camera_json(&camera),
                "image": BASE64.encode(&pics.image),
                "depth": BASE64.encode(&pics.depth),
                "depth_scale": 0.001,
                "unexplained_mask": true,
            }),
        )
        .ok();
    check_statuses(&a, &model);
    let table = by_name(&a, "table");
    assert!(
        table["evidence"]["depth_agreement"]
            .as_f64()
            .expect("agreement")
            > 0.8,
        "{table}"
    );
    let with_depth = iou(&mask_of(&a), &pics.stranger);
    eprintln!("with depth: IoU {with_depth:.3}, {} ms", a["elapsed_ms"]);
    assert!(
        with_depth >= 0.8,
        "IoU with the stranger with depth: {with_depth}"
    );

    // The raw form.
    let a = s
        .post_raw("/v1/recognition?camera=robot", "image/png", &pics.image)
        .ok();
    check_statuses(&a, &model);
    assert_eq!(
        revision(&s),
        before,
        "recognition without update writes nothing"
    );

    // With update, the cube's corrected pose is written in one revision.
    let a = s
        .post(
            "/v1/recognition",
            &json!({"camera": "robot", "image": BASE64.encode(&pics.image), "update": true}),
        )
        .ok();
    assert_eq!(a["updated_revision"], before + 1, "{a}");
    assert_eq!(revision(&s), before + 1);
    let again = s
        .post(
            "/v1/recognition",
            &json!({"camera": "robot", "image": BASE64.encode(&pics.image)}),
        )
        .ok();
    let cube = by_name(&again, "cube");
    assert_eq!(cube["status"], "seen", "after the update: {cube}");
}

#[test]
fn bad_requests_get_problems_and_change_nothing() {
    let (_, s, camera, pics) = served();
    let before = revision(&s);
    let image = BASE64.encode(&pics.image);
    let small = BASE64.encode(png_rgb(32, 24, &vec![128; 32 * 24 * 3]));
    let small_depth = BASE64.encode(png_depth(32, 24, &vec![1000; 32 * 24]));
    let mut nan_camera = camera_json(&camera);
    nan_camera["intrinsics"]["fx"] = json!("NaN");
    let mut no_rotation = camera_json(&camera);
    no_rotation["pose"]["rotation"] = json!([0.0, 0.0, 0.0, 0.0]);
    let cases: Vec<(Value, u16)> = vec![
        (json!({"image": image}), 400),
        (json!({"camera": "robot"}), 400),
        (json!({"camera": "nobody", "image": image}), 404),
        (json!({"camera": "robot", "image": small}), 422),
        (json!({"camera": "robot", "image": "%%%"}), 400),
        (
            json!({"camera": "robot", "image": BASE64.encode(b"not a png")}),
            400,
        ),
        (
            json!({"camera": "robot", "image": BASE64.encode(&pics.image[..200])}),
            400,
        ),
        (
            json!({"camera": "robot", "image": image, "depth": small_depth}),
            422,
        ),
        (
            json!({"camera": "robot", "image": image, "depth": image}),
            400,
        ),
        (
            json!({"camera": "robot", "image": image, "depth_scale": -1.0}),
            422,
        ),
        (
            json!({"camera": "robot", "image": image, "search": {"translation_m": 0.0}}),
            422,
        ),
        (
            json!({"camera": "robot", "image": image, "surprise": 1}),
            400,
        ),
        (json!({"camera": nan_camera, "image": image}), 400),
        (json!({"camera": no_rotation, "image": image}), 422),
    ];
    for (body, status) in cases {
        let p = s.post("/v1/recognition", &body).problem(status);
        assert!(p["detail"].is_string(), "{p}");
    }
    // The raw form needs a camera, and the body must be JSON or PNG.
    s.post_raw("/v1/recognition", "image/png", &pics.image)
        .problem(400);
    s.post_raw("/v1/recognition?camera=robot", "text/plain", b"hello")
        .problem(415);
    assert_eq!(revision(&s), before);

    // A camera that sees none of the model is a valid question: no bodies, and the
    // picture's edges are unexplained.
    let away = Camera::look_at(
        DVec3::new(0.0, 0.0, 0.8),
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::X,
        camera.intrinsics,
    )
    .expect("a camera");
    let a = s
        .post(
            "/v1/recognition",
            &json!({"camera": camera_json(&away), "image": image}),
        )
        .ok();
    assert_eq!(a["bodies"].as_array().map(Vec::len), Some(0), "{a}");
    assert!(
        !a["unexplained"].as_array().expect("regions").is_empty(),
        "{a}"
    );

    // A blank picture shows nothing of the model: every body in view is absent. Aligning
    // the camera with it is refused.
    let blank = BASE64.encode(png_rgb(640, 480, &vec![90; 640 * 480 * 3]));
    let a = s
        .post(
            "/v1/recognition",
            &json!({"camera": "robot", "image": blank}),
        )
        .ok();
    let bodies = a["bodies"].as_array().expect("bodies");
    assert!(!bodies.is_empty(), "{a}");
    assert!(bodies.iter().all(|b| b["status"] == "absent"), "{a}");
    let p = s
        .post(
            "/v1/recognition",
            &json!({"camera": "robot", "image": blank, "refine_camera": true}),
        )
        .problem(422);
    assert!(
        p["type"]
            .as_str()
            .expect("a type")
            .ends_with("no-image-edges"),
        "{p}"
    );
    assert_eq!(revision(&s), before);
}
