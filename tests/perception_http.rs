//! Perception over real HTTP (`POST /v1/perception`), from masks that winged did not
//! draw: a ray caster in the test draws the world as it really is, a box the model
//! lacks (the "cup") standing behind a crate the model has, and marks where the cup is
//! the nearest surface. Eight cameras stand around it; four views make a provisional
//! body, four more carve it further. The crate hides the cup's foot from some views,
//! which must not cut it off. Bad input gets problem+json answers and leaves the world
//! unchanged.

#[path = "support/raycast.rs"]
mod raycast;
#[path = "support/http.rs"]
mod support;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as BASE64;
use glam::DVec3;
use serde_json::{Value, json};
use support::{TestServer, camera_json, png_rgb};
use winged::model::solids::box_solid;
use winged::model::{Camera, Intrinsics, Pose, World};
use winged::render::Scene;

const CUP_AT: DVec3 = DVec3::new(0.0, 0.0, 0.06);
const CUP_SIZE: DVec3 = DVec3::new(0.08, 0.06, 0.12);
const CRATE_AT: DVec3 = DVec3::new(0.2, 0.0, 0.04);
const CRATE_SIZE: DVec3 = DVec3::new(0.06, 0.3, 0.08);

/// The model: the crate alone.
fn model() -> World {
    let mut w = World::new();
    let root = w.root();
    w.insert_with(Some("crate"), root, Pose::from_translation(CRATE_AT), |s| {
        box_solid(s, CRATE_SIZE)
    })
    .expect("the crate");
    w
}

/// The cup alone.
fn cup() -> World {
    let mut w = World::new();
    let root = w.root();
    w.insert_with(Some("cup"), root, Pose::from_translation(CUP_AT), |s| {
        box_solid(s, CUP_SIZE)
    })
    .expect("the cup");
    w
}

/// The world as it is: the crate and the cup.
fn truth() -> World {
    let mut w = model();
    let root = w.root();
    w.insert_with(Some("cup"), root, Pose::from_translation(CUP_AT), |s| {
        box_solid(s, CUP_SIZE)
    })
    .expect("the cup");
    w
}

/// Eight cameras 0.7 m from the cup, 25° above the floor, camera 0 behind the crate.
fn cameras() -> Vec<Camera> {
    let k = Intrinsics::centered(640, 480, 700.0).expect("intrinsics");
    (0..8)
        .map(|i| {
            let a = (i as f64) * std::f64::consts::TAU / 8.0;
            let e = 25f64.to_radians();
            let eye = CUP_AT + DVec3::new(a.cos() * e.cos(), a.sin() * e.cos(), e.sin()) * 0.7;
            Camera::look_at(eye, CUP_AT, DVec3::Z, k).expect("a camera")
        })
        .collect()
}

/// Pixels where the cup is the nearest surface, and the truth's picture.
fn seen(camera: &Camera) -> (Vec<bool>, Vec<u8>) {
    let look = raycast::Look::default();
    let whole = raycast::draw(&Scene::build(&truth()), camera, &look);
    let alone = raycast::draw(&Scene::build(&cup()), camera, &look);
    let mask = whole
        .depth
        .iter()
        .zip(&alone.depth)
        .map(|(&d, &s)| s.is_finite() && (d - s).abs() < 1e-9)
        .collect();
    let noisy = raycast::with_noise(&whole.rgb, 8.0, 5);
    (mask, png_rgb(whole.width, whole.height, &noisy))
}

/// A mask as a base64 grey PNG, 255 inside.
fn mask_png(width: u32, height: u32, bits: &[bool]) -> String {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Grayscale);
    let samples: Vec<u8> = bits.iter().map(|&b| if b { 255 } else { 0 }).collect();
    encoder
        .write_header()
        .expect("a header")
        .write_image_data(&samples)
        .expect("samples");
    BASE64.encode(out)
}

fn revision(s: &TestServer) -> u64 {
    s.get("/v1/world").ok()["revision"]
        .as_u64()
        .expect("a revision")
}

/// The body's vertices (world coordinates: its pose is the identity) and faces.
fn polygons(s: &TestServer, id: u64) -> (Vec<DVec3>, Vec<Vec<u32>>) {
    let t = s.get(&format!("/v1/bodies/{id}/topology")).ok();
    let mut index = std::collections::HashMap::new();
    let mut positions = Vec::new();
    for v in t["vertices"].as_array().expect("vertices") {
        let p = &v["position"];
        let c = |k: usize| p[k].as_f64().expect("a coordinate");
        index.insert(v["id"].as_u64().expect("an id"), positions.len() as u32);
        positions.push(DVec3::new(c(0), c(1), c(2)));
    }
    let faces = t["faces"]
        .as_array()
        .expect("faces")
        .iter()
        .map(|f| {
            f["vertices"]
                .as_array()
                .expect("a ring")
                .iter()
                .map(|v| index[&v.as_u64().expect("an id")])
                .collect()
        })
        .collect();
    (positions, faces)
}

/// The winding number of the body about `x` (1 inside, 0 outside).
fn winding((positions, faces): &(Vec<DVec3>, Vec<Vec<u32>>), x: DVec3) -> f64 {
    winged::model::geometry::winding_number(positions, faces, x)
}

/// The cup's corners, pulled in by a micrometre.
fn cup_corners() -> Vec<DVec3> {
    let h = CUP_SIZE / 2.0 - 1e-6;
    (0..8)
        .map(|i| {
            CUP_AT
                + DVec3::new(
                    if i & 1 == 0 { -h.x } else { h.x },
                    if i & 2 == 0 { -h.y } else { h.y },
                    if i & 4 == 0 { -h.z } else { h.z },
                )
        })
        .collect()
}

/// A server holding the model and the eight cameras, with each view's mask.
fn setup() -> (TestServer, Vec<Value>, Vec<Camera>) {
    let s = TestServer::with_world(model());
    let cams = cameras();
    let mut views = Vec::new();
    for (i, c) in cams.iter().enumerate() {
        s.put(&format!("/v1/cameras/c{i}"), &camera_json(c)).ok();
        let (mask, _) = seen(c);
        let k = c.intrinsics;
        views.push(json!({"camera": format!("c{i}"), "mask": mask_png(k.width, k.height, &mask)}));
    }
    (s, views, cams)
}

#[test]
fn four_views_make_a_body_and_four_more_carve_it_keeping_what_the_crate_hides() {
    let (s, views, cams) = setup();
    // The crate hides the cup's foot from camera 0: its mask lacks those pixels.
    let (mask0, _) = seen(&cams[0]);
    let foot = CUP_AT + DVec3::new(CUP_SIZE.x / 2.0 - 1e-3, 0.0, -CUP_SIZE.z / 2.0 + 1e-3);
    let q = cams[0].project(foot).expect("in front");
    assert!(
        !mask0[q.y as usize * 640 + q.x as usize],
        "the foot is hidden from camera 0"
    );

    let made = s.post(
        "/v1/perception",
        &json!({"views": views[..4], "name": "cup"}),
    );
    assert_eq!(made.status, 201, "{}", made.json());
    let made = made.json();
    let inserted = made["inserted"].as_array().expect("inserted");
    assert_eq!(inserted.len(), 1, "{made}");
    let id = inserted[0]["id"].as_u64().expect("an id");
    assert_eq!(inserted[0]["name"], "cup");
    assert_eq!(inserted[0]["views"], 4);
    let first_volume = inserted[0]["volume"].as_f64().expect("a volume");
    let body = s.get(&format!("/v1/bodies/{id}")).ok();
    assert_eq!(body["provisional"], true, "{body}");
    assert_eq!(body["views"], 4);
    let faces = polygons(&s, id);
    for x in cup_corners() {
        assert!(
            (winding(&faces, x) - 1.0).abs() < 1e-6,
            "{x} cut away by 4 views"
        );
    }

    let carved = s
        .post("/v1/perception", &json!({"views": views[4..], "body": id}))
        .ok();
    assert_eq!(carved["carved"][0]["id"], id, "{carved}");
    assert_eq!(carved["carved"][0]["views"], 8);
    assert_eq!(carved["carved"][0]["name"], "cup");
    assert!(carved["inserted"].as_array().expect("inserted").is_empty());
    let volume = carved["carved"][0]["volume"].as_f64().expect("a volume");
    let truth = CUP_SIZE.x * CUP_SIZE.y * CUP_SIZE.z;
    assert!(
        volume < first_volume && volume > truth && volume < 2.0 * truth,
        "4 views {first_volume}, 8 views {volume}, the cup {truth}"
    );
    let faces = polygons(&s, id);
    for x in cup_corners() {
        assert!(
            (winding(&faces, x) - 1.0).abs() < 1e-6,
            "{x} cut away by 8 views"
        );
    }
    assert!(
        (winding(&faces, foot) - 1.0).abs() < 1e-6,
        "the hidden foot is kept"
    );
    // Every face says which view made it.
    let topology = s.get(&format!("/v1/bodies/{id}/topology")).ok();
    let made_by: Vec<&Value> = topology["faces"]
        .as_array()
        .expect("faces")
        .iter()
        .map(|f| &f["made_by"])
        .collect();
    assert!(made_by.iter().all(|m| m["kind"] == "wall"), "{made_by:?}");
    let views_seen: std::collections::BTreeSet<u64> =
        made_by.iter().filter_map(|m| m["view"].as_u64()).collect();
    assert!(views_seen.iter().any(|&v| v >= 4), "{views_seen:?}");

    // A view that sees the cup nowhere near where the body is carves it away.
    let corner: Vec<bool> = (0..480 * 640)
        .map(|i| i % 640 < 40 && i / 640 < 40)
        .collect();
    let gone = s
        .post(
            "/v1/perception",
            &json!({"views": [{"camera": "c4", "mask": mask_png(640, 480, &corner)}], "body": id}),
        )
        .ok();
    assert_eq!(gone["removed"], json!([id]), "{gone}");
    assert_eq!(s.get(&format!("/v1/bodies/{id}")).status, 404);
}

/// The loop closed: recognition on the pictures the masks came from reports the body
/// perception made `seen`, with at most 0.5 % of its pixels unexplained. Not met yet:
/// from camera 5 the hull's outline finds image edges along 33 % of its length, and the
/// body is reported absent (see BENCHMARKS.md, Perception).
#[test]
#[ignore = "goal not met: the hull's outline is supported along 33 % of its length in view 5"]
fn recognition_sees_the_perceived_body_where_it_stands() {
    let (s, views, cams) = setup();
    let made = s
        .post("/v1/perception", &json!({"views": views, "name": "cup"}))
        .ok();
    let id = made["inserted"][0]["id"].as_u64().expect("an id");
    for view in [2usize, 5] {
        let (cup_pixels, picture) = seen(&cams[view]);
        let answer = s
            .post(
                "/v1/recognition",
                &json!({"camera": format!("c{view}"), "image": BASE64.encode(picture),
                        "unexplained_mask": true, "search": null}),
            )
            .ok();
        let cup = answer["bodies"]
            .as_array()
            .expect("bodies")
            .iter()
            .find(|b| b["id"] == id)
            .unwrap_or_else(|| panic!("the cup is not in view {view}: {answer}"));
        assert_eq!(cup["status"], "seen", "view {view}: {cup}");
        let png = BASE64
            .decode(answer["unexplained_mask"].as_str().expect("a mask"))
            .expect("base64");
        let mut reader = png::Decoder::new(std::io::Cursor::new(png))
            .read_info()
            .expect("a PNG");
        let mut buf = vec![0; reader.output_buffer_size().expect("a size")];
        reader.next_frame(&mut buf).expect("pixels");
        let total = cup_pixels.iter().filter(|&&b| b).count();
        let unexplained = cup_pixels
            .iter()
            .zip(&buf)
            .filter(|&(&c, &m)| c && m != 0)
            .count();
        let share = unexplained as f64 / total as f64;
        assert!(
            share <= 0.005,
            "view {view}: {unexplained} of the cup's {total} pixels unexplained ({share:.4})"
        );
    }
}

#[test]
fn bad_views_are_refused_and_change_nothing() {
    let (s, views, _) = setup();
    let crate_id = s.get("/v1/bodies?name=crate").ok()["bodies"][0]["id"]
        .as_u64()
        .expect("the crate");
    let before = revision(&s);
    let small = mask_png(8, 8, &[true; 64]);
    let empty = mask_png(640, 480, &vec![false; 640 * 480]);
    // A patch in a corner of camera 4's picture: its cone misses camera 0's.
    let corner: Vec<bool> = (0..480 * 640)
        .map(|i| i % 640 < 40 && i / 640 < 40)
        .collect();
    let corner = mask_png(640, 480, &corner);
    let cases = [
        (
            json!({"views": [{"camera": "c0", "mask": small}]}),
            422,
            "invalid-mask",
        ),
        (
            json!({"views": [{"camera": "c0", "mask": empty}]}),
            422,
            "empty-mask",
        ),
        (
            json!({"views": [{"camera": "nobody", "mask": small}]}),
            404,
            "not-found",
        ),
        (json!({"views": [{"camera": "c0"}]}), 400, "bad-request"),
        (
            json!({"views": [{"camera": "c0", "mask": "not base64!"}]}),
            400,
            "bad-request",
        ),
        (
            json!({"views": [{"camera": "c0", "mask": BASE64.encode(b"not a PNG")}]}),
            400,
            "invalid-image",
        ),
        (
            json!({"views": [views[0]], "near": 2.0, "far": 1.0}),
            422,
            "invalid-parameter",
        ),
        (
            json!({"views": [views[0]], "tolerance_px": -1.0}),
            422,
            "invalid-parameter",
        ),
        (json!({"views": []}), 422, "invalid-parameter"),
        (
            json!({"views": [views[0]], "body": 999_999}),
            404,
            "not-found",
        ),
        (
            json!({"views": [views[0]], "body": crate_id}),
            422,
            "not-provisional",
        ),
        (
            json!({"views": [{"camera": {"pose": {"position": [0.0, 0.0, 1.0], "rotation": [0.0, 0.0, 0.0, 1.0]},
                                          "intrinsics": {"width": 640, "height": 480, "fx": 0.0, "fy": 600.0, "cx": 320.0, "cy": 240.0}},
                              "mask": small}]}),
            422,
            "invalid-camera",
        ),
        (
            json!({"views": [views[0], {"camera": "c4", "mask": corner}]}),
            422,
            "cones-apart",
        ),
    ];
    for (body, status, kind) in cases {
        let reply = s.post("/v1/perception", &body);
        let p = reply.problem(status);
        assert_eq!(
            p["type"],
            format!("urn:winged:problem:{kind}"),
            "{p} for {}",
            serde_json::to_string(&body)
                .expect("JSON")
                .chars()
                .take(200)
                .collect::<String>()
        );
        if kind == "cones-apart" {
            let detail = p["detail"].as_str().expect("a detail");
            assert!(detail.contains("[0, 1]"), "the views are named: {detail}");
        }
        assert_eq!(revision(&s), before, "{p}");
    }
    assert!(s.get("/v1/healthz").status == 404 || s.get("/healthz").status == 200);
}
