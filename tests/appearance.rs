//! Appearance over real HTTP: every mode and format from a stored or inline camera, the
//! numbers an image carries (depth scale, ids legend), and bad requests refused with
//! problem+json while the world stays as it was.

#[path = "support/http.rs"]
mod support;

use glam::DVec3;
use serde_json::{Value, json};
use support::TestServer;
use winged::model::{Camera, Intrinsics, Pose, World, solids};

/// A decoded PNG: size, channels, bit depth and samples (16-bit samples as u16).
struct Png {
    width: u32,
    height: u32,
    channels: usize,
    depth16: bool,
    samples: Vec<u16>,
}

impl Png {
    fn decode(bytes: &[u8]) -> Png {
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes.to_vec()));
        let mut reader = decoder.read_info().expect("a PNG header");
        let mut buf = vec![0; reader.output_buffer_size().expect("a size")];
        let info = reader.next_frame(&mut buf).expect("PNG data");
        let channels = info.color_type.samples();
        let depth16 = info.bit_depth == png::BitDepth::Sixteen;
        let samples = if depth16 {
            buf[..info.buffer_size()]
                .chunks_exact(2)
                .map(|c| u16::from_be_bytes([c[0], c[1]]))
                .collect()
        } else {
            buf[..info.buffer_size()]
                .iter()
                .map(|&b| b as u16)
                .collect()
        };
        Png {
            width: info.width,
            height: info.height,
            channels,
            depth16,
            samples,
        }
    }

    fn at(&self, x: u32, y: u32) -> &[u16] {
        let i = (y as usize * self.width as usize + x as usize) * self.channels;
        &self.samples[i..i + self.channels]
    }
}

const W: u32 = 320;
const H: u32 = 240;
const F: f64 = 300.0;

fn eye() -> DVec3 {
    DVec3::new(3.0, -4.0, 2.5)
}

/// A world with one unit cube at the origin and a camera "eye" looking at it.
fn cube_world() -> World {
    let mut w = World::new();
    let root = w.root();
    w.insert_with(Some("cube"), root, Pose::IDENTITY, |s| {
        solids::mkcube(s, 1.0, 1.0, 1.0)
    })
    .unwrap();
    let k = Intrinsics::centered(W, H, F).unwrap();
    let cam = Camera::look_at(eye(), DVec3::ZERO, DVec3::Z, k).unwrap();
    w.set_camera("eye", cam).unwrap();
    w
}

fn revision(s: &TestServer) -> u64 {
    s.get("/v1/world").ok()["revision"].as_u64().unwrap()
}

#[test]
fn every_mode_is_a_png_of_the_cameras_size() {
    let s = TestServer::with_world(cube_world());
    for (mode, channels, depth16) in [
        ("shaded", 3, false),
        ("wire", 3, false),
        ("hidden", 3, false),
        ("depth", 1, true),
        ("ids", 1, true),
    ] {
        let r = s.get(&format!("/v1/cameras/eye/image?mode={mode}"));
        assert_eq!(r.status, 200, "{mode}: {}", r.text);
        assert_eq!(r.content_type, "image/png", "{mode}");
        assert_eq!(r.header("etag"), format!("\"{}\"", revision(&s)));
        let png = Png::decode(&r.bytes);
        assert_eq!((png.width, png.height), (W, H), "{mode}");
        assert_eq!((png.channels, png.depth16), (channels, depth16), "{mode}");
        // Something is drawn: the image is not one flat colour.
        let first = png.at(0, 0).to_vec();
        let drawn = (0..H).any(|y| (0..W).any(|x| png.at(x, y) != first.as_slice()));
        assert!(drawn, "{mode}: the cube is in view");
    }
    // The default is shaded, and a size can be asked for (aspect kept with one side).
    let r = s.get("/v1/cameras/eye/image?width=160");
    let png = Png::decode(&r.bytes);
    assert_eq!((png.width, png.height, png.channels), (160, 120, 3));
}

/// The distance along the view axis to the first face of the unit cube hit by the ray
/// through pixel centre (u, v), by the slab method.
fn cube_depth(cam: &Camera, u: f64, v: f64) -> Option<f64> {
    let d = cam.pixel_ray(glam::DVec2::new(u, v));
    let o = cam.position();
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for a in 0..3 {
        let (lo, hi) = ((-0.5 - o[a]) / d[a], (0.5 - o[a]) / d[a]);
        t0 = t0.max(lo.min(hi));
        t1 = t1.min(lo.max(hi));
    }
    (t0 <= t1).then(|| (d * t0).dot(cam.view_direction()))
}

#[test]
fn depth_values_times_the_scale_are_distances_along_the_view_axis() {
    let world = cube_world();
    let cam = *world.camera("eye").unwrap();
    let s = TestServer::with_world(world);
    let r = s.get("/v1/cameras/eye/image?mode=depth&depth_scale=0.0001");
    assert_eq!(r.status, 200, "{}", r.text);
    let scale: f64 = r.header("x-depth-scale").parse().unwrap();
    assert_eq!(scale, 0.0001);
    assert_eq!(r.header("x-depth-background"), "0");
    let png = Png::decode(&r.bytes);
    let (cx, cy) = (W / 2, H / 2);
    let expected = cube_depth(&cam, cx as f64 + 0.5, cy as f64 + 0.5).unwrap();
    let got = png.at(cx, cy)[0] as f64 * scale;
    assert!(
        (got - expected).abs() / expected < 1e-3,
        "depth {got} m, analytic {expected} m"
    );
    assert_eq!(png.at(0, 0)[0], 0, "no surface: 0");
}

/// The id of the body named "cube".
fn cube_id(s: &TestServer) -> u64 {
    s.get("/v1/bodies").ok()["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .find(|b| b["name"] == "cube")
        .unwrap()["id"]
        .as_u64()
        .unwrap()
}

#[test]
fn ids_name_the_body_through_the_legend_and_json_counts_its_pixels() {
    let s = TestServer::with_world(cube_world());
    let cube = cube_id(&s);
    let r = s.get("/v1/cameras/eye/image?mode=ids");
    assert_eq!(r.header("x-body-ids"), format!("1={cube}"));
    let png = Png::decode(&r.bytes);
    assert_eq!(png.at(W / 2, H / 2)[0], 1);
    assert_eq!(png.at(0, 0)[0], 0);
    let covered = png.samples.iter().filter(|&&v| v == 1).count() as u64;

    let j = s.get("/v1/cameras/eye/image?mode=ids&format=json").ok();
    let bodies = j["bodies"].as_array().unwrap();
    assert_eq!(bodies.len(), 1);
    assert_eq!(bodies[0]["id"], cube);
    assert_eq!(bodies[0]["name"], "cube");
    assert_eq!(bodies[0]["value"], 1);
    assert_eq!(bodies[0]["pixels"], covered);
    let bbox: Vec<u64> = bodies[0]["bbox"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert!(bbox[0] < bbox[2] && bbox[1] < bbox[3] && bbox[2] <= W as u64);
}

#[test]
fn hidden_lines_come_as_png_json_and_svg() {
    let s = TestServer::with_world(cube_world());
    let j = s.get("/v1/cameras/eye/image?mode=hidden&format=json").ok();
    let segments = j["segments"].as_array().unwrap();
    let edges: std::collections::BTreeSet<u64> = segments
        .iter()
        .map(|seg| seg["edge"].as_u64().unwrap())
        .collect();
    assert_eq!(edges.len(), 9, "a cube in general position shows 9 edges");
    assert_eq!(
        (j["width"].as_u64(), j["height"].as_u64()),
        (Some(320), Some(240))
    );
    let r = s.get("/v1/cameras/eye/image?mode=hidden&format=svg");
    assert_eq!(r.status, 200);
    assert_eq!(r.content_type, "image/svg+xml");
    assert!(r.text.contains("<svg") && r.text.contains("viewBox"));
}

#[test]
fn post_appearance_takes_a_named_or_an_inline_camera() {
    let s = TestServer::with_world(cube_world());
    let named = s.post("/v1/appearance", &json!({"camera": "eye", "mode": "ids"}));
    assert_eq!(named.status, 200, "{}", named.text);
    let inline = s.post(
        "/v1/appearance",
        &json!({
            "camera": {
                "look_at": {"eye": eye().to_array(), "target": [0, 0, 0]},
                "intrinsics": {"width": W, "height": H, "fx": F, "fy": F,
                               "cx": W as f64 / 2.0, "cy": H as f64 / 2.0}
            },
            "mode": "ids"
        }),
    );
    assert_eq!(inline.status, 200, "{}", inline.text);
    assert_eq!(
        Png::decode(&named.bytes).samples,
        Png::decode(&inline.bytes).samples,
        "the same camera by name and inline draws the same image"
    );
}

#[test]
fn cameras_inside_or_facing_away_draw_correct_images() {
    let s = TestServer::with_world(cube_world());
    let k = json!({"width": 64, "height": 48, "fx": 50, "fy": 50, "cx": 32, "cy": 24});
    // Facing away: nothing in view, every pixel is background.
    let away = s.post(
        "/v1/appearance",
        &json!({"camera": {"look_at": {"eye": [0, 0, 3], "target": [0.5, 0.2, 6]}, "intrinsics": k},
                "mode": "ids"}),
    );
    assert_eq!(away.status, 200, "{}", away.text);
    assert!(Png::decode(&away.bytes).samples.iter().all(|&v| v == 0));
    // Inside the cube: its faces are all seen from behind and culled; nothing is hidden
    // by anything, and nothing panics.
    for mode in ["shaded", "wire", "hidden", "depth", "ids"] {
        let inside = s.post(
            "/v1/appearance",
            &json!({"camera": {"look_at": {"eye": [0.1, 0.1, 0.1], "target": [1, 0, 0]},
                               "intrinsics": k}, "mode": mode}),
        );
        assert_eq!(inside.status, 200, "{mode}: {}", inside.text);
    }
    // A 1×1 image.
    let tiny = s.get("/v1/cameras/eye/image?mode=depth&width=1&height=1");
    assert_eq!(Png::decode(&tiny.bytes).samples.len(), 1);
}

#[test]
fn bad_requests_are_problems_and_change_nothing() {
    let limits = winged::server::Limits {
        max_render_pixels: 1_000_000,
        ..winged::server::Limits::default()
    };
    let s = TestServer::with_limits(cube_world(), limits);
    let before = revision(&s);
    let problems: Vec<(&str, u16)> = vec![
        ("/v1/cameras/nobody/image", 404),
        ("/v1/cameras/eye/image?mode=bogus", 400),
        ("/v1/cameras/eye/image?format=gif", 400),
        ("/v1/cameras/eye/image?mode=shaded&format=json", 422),
        ("/v1/cameras/eye/image?mode=depth&format=svg", 422),
        ("/v1/cameras/eye/image?width=0", 400),
        ("/v1/cameras/eye/image?width=20000", 400),
        ("/v1/cameras/eye/image?width=2000&height=2000", 422),
        ("/v1/cameras/eye/image?near=-1", 400),
        ("/v1/cameras/eye/image?near=NaN", 400),
        ("/v1/cameras/eye/image?depth_scale=0", 400),
        ("/v1/cameras/eye/image?background=red", 400),
        ("/v1/cameras/eye/image?colour=red", 400),
    ];
    for (path, status) in problems {
        let r = s.get(path);
        assert_eq!(r.status, status, "{path}: {}", r.text);
        r.problem(status);
    }
    let k = json!({"width": 64, "height": 48, "fx": 50, "fy": 50, "cx": 32, "cy": 24});
    let bodies: Vec<(Value, u16)> = vec![
        (json!({"mode": "ids"}), 400),
        (json!({"camera": "nobody"}), 404),
        (json!({"camera": 7}), 400),
        (
            json!({"camera": {"look_at": {"eye": [1, 1, 1], "target": [1, 1, 1]},
                              "intrinsics": k}}),
            422,
        ),
        (
            json!({"camera": {"look_at": {"eye": [1, 1, 1], "target": [0, 0, 0]},
                              "intrinsics": {"width": 64, "height": 48, "fx": -5, "fy": 50,
                                             "cx": 32, "cy": 24}}}),
            422,
        ),
        (json!({"camera": "eye", "depth_scale": -1}), 400),
        (json!({"camera": "eye", "unknown": 1}), 400),
    ];
    for (body, status) in bodies {
        let r = s.post("/v1/appearance", &body);
        assert_eq!(r.status, status, "{body}: {}", r.text);
        r.problem(status);
    }
    let broken = s.post_raw("/v1/appearance", "application/json", b"{\"camera\": ");
    broken.problem(400);
    assert_eq!(revision(&s), before, "reads change nothing");
    assert_eq!(s.get("/healthz").status, 200);
}

#[test]
fn a_drawing_follows_the_world() {
    let s = TestServer::with_world(cube_world());
    let ids = |s: &TestServer| Png::decode(&s.get("/v1/cameras/eye/image?mode=ids").bytes);
    let covered = |p: &Png| p.samples.iter().filter(|&&v| v != 0).count();
    let before = covered(&ids(&s));
    let cube = cube_id(&s);
    // Move the cube out of view: the next drawing is empty.
    s.patch(
        &format!("/v1/bodies/{cube}"),
        &json!({"pose": {"position": [0, 0, 50]}}),
    )
    .ok();
    assert!(before > 1000);
    assert_eq!(covered(&ids(&s)), 0);
    // Colour shows in shaded mode.
    s.patch(
        &format!("/v1/bodies/{cube}"),
        &json!({"pose": {"position": [0, 0, 0]}, "color": "#ff0000"}),
    )
    .ok();
    assert_eq!(
        s.get(&format!("/v1/bodies/{cube}")).ok()["color"],
        "#ff0000"
    );
    let shaded = Png::decode(&s.get("/v1/cameras/eye/image?shadows=false").bytes);
    let c = shaded.at(W / 2, H / 2);
    assert!(c[0] > 0 && c[1] == 0 && c[2] == 0, "a red cube: {c:?}");
}

#[test]
fn renderings_run_while_the_world_is_written() {
    let s = TestServer::with_world(cube_world());
    std::thread::scope(|scope| {
        for _ in 0..3 {
            scope.spawn(|| {
                for _ in 0..10 {
                    let r = s.get("/v1/cameras/eye/image?mode=shaded");
                    assert_eq!(r.status, 200, "{}", r.text);
                }
            });
        }
        scope.spawn(|| {
            for i in 0..20 {
                s.put(
                    &format!("/v1/lights/l{i}"),
                    &json!({"type": "sun", "direction": [0, 0.1 * i as f64, -1], "intensity": 0.1}),
                )
                .ok();
            }
        });
    });
}
