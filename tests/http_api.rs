//! The HTTP API over a real server and a real client: every route, the Euler
//! walk-through of the seeds, every kind of error, and that a refused request changes
//! nothing.

#[path = "support/http.rs"]
mod support;

use serde_json::{Value, json};
use support::{TestServer, check_topology_dump};

fn create(s: &TestServer, body: Value) -> Value {
    let r = s.post("/v1/bodies", &body);
    assert_eq!(r.status, 201, "{}", r.text);
    r.json()
}

fn ids(v: &Value) -> Vec<u64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect()
}

/// The world summary and a body's topology: what must not change on a refusal.
fn state(s: &TestServer, body: u64) -> (Value, Value) {
    (
        s.get("/v1/world").ok(),
        s.get(&format!("/v1/bodies/{body}/topology")).ok(),
    )
}

#[test]
fn health_world_and_spec_answer() {
    let s = TestServer::start();
    let h = s.get("/healthz").ok();
    assert_eq!(h["status"], "ok");
    assert_eq!(h["revision"], 0);
    let w = s.get("/v1/world").ok();
    assert_eq!(
        (w["revision"].as_u64(), w["bodies"].as_u64()),
        (Some(0), Some(0))
    );
    let spec = s.get("/openapi.json").ok();
    assert!(spec["openapi"].as_str().unwrap().starts_with("3.1"));
    s.get("/no/such/route").problem(404);
}

#[test]
fn the_seeds_cube_through_the_euler_operators() {
    let s = TestServer::start();
    let seed = create(
        &s,
        json!({"name": "cube", "shape": {"type": "seminal", "position": [1, 1, -1]}}),
    );
    let b = seed["id"].as_u64().unwrap();
    let (f, v1) = (
        seed["face"].as_u64().unwrap(),
        seed["vertex"].as_u64().unwrap(),
    );
    assert_eq!(
        (
            seed["faces"].as_u64(),
            seed["edges"].as_u64(),
            seed["vertices"].as_u64()
        ),
        (Some(1), Some(0), Some(1))
    );
    let euler = |op: Value| s.post(&format!("/v1/bodies/{b}/euler"), &op).ok();
    let mut rev = seed["revision"].as_u64().unwrap();
    let mut step = |a: &Value| {
        let r = a["revision"].as_u64().unwrap();
        assert_eq!(r, rev + 1, "each write advances the revision by one");
        rev = r;
    };
    let mut wire = vec![v1];
    for p in [[-1, 1, -1], [-1, -1, -1], [1, -1, -1]] {
        let a = euler(json!({"op": "mkev", "face": f, "vertex": wire.last(), "position": p}));
        step(&a);
        wire.push(a["vertex"].as_u64().unwrap());
    }
    let lamina = euler(json!({"op": "mkfe", "v1": wire[0], "face": f, "v2": wire[3]}));
    step(&lamina);
    let top = lamina["face"].as_u64().unwrap();
    let mut tips = vec![];
    for &v in &wire {
        let t = s.get(&format!("/v1/bodies/{b}/topology")).ok();
        let p = t["vertices"]
            .as_array()
            .unwrap()
            .iter()
            .find(|x| x["id"] == v)
            .unwrap()["position"]
            .clone();
        let a =
            euler(json!({"op": "mkev", "face": top, "vertex": v, "position": [p[0], p[1], 1.0]}));
        step(&a);
        tips.push(a["vertex"].as_u64().unwrap());
    }
    for i in 0..4 {
        let a = euler(json!({"op": "mkfe", "v1": tips[i], "face": top, "v2": tips[(i + 1) % 4]}));
        step(&a);
    }
    let body = s.get(&format!("/v1/bodies/{b}")).ok();
    assert_eq!(body["euler"], json!({"F": 6, "E": 12, "V": 8, "H": 0}));
    assert!((body["volume"].as_f64().unwrap() - 8.0).abs() < 1e-12);
    assert_eq!(
        body["bounds"],
        json!({"min": [-1.0, -1.0, -1.0], "max": [1.0, 1.0, 1.0]})
    );
    let t = s.get(&format!("/v1/bodies/{b}/topology")).ok();
    check_topology_dump(&t, 0);
    assert!(
        t["faces"]
            .as_array()
            .unwrap()
            .iter()
            .all(|f| f["vertices"].as_array().unwrap().len() == 4)
    );
    // ESPLIT and its inverse KLEV.
    let e = t["edges"][0]["id"].as_u64().unwrap();
    let split = euler(json!({"op": "esplit", "edge": e}));
    let v = split["vertex"].as_u64().unwrap();
    assert_eq!(split["vertices"], 9);
    let back = euler(json!({"op": "klev", "vertex": v}));
    assert_eq!(
        (back["edges"].as_u64(), back["vertices"].as_u64()),
        (Some(12), Some(8))
    );
    // Move it, then delete it.
    let moved = s
        .post(
            &format!("/v1/bodies/{b}/transform"),
            &json!({"op": "translate", "vector": [0, 0, 5]}),
        )
        .ok();
    assert!(moved["revision"].as_u64().unwrap() > rev);
    let body = s.get(&format!("/v1/bodies/{b}")).ok();
    assert_eq!(body["world_pose"]["position"], json!([0.0, 0.0, 5.0]));
    let gone = s.delete(&format!("/v1/bodies/{b}")).ok();
    assert_eq!(ids(&gone["killed"]), vec![b]);
    s.get(&format!("/v1/bodies/{b}")).problem(404);
}

#[test]
fn bodies_of_every_shape_list_patch_and_delete_with_parts() {
    let s = TestServer::start();
    let shapes = [
        json!({"type": "box", "size": [1, 2, 3]}),
        json!({"type": "tetrahedron", "radius": 1}),
        json!({"type": "prism", "polygon": [[0, 0], [1, 0], [0, 1]], "height": 2}),
        json!({"type": "pyramid", "polygon": [[-1, -1], [1, -1], [1, 1], [-1, 1]], "height": 3}),
        json!({"type": "cylinder", "radius": 1, "height": 2, "segments": 12}),
        json!({"type": "cone", "radius": 1, "height": 2}),
        json!({"type": "sphere", "radius": 1, "segments": 12, "rings": 6}),
        json!({"type": "torus", "major_radius": 2, "minor_radius": 0.5}),
        json!({"type": "polyhedron", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], "faces": [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]}),
        json!({"type": "seminal"}),
    ];
    let mut made = vec![];
    for (i, shape) in shapes.iter().enumerate() {
        let a = create(&s, json!({"name": format!("b{i}"), "shape": shape}));
        made.push(a["id"].as_u64().unwrap());
        let body = s.get(&format!("/v1/bodies/{}", made[i])).ok();
        let e = &body["euler"];
        let chi = e["F"].as_i64().unwrap() - e["E"].as_i64().unwrap() + e["V"].as_i64().unwrap();
        assert_eq!(chi, 2 * (1 - e["H"].as_i64().unwrap()), "{shape}");
        check_topology_dump(
            &s.get(&format!("/v1/bodies/{}/topology", made[i])).ok(),
            e["H"].as_i64().unwrap(),
        );
    }
    let vol = |id: u64| {
        s.get(&format!("/v1/bodies/{id}")).ok()["volume"]
            .as_f64()
            .unwrap()
    };
    assert!((vol(made[0]) - 6.0).abs() < 1e-12);
    assert!((vol(made[2]) - 1.0).abs() < 1e-12);
    assert!((vol(made[3]) - 4.0).abs() < 1e-12);
    assert!((vol(made[8]) - 1.0 / 6.0).abs() < 1e-12);
    // List, filter by name and by parent.
    let all = s.get("/v1/bodies").ok();
    assert_eq!(all["bodies"].as_array().unwrap().len(), shapes.len());
    let one = s.get("/v1/bodies?name=b3").ok();
    assert_eq!(one["bodies"][0]["id"], made[3]);
    // Re-parent b1 under b0, rename it, give it a pose; its world pose composes.
    let (b0, b1) = (made[0], made[1]);
    s.patch(
        &format!("/v1/bodies/{b0}"),
        &json!({"pose": {"position": [10, 0, 0]}}),
    )
    .ok();
    s.patch(
        &format!("/v1/bodies/{b1}"),
        &json!({"parent": b0, "name": "child", "pose": {"position": [0, 1, 0]}}),
    )
    .ok();
    let child = s.get(&format!("/v1/bodies/{b1}")).ok();
    assert_eq!(child["name"], "child");
    assert_eq!(child["parent"], b0);
    assert_eq!(child["world_pose"]["position"], json!([10.0, 1.0, 0.0]));
    let kids = s.get(&format!("/v1/bodies?parent={b0}")).ok();
    assert_eq!(kids["bodies"].as_array().unwrap().len(), 1);
    // Moving the parent moves the child.
    s.post(
        &format!("/v1/bodies/{b0}/transform"),
        &json!({"op": "rotate", "axis": [0, 0, 1], "angle_deg": 90}),
    )
    .ok();
    let p = s.get(&format!("/v1/bodies/{b1}")).ok()["world_pose"]["position"].clone();
    assert!(
        (p[0].as_f64().unwrap() + 1.0).abs() < 1e-9 && (p[1].as_f64().unwrap() - 10.0).abs() < 1e-9,
        "{p}"
    );
    // Deleting the parent deletes the child.
    let gone = s.delete(&format!("/v1/bodies/{b0}")).ok();
    let mut killed = ids(&gone["killed"]);
    killed.sort();
    assert_eq!(killed, vec![b0, b1]);
    s.get(&format!("/v1/bodies/{b1}")).problem(404);
}

#[test]
fn sweeps_dual_evert_and_copy() {
    let s = TestServer::start();
    let b = create(&s, json!({"shape": {"type": "box", "size": [2, 2, 2]}}))["id"]
        .as_u64()
        .unwrap();
    let top = |s: &TestServer| {
        let t = s.get(&format!("/v1/bodies/{b}/topology")).ok();
        t["faces"]
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f["plane"][2].as_f64().unwrap() > 0.9)
            .unwrap()["id"]
            .as_u64()
            .unwrap()
    };
    let a = s
        .post(
            &format!("/v1/bodies/{b}/sweep"),
            &json!({"face": top(&s), "kind": "prism", "distance": 1}),
        )
        .ok();
    assert_eq!(
        (
            a["faces"].as_u64(),
            a["edges"].as_u64(),
            a["vertices"].as_u64()
        ),
        (Some(10), Some(20), Some(12))
    );
    let vol = |s: &TestServer| {
        s.get(&format!("/v1/bodies/{b}")).ok()["volume"]
            .as_f64()
            .unwrap()
    };
    assert!((vol(&s) - 12.0).abs() < 1e-9);
    let a = s
        .post(
            &format!("/v1/bodies/{b}/sweep"),
            &json!({"face": top(&s), "kind": "pyramid", "distance": 3}),
        )
        .ok();
    assert_eq!(a["faces"], 13);
    assert!((vol(&s) - 16.0).abs() < 1e-9);
    let a = s.post(&format!("/v1/bodies/{b}/evert"), &json!({})).ok();
    assert_eq!(a["id"], b);
    assert!((vol(&s) + 16.0).abs() < 1e-9);
    s.post(&format!("/v1/bodies/{b}/evert"), &json!({})).ok();
    let c = s.post(&format!("/v1/bodies/{b}/copy"), &json!({"name": "twin"}));
    assert_eq!(c.status, 201, "{}", c.text);
    let twin = c.json()["id"].as_u64().unwrap();
    assert_ne!(twin, b);
    assert!(
        (s.get(&format!("/v1/bodies/{twin}")).ok()["volume"]
            .as_f64()
            .unwrap()
            - 16.0)
            .abs()
            < 1e-9
    );
    let cube = create(&s, json!({"shape": {"type": "box", "size": [2, 2, 2]}}))["id"]
        .as_u64()
        .unwrap();
    let d = s.post(&format!("/v1/bodies/{cube}/dual"), &json!({})).ok();
    assert_eq!(
        (
            d["faces"].as_u64(),
            d["edges"].as_u64(),
            d["vertices"].as_u64()
        ),
        (Some(8), Some(12), Some(6))
    );
}

#[test]
fn glue_across_bodies_and_unglue() {
    let s = TestServer::start();
    let a = create(&s, json!({"shape": {"type": "box", "size": [2, 2, 2]}}))["id"]
        .as_u64()
        .unwrap();
    let b = create(
        &s,
        json!({"shape": {"type": "box", "size": [2, 2, 2]}, "pose": {"position": [0, 0, 2]}}),
    )["id"]
        .as_u64()
        .unwrap();
    let face_with = |id: u64, z: f64| {
        let t = s.get(&format!("/v1/bodies/{id}/topology")).ok();
        t["faces"]
            .as_array()
            .unwrap()
            .iter()
            .find(|f| (f["plane"][2].as_f64().unwrap() - z).abs() < 1e-9)
            .unwrap()
            .clone()
    };
    let (fa, fb) = (face_with(a, 1.0), face_with(b, -1.0));
    let glued = s
        .post(
            &format!("/v1/bodies/{a}/euler"),
            &json!({"op": "glue", "face1": fa["id"], "face2": fb["id"]}),
        )
        .ok();
    assert_eq!(
        (
            glued["faces"].as_u64(),
            glued["edges"].as_u64(),
            glued["vertices"].as_u64()
        ),
        (Some(10), Some(20), Some(12))
    );
    s.get(&format!("/v1/bodies/{b}")).problem(404);
    assert_eq!(
        ids(&glued["killed"]),
        vec![b],
        "the absorbed body is reported killed"
    );
    let body = s.get(&format!("/v1/bodies/{a}")).ok();
    assert!((body["volume"].as_f64().unwrap() - 16.0).abs() < 1e-9);
    // The seam: the edges of the old top face, now shared by the two halves.
    let t = s.get(&format!("/v1/bodies/{a}/topology")).ok();
    let at_z1: Vec<u64> = t["vertices"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|v| (v["position"][2].as_f64().unwrap() - 1.0).abs() < 1e-9)
        .map(|v| v["id"].as_u64().unwrap())
        .collect();
    let seam: Vec<u64> = t["edges"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| {
            at_z1.contains(&e["nvt"].as_u64().unwrap())
                && at_z1.contains(&e["pvt"].as_u64().unwrap())
        })
        .map(|e| e["id"].as_u64().unwrap())
        .collect();
    assert_eq!(seam.len(), 4);
    let cut = s
        .post(
            &format!("/v1/bodies/{a}/euler"),
            &json!({"op": "unglue", "edges": seam}),
        )
        .ok();
    let split = cut["split_off"]
        .as_u64()
        .expect("the seam separates the halves");
    for id in [a, split] {
        let e = &s.get(&format!("/v1/bodies/{id}")).ok()["euler"];
        assert_eq!(*e, json!({"F": 6, "E": 12, "V": 8, "H": 0}));
    }
}

#[test]
fn cameras_and_lights() {
    let s = TestServer::start();
    let cam = json!({"look_at": {"eye": [3, 0, 1], "target": [0, 0, 1]}, "intrinsics": {"width": 640, "height": 480, "fx": 500, "fy": 500, "cx": 320, "cy": 240}});
    s.put("/v1/cameras/eye", &cam).ok();
    let c = s.get("/v1/cameras/eye").ok();
    let d = &c["view_direction"];
    assert!(
        (d[0].as_f64().unwrap() + 1.0).abs() < 1e-12,
        "looks along -x toward the target: {d}"
    );
    assert_eq!(c["intrinsics"]["width"], 640);
    let bg = json!({"pose": {"position": [0, 0, 2]}, "baumgart": {"focal": 12.5, "ldx": 512, "ldy": 480, "pdx": 12.8, "pdy": 9.6}});
    s.put("/v1/cameras/tv", &bg).ok();
    assert_eq!(
        s.get("/v1/cameras").ok()["cameras"]
            .as_array()
            .unwrap()
            .len(),
        2
    );
    // Bad cameras: both placements, zero focal length, a non-unit rotation.
    let both = json!({"pose": {"position": [0, 0, 0]}, "look_at": {"eye": [1, 0, 0], "target": [0, 0, 0]}, "intrinsics": {"width": 1, "height": 1, "fx": 1, "fy": 1, "cx": 0, "cy": 0}});
    s.put("/v1/cameras/bad", &both).problem(422);
    let zero_f = json!({"pose": {}, "intrinsics": {"width": 640, "height": 480, "fx": 0, "fy": 500, "cx": 320, "cy": 240}});
    s.put("/v1/cameras/bad", &zero_f).problem(422);
    let zero_w = json!({"pose": {}, "intrinsics": {"width": 0, "height": 480, "fx": 5, "fy": 500, "cx": 320, "cy": 240}});
    s.put("/v1/cameras/bad", &zero_w).problem(422);
    s.get("/v1/cameras/bad").problem(404);
    s.get("/v1/cameras/%FF").problem(400);
    s.delete("/v1/cameras/tv").ok();
    s.get("/v1/cameras/tv").problem(404);
    s.delete("/v1/cameras/tv").problem(404);
    s.put(
        "/v1/lights/sun",
        &json!({"type": "sun", "direction": [0, 0, -2]}),
    )
    .ok();
    let l = s.get("/v1/lights/sun").ok();
    assert_eq!(l["direction"], json!([0.0, 0.0, -1.0]));
    s.put(
        "/v1/lights/lamp",
        &json!({"type": "point", "position": [0, 0, 3], "intensity": 0.5}),
    )
    .ok();
    assert_eq!(
        s.get("/v1/lights").ok()["lights"].as_array().unwrap().len(),
        2
    );
    s.put(
        "/v1/lights/dark",
        &json!({"type": "sun", "direction": [0, 0, 0]}),
    )
    .problem(422);
    s.delete("/v1/lights/lamp").ok();
    s.get("/v1/lights/lamp").problem(404);
}

#[test]
fn bad_input_gets_a_problem_and_changes_nothing() {
    let s = TestServer::start();
    let b = create(
        &s,
        json!({"name": "cube", "shape": {"type": "box", "size": [2, 2, 2]}}),
    )["id"]
        .as_u64()
        .unwrap();
    let before = state(&s, b);
    let t = &before.1;
    let (e, v, f) = (
        t["edges"][0]["id"].as_u64().unwrap(),
        t["vertices"][0]["id"].as_u64().unwrap(),
        t["faces"][0]["id"].as_u64().unwrap(),
    );
    let euler = format!("/v1/bodies/{b}/euler");
    // Malformed JSON, wrong types, unknown fields and operators: 400.
    s.post_raw(&euler, "application/json", b"{\"op\": \"klev\", ")
        .problem(400);
    s.post(&euler, &json!({"op": "klev", "vertex": "seven"}))
        .problem(400);
    s.post(&euler, &json!({"op": "klev", "vertex": v, "extra": 1}))
        .problem(400);
    s.post(&euler, &json!({"op": "frobnicate"})).problem(400);
    s.post("/v1/bodies", &json!({"shape": {"type": "box"}}))
        .problem(400);
    s.get("/v1/bodies/not-a-number").problem(400);
    // Refused before its body is read: the client is told not to reuse the connection.
    let unread = s.post_raw(&euler, "text/plain", b"{}");
    assert_eq!(unread.header("connection"), "close");
    unread.problem(415);
    // NaN and infinity cannot be written in JSON; out-of-range numbers are refused.
    s.post_raw(
        &euler,
        "application/json",
        b"{\"op\":\"esplit\",\"edge\":1,\"position\":[NaN,0,0]}",
    )
    .problem(400);
    s.post_raw(
        &euler,
        "application/json",
        format!("{{\"op\":\"esplit\",\"edge\":{e},\"position\":[1e999,0,0]}}").as_bytes(),
    )
    .problem(400);
    s.post_raw(
        &format!("/v1/bodies/{b}/transform"),
        "application/json",
        b"{\"op\":\"translate\",\"vector\":[1e400,0,0]}",
    )
    .problem(400);
    // Unknown ids: 404.
    s.get("/v1/bodies/999999/topology").problem(404);
    s.post(
        "/v1/bodies/999999/euler",
        &json!({"op": "klev", "vertex": v}),
    )
    .problem(404);
    s.post(&euler, &json!({"op": "klev", "vertex": 999999}))
        .problem(404);
    s.post(&euler, &json!({"op": "klfe", "edge": v}))
        .problem(404);
    s.patch("/v1/bodies/999999", &json!({"name": "x"}))
        .problem(404);
    s.delete("/v1/bodies/999999").problem(404);
    s.post(
        "/v1/bodies",
        &json!({"parent": 999999, "shape": {"type": "box", "size": [1, 1, 1]}}),
    )
    .problem(404);
    // Refused Euler operators: 422 with the reason.
    let p = s
        .post(&euler, &json!({"op": "klev", "vertex": v}))
        .problem(422);
    assert!(p["detail"].as_str().unwrap().contains("3 edges"), "{p}");
    s.post(&euler, &json!({"op": "mkfe", "v1": v, "face": f, "v2": v}))
        .problem(422);
    let off: u64 = t["faces"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| !x["vertices"].as_array().unwrap().iter().any(|y| y == v))
        .unwrap()["id"]
        .as_u64()
        .unwrap();
    s.post(&euler, &json!({"op": "mkev", "face": off, "vertex": v}))
        .problem(422);
    s.post(&euler, &json!({"op": "glue", "face1": f, "face2": f}))
        .problem(422);
    s.post(&euler, &json!({"op": "unglue", "edges": [e]}))
        .problem(422);
    // Bad solids and transforms: 422; a duplicate name: 409; a cycle in the parts tree: 422.
    s.post(
        "/v1/bodies",
        &json!({"shape": {"type": "box", "size": [1, -1, 1]}}),
    )
    .problem(422);
    s.post("/v1/bodies", &json!({"shape": {"type": "polyhedron", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "faces": [[0, 1, 2]]}})).problem(422);
    s.post(
        "/v1/bodies",
        &json!({"shape": {"type": "sphere", "radius": 1, "segments": 2}}),
    )
    .problem(422);
    s.post(
        "/v1/bodies",
        &json!({"name": "cube", "shape": {"type": "box", "size": [1, 1, 1]}}),
    )
    .problem(409);
    s.patch(&format!("/v1/bodies/{b}"), &json!({"parent": b}))
        .problem(422);
    s.post(
        &format!("/v1/bodies/{b}/transform"),
        &json!({"op": "dilate", "factor": 0}),
    )
    .problem(422);
    s.post(
        &format!("/v1/bodies/{b}/transform"),
        &json!({"op": "rotate", "axis": [0, 0, 0], "angle_deg": 10}),
    )
    .problem(422);
    s.post(
        &format!("/v1/bodies/{b}/transform"),
        &json!({"op": "translate", "vector": [1, 0, 0], "target": 999999}),
    )
    .problem(404);
    s.post(
        &format!("/v1/bodies/{b}/sweep"),
        &json!({"face": f, "kind": "prism", "distance": -1}),
    )
    .problem(422);
    // Oversized bodies: a sphere of too many faces, and a request body over the limit.
    s.post(
        "/v1/bodies",
        &json!({"shape": {"type": "sphere", "radius": 1, "segments": 100000, "rings": 100000}}),
    )
    .problem(413);
    let huge = vec![b' '; winged::server::api::MAX_REQUEST_BYTES + 1];
    s.post_raw("/v1/bodies", "application/json", &huge)
        .problem(413);
    // Nothing changed.
    assert_eq!(state(&s, b), before);
    // And the server still works.
    s.post(&euler, &json!({"op": "esplit", "edge": e})).ok();
}

#[test]
fn a_body_a_route_ignores_does_not_cost_the_connection() {
    // EVERT, DUAL and DELETE take no body; one sent anyway is read and dropped, so the
    // kept-alive connection carries the next request.
    let s = TestServer::start();
    let b = s
        .post(
            "/v1/bodies",
            &json!({"shape": {"type": "box", "size": [1, 1, 1]}}),
        )
        .ok()["id"]
        .as_u64()
        .expect("an id");
    for _ in 0..300 {
        s.post(&format!("/v1/bodies/{b}/evert"), &json!({"ignored": true}))
            .ok();
        s.get("/v1/world").ok();
    }
}
