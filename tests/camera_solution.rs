//! Camera solution over real HTTP: a camera stored in the world sees the model's vertices;
//! their pixels (some replaced by wrong matches) and ids give the camera back, by
//! vertex id and by world point, with intrinsics inline or from a stored camera, and
//! `store_as` stores it. Bad requests get problem+json and leave the world unchanged.

#[path = "support/http.rs"]
mod support;

use glam::{DMat3, DQuat, DVec2, DVec3};
use serde_json::{Value, json};
use support::{Rng, TestServer};
use winged::model::solids::mkcube;
use winged::model::{BodyId, Camera, Intrinsics, Pose, Serial, World};

/// A scene: boxes of different sizes scattered over a table-sized area, and the camera
/// `truth` looking at them from 3 m.
struct Scene {
    world: World,
    truth: Camera,
    /// Every vertex the truth camera sees in its image: (id, world locus, pixel).
    seen: Vec<(u64, DVec3, DVec2)>,
}

fn scene() -> Scene {
    let mut world = World::new();
    let root = world.root();
    let boxes = [
        ([0.0, 0.0, 0.25], [0.5, 0.5, 0.5], 0.0),
        ([0.8, 0.3, 0.15], [0.3, 0.6, 0.3], 0.4),
        ([-0.7, 0.5, 0.4], [0.4, 0.4, 0.8], -0.3),
        ([0.3, -0.8, 0.1], [0.7, 0.2, 0.2], 1.1),
        ([-0.5, -0.6, 0.3], [0.2, 0.2, 0.6], 0.2),
    ];
    let mut ids: Vec<BodyId> = Vec::new();
    for (k, (at, size, turn)) in boxes.iter().enumerate() {
        let pose = Pose {
            position: DVec3::from_array(*at),
            rotation: DQuat::from_rotation_z(*turn),
        };
        let id = world
            .insert_with(Some(&format!("box{k}")), root, pose, |s| {
                mkcube(s, size[0], size[1], size[2])
            })
            .expect("a box");
        ids.push(id);
    }
    let intrinsics = Intrinsics::new(640, 480, 600.0, 600.0, 321.5, 238.0).expect("intrinsics");
    let truth = Camera::look_at(
        DVec3::new(2.2, -1.6, 1.5),
        DVec3::new(0.0, 0.0, 0.2),
        DVec3::Z,
        intrinsics,
    )
    .expect("a camera");
    world.set_camera("truth", truth).expect("stored");
    let mut seen = Vec::new();
    for id in ids {
        let body = world.body(id).expect("the box");
        let serials: Vec<Serial> = body.vertices().map(|v| body.vertex_serial(v)).collect();
        for (s, found) in serials.iter().zip(world.find_vertices(&serials)) {
            let (_, _, p) = found.expect("a live vertex");
            let px = truth.project(p).expect("in front");
            if (0.0..640.0).contains(&px.x) && (0.0..480.0).contains(&px.y) {
                seen.push((s.get(), p, px));
            }
        }
    }
    assert!(seen.len() >= 30, "the camera sees {} vertices", seen.len());
    Scene { world, truth, seen }
}

fn intrinsics_json(k: &Intrinsics) -> Value {
    json!({"width": k.width, "height": k.height, "fx": k.fx, "fy": k.fy, "cx": k.cx, "cy": k.cy})
}

fn vec3(v: &Value) -> DVec3 {
    DVec3::new(
        v[0].as_f64().expect("x"),
        v[1].as_f64().expect("y"),
        v[2].as_f64().expect("z"),
    )
}

/// The answered camera: its position and its rotation as a quaternion.
fn answered_pose(a: &Value) -> (DVec3, DQuat) {
    let p = &a["camera"]["pose"];
    let q = &p["rotation"];
    (
        vec3(&p["position"]),
        DQuat::from_xyzw(
            q[0].as_f64().expect("qx"),
            q[1].as_f64().expect("qy"),
            q[2].as_f64().expect("qz"),
            q[3].as_f64().expect("qw"),
        ),
    )
}

/// Rotation error (degrees) and position error (meters) of an answer against `truth`.
fn errors(a: &Value, truth: &Camera) -> (f64, f64) {
    let (position, rotation) = answered_pose(a);
    let angle = rotation.angle_between(truth.pose.rotation).to_degrees();
    (angle, position.distance(truth.pose.position))
}

fn revision(s: &TestServer) -> u64 {
    s.get("/v1/world").ok()["revision"]
        .as_u64()
        .expect("a revision")
}

#[test]
fn vertices_and_points_seen_by_a_camera_give_it_back_despite_wrong_matches() {
    let sc = scene();
    let s = TestServer::with_world(sc.world);
    let mut rng = Rng(7);
    // Every third correspondence is a wrong match: a random pixel.
    let mut wrong = Vec::new();
    let correspondences: Vec<Value> = sc
        .seen
        .iter()
        .enumerate()
        .map(|(i, (id, p, px))| {
            let pixel = if i % 3 == 1 {
                wrong.push(i);
                [rng.uniform() * 640.0, rng.uniform() * 480.0]
            } else {
                px.to_array()
            };
            // Half by vertex id, half by world point.
            if i % 2 == 0 {
                json!({"pixel": pixel, "vertex": id})
            } else {
                json!({"pixel": pixel, "point": p.to_array()})
            }
        })
        .collect();
    let before = revision(&s);
    let a = s
        .post(
            "/v1/camera-solution",
            &json!({
                "intrinsics": intrinsics_json(&sc.truth.intrinsics),
                "correspondences": correspondences,
            }),
        )
        .ok();
    let (angle, offset) = errors(&a, &sc.truth);
    assert!(angle < 1e-6 && offset < 1e-6, "{angle}° {offset} m: {a}");
    assert!(a["rms_px"].as_f64().expect("rms") < 1e-6, "{a}");
    // The inliers are exactly the right matches (a random pixel may fall within the
    // default 8 px of where its point is seen, by chance; the seed above gives none).
    let inliers: Vec<usize> = a["inliers"]
        .as_array()
        .expect("inliers")
        .iter()
        .map(|i| i.as_u64().expect("an index") as usize)
        .collect();
    let right: Vec<usize> = (0..sc.seen.len()).filter(|i| !wrong.contains(i)).collect();
    assert_eq!(inliers, right, "{a}");
    assert_eq!(a["correspondences"], sc.seen.len());
    // With wrong matches among them, RANSAC ran.
    assert!(a["iterations"]["ransac"].as_u64().expect("ransac") >= 1);
    assert_eq!(
        a["camera"]["intrinsics"],
        intrinsics_json(&sc.truth.intrinsics)
    );
    // OpenCV's extrinsics and camera matrix.
    let (r, t) = sc.truth.to_opencv();
    let rvec = vec3(&a["opencv"]["rvec"]);
    let turned = DMat3::from_axis_angle(rvec.normalize(), rvec.length());
    assert!(
        (turned - r).to_cols_array().iter().all(|d| d.abs() < 1e-6),
        "{a}"
    );
    assert!(vec3(&a["opencv"]["tvec"]).distance(t) < 1e-6, "{a}");
    assert_eq!(
        a["opencv"]["camera_matrix"],
        json!([[600.0, 0.0, 321.0], [0.0, 600.0, 237.5], [0.0, 0.0, 1.0]])
    );
    assert_eq!(a["revision"], before);
    assert!(a.get("stored_as").is_none());
    assert_eq!(revision(&s), before, "solving alone writes nothing");
}

#[test]
fn intrinsics_of_a_stored_camera_and_store_as() {
    let sc = scene();
    let s = TestServer::with_world(sc.world);
    let mut rng = Rng(11);
    // Half a pixel of noise on every pixel.
    let correspondences: Vec<Value> = sc
        .seen
        .iter()
        .map(|(id, _, px)| {
            let noisy = *px + 0.5 * DVec2::new(rng.normal(), rng.normal());
            json!({"pixel": noisy.to_array(), "vertex": id})
        })
        .collect();
    let before = revision(&s);
    let a = s
        .post(
            "/v1/camera-solution",
            &json!({
                "intrinsics": "truth",
                "correspondences": correspondences,
                "store_as": "solved",
                "threshold_px": 3.0,
                "seed": 42,
            }),
        )
        .ok();
    let (angle, offset) = errors(&a, &sc.truth);
    assert!(angle < 0.2 && offset < 0.01, "{angle}° {offset} m: {a}");
    let rms = a["rms_px"].as_f64().expect("rms");
    assert!(rms > 0.2 && rms < 1.0, "rms {rms} px for σ = 0.5 px");
    assert_eq!(
        a["inliers"].as_array().expect("inliers").len(),
        sc.seen.len()
    );
    // Every correspondence fits the global solve of all of them: RANSAC was not needed.
    assert_eq!(a["iterations"]["ransac"], 0, "{a}");
    assert_eq!(a["confident"], true);
    assert_eq!(a["stored_as"], "solved");
    assert_eq!(a["revision"], before + 1);
    assert_eq!(
        a["camera"]["intrinsics"],
        intrinsics_json(&sc.truth.intrinsics)
    );
    // The stored camera is the answered one.
    let stored = s.get("/v1/cameras/solved").ok();
    assert_eq!(stored["pose"], a["camera"]["pose"]);
    assert_eq!(stored["intrinsics"], a["camera"]["intrinsics"]);
    assert_eq!(revision(&s), before + 1);
    // The same request (same seed) gives the same camera.
    let again = s
        .post(
            "/v1/camera-solution",
            &json!({
                "intrinsics": "solved",
                "correspondences": correspondences,
                "threshold_px": 3.0,
                "seed": 42,
            }),
        )
        .ok();
    assert_eq!(again["camera"], a["camera"]);
}

#[test]
fn bad_requests_get_problems_and_change_nothing() {
    let sc = scene();
    let k = intrinsics_json(&sc.truth.intrinsics);
    let good: Vec<Value> = sc
        .seen
        .iter()
        .map(|(id, _, px)| json!({"pixel": px.to_array(), "vertex": id}))
        .collect();
    let face = {
        let (id, body) = sc.world.bodies().next().expect("a body");
        let _ = id;
        let f = body.body.faces().next().expect("a face");
        body.body.face_serial(f).get()
    };
    let s = TestServer::with_world(sc.world);
    let before = revision(&s);
    let line: Vec<Value> = (0..10)
        .map(|i| {
            let x = i as f64 * 0.1;
            json!({"pixel": [100.0 + 20.0 * i as f64, 200.0 + 3.0 * i as f64], "point": [x, 2.0 * x, 0.5]})
        })
        .collect();
    let mut rng = Rng(3);
    let random: Vec<Value> = sc
        .seen
        .iter()
        .map(|(id, _, _)| {
            json!({"pixel": [rng.uniform() * 640.0, rng.uniform() * 480.0], "vertex": id})
        })
        .collect();
    let many: Vec<Value> = (0..20_001)
        .map(|i| json!({"pixel": [1.0, 2.0], "point": [i as f64, 0.0, 1.0]}))
        .collect();
    // Eight good correspondences and one more.
    let plus = |extra: Value| {
        let mut list = good[..8].to_vec();
        list.push(extra);
        list
    };
    let with = |extra: Value| {
        let mut body = json!({"intrinsics": k, "correspondences": good});
        for (key, v) in extra.as_object().expect("an object") {
            body[key] = v.clone();
        }
        body
    };
    let cases: Vec<(&str, Value, u16, &str)> = vec![
        (
            "three correspondences",
            with(json!({"correspondences": good[..3]})),
            422,
            "too-few-correspondences",
        ),
        (
            "no correspondences",
            with(json!({"correspondences": []})),
            422,
            "too-few-correspondences",
        ),
        (
            "points on a line",
            with(json!({"correspondences": line})),
            422,
            "degenerate-correspondences",
        ),
        (
            "an unknown vertex",
            with(
                json!({"correspondences": plus(json!({"pixel": [1, 2], "vertex": 987_654_321u64}))}),
            ),
            422,
            "unknown-vertex",
        ),
        (
            "a face id for a vertex",
            with(json!({"correspondences": plus(json!({"pixel": [1, 2], "vertex": face}))})),
            422,
            "unknown-vertex",
        ),
        (
            "only wrong matches",
            with(json!({"correspondences": random})),
            422,
            "no-consensus",
        ),
        (
            "too many correspondences",
            with(json!({"correspondences": many})),
            422,
            "too-many-correspondences",
        ),
        (
            "negative focal length",
            with(
                json!({"intrinsics": {"width": 640, "height": 480, "fx": -600.0, "fy": 600.0, "cx": 320.0, "cy": 240.0}}),
            ),
            422,
            "invalid-intrinsics",
        ),
        (
            "zero threshold",
            with(json!({"threshold_px": 0.0})),
            422,
            "invalid-parameter",
        ),
        (
            "confidence of 1.5",
            with(json!({"confidence": 1.5})),
            422,
            "invalid-parameter",
        ),
        (
            "no iterations",
            with(json!({"max_iterations": 0})),
            422,
            "invalid-parameter",
        ),
        (
            "two inliers",
            with(json!({"min_inliers": 2})),
            422,
            "invalid-parameter",
        ),
        (
            "an unknown camera",
            with(json!({"intrinsics": "nobody"})),
            404,
            "not-found",
        ),
        (
            "neither vertex nor point",
            with(json!({"correspondences": plus(json!({"pixel": [1, 2]}))})),
            400,
            "bad-request",
        ),
        (
            "both vertex and point",
            with(
                json!({"correspondences": plus(json!({"pixel": [1, 2], "vertex": 5, "point": [0, 0, 0]}))}),
            ),
            400,
            "bad-request",
        ),
        (
            "an empty name to store as",
            with(json!({"store_as": ""})),
            422,
            "invalid-name",
        ),
        (
            "an unknown field",
            with(json!({"focal": 3})),
            400,
            "bad-request",
        ),
        (
            "a pixel of three numbers",
            with(json!({"correspondences": plus(json!({"pixel": [1, 2, 3], "point": [0, 0, 0]}))})),
            400,
            "bad-request",
        ),
        (
            "no intrinsics",
            json!({"correspondences": good}),
            400,
            "bad-request",
        ),
    ];
    for (what, body, status, kind) in cases {
        let p = s.post("/v1/camera-solution", &body).problem(status);
        assert_eq!(
            p["type"],
            format!("urn:winged:problem:{kind}"),
            "{what}: {p}"
        );
        if kind == "unknown-vertex" {
            let id = if what.contains("face") {
                face
            } else {
                987_654_321
            };
            assert!(
                p["detail"]
                    .as_str()
                    .expect("detail")
                    .contains(&id.to_string()),
                "{p}"
            );
        }
    }
    // Numbers JSON cannot carry: NaN, infinities, overflow.
    for number in ["NaN", "Infinity", "-inf", "1e400"] {
        let text = format!(
            r#"{{"intrinsics": "truth", "correspondences": [{{"pixel": [{number}, 1], "point": [0, 0, 1]}}]}}"#
        );
        s.post_raw("/v1/camera-solution", "application/json", text.as_bytes())
            .problem(400);
    }
    s.post_raw("/v1/camera-solution", "application/json", b"{")
        .problem(400);
    assert_eq!(revision(&s), before, "refused requests write nothing");
    assert!(s.get("/v1/cameras/solved").status == 404);
    // The server still solves.
    s.post("/v1/camera-solution", &with(json!({}))).ok();
}

#[test]
fn the_focal_length_is_solved_when_asked_and_refused_when_the_view_cannot_fix_it() {
    let sc = scene();
    let s = TestServer::with_world(sc.world);
    let k = &sc.truth.intrinsics;
    // The intrinsics' focal lengths are wrong on purpose: only their centre and aspect
    // are used.
    let guess = json!({"width": k.width, "height": k.height, "fx": 900.0, "fy": 900.0, "cx": k.cx, "cy": k.cy});
    let correspondences: Vec<Value> = sc
        .seen
        .iter()
        .map(|(id, _, px)| json!({"pixel": px.to_array(), "vertex": id}))
        .collect();
    let a = s
        .post(
            "/v1/camera-solution",
            &json!({"intrinsics": guess, "correspondences": correspondences, "solve_focal": true}),
        )
        .ok();
    let (angle, offset) = errors(&a, &sc.truth);
    assert!(angle < 1e-6 && offset < 1e-6, "{angle}° {offset} m: {a}");
    for key in ["fx", "fy"] {
        let got = a["focal"][key].as_f64().expect("a focal length");
        assert!((got - 600.0).abs() < 1e-6, "{key} {got}: {a}");
        assert_eq!(a["camera"]["intrinsics"][key], a["focal"][key]);
    }
    assert!(
        a["focal"]["fx_std"].as_f64().expect("a spread") < 30.0,
        "{a}"
    );
    assert_eq!(a["camera"]["intrinsics"]["cx"], k.cx);
    // Without solve_focal the answer has no focal field.
    let plain = s
        .post(
            "/v1/camera-solution",
            &json!({"intrinsics": "truth", "correspondences": correspondences}),
        )
        .ok();
    assert!(plain.get("focal").is_none(), "{plain}");

    // A plane seen face-on: the focal length trades for the distance.
    let before = revision(&s);
    let cam = &sc.truth;
    let mut rng = Rng(5);
    let face_on: Vec<Value> = (0..30)
        .map(|n| {
            let (a, b) = ((n % 6) as f64 * 0.2 - 0.5, (n / 6) as f64 * 0.2 - 0.4);
            let p = cam.pose.position + 3.0 * cam.view_direction() + a * cam.i() + b * cam.j();
            let px =
                cam.project(p).expect("in front") + 0.3 * DVec2::new(rng.normal(), rng.normal());
            json!({"pixel": px.to_array(), "point": p.to_array()})
        })
        .collect();
    let p = s
        .post(
            "/v1/camera-solution",
            &json!({"intrinsics": guess, "correspondences": face_on, "solve_focal": true, "store_as": "x"}),
        )
        .problem(422);
    assert_eq!(
        p["type"], "urn:winged:problem:degenerate-correspondences",
        "{p}"
    );
    assert!(
        p["detail"]
            .as_str()
            .expect("detail")
            .contains("focal length"),
        "{p}"
    );
    assert_eq!(revision(&s), before);
    // The same points with the focal length known are a fine camera.
    s.post(
        "/v1/camera-solution",
        &json!({"intrinsics": "truth", "correspondences": face_on}),
    )
    .ok();
}
