//! `POST /v1/bodies/{id}/boolean` over real HTTP: holes, unions, empty results and kept
//! operands; every refusal (unknown ids, a body with itself or its own parts, open and
//! self-intersecting bodies) answered as a problem with the world unchanged; the result
//! surviving a restart through the journal, which keeps its polygons.
//!
//! The refusals of ids, of a body with itself and of its parts are made before the
//! kernel runs; the other tests need the kernel (`model::boolean::boolean`).

#[path = "support/http.rs"]
mod support;

#[path = "support/process.rs"]
mod process;

use std::f64::consts::PI;
use std::time::Duration;

use serde_json::{Value, json};
use support::TestServer;

/// Makes a body of `shape` at `position` (under `parent`, if given); its id.
fn make(s: &TestServer, shape: Value, position: [f64; 3], parent: Option<u64>) -> u64 {
    let mut req = json!({"shape": shape, "pose": {"position": position}});
    if let Some(p) = parent {
        req["parent"] = json!(p);
    }
    let v = s.post("/v1/bodies", &req).ok();
    v["id"].as_u64().expect("an id")
}

fn cube(side: f64) -> Value {
    json!({"type": "box", "size": [side, side, side]})
}

fn boolean(s: &TestServer, b1: u64, req: Value) -> support::Reply {
    s.post(&format!("/v1/bodies/{b1}/boolean"), &req)
}

/// The world as a client sees it: its summary and every body.
fn world(s: &TestServer) -> (Value, Value) {
    (s.get("/v1/world").ok(), s.get("/v1/bodies").ok())
}

/// Asserts that `req` on `b1` is refused with `status` (and `kind`, if given) and that
/// the world is as it was; the problem.
fn refused(s: &TestServer, b1: u64, req: Value, status: u16, kind: Option<&str>) -> Value {
    let before = world(s);
    let p = boolean(s, b1, req.clone()).problem(status);
    if let Some(kind) = kind {
        assert_eq!(
            p["type"],
            format!("urn:winged:problem:{kind}"),
            "{req}: {p}"
        );
    }
    assert_eq!(world(s), before, "{req} changed the world");
    p
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1.0)
}

// ----- refusals made before the kernel runs ------------------------------------------

#[test]
fn unknown_ids_are_not_found_and_change_nothing() {
    let s = TestServer::start();
    let a = make(&s, cube(2.0), [0.0; 3], None);
    let b = make(&s, cube(2.0), [1.0, 0.0, 0.0], None);
    let p = refused(
        &s,
        a,
        json!({"op": "union", "with": 999_999}),
        404,
        Some("not-found"),
    );
    assert!(p["detail"].as_str().unwrap().contains("999999"), "{p}");
    refused(
        &s,
        999_999,
        json!({"op": "union", "with": b}),
        404,
        Some("not-found"),
    );
    // A face's id is not a body's.
    let face = s.get(&format!("/v1/bodies/{a}/topology")).ok()["faces"][0]["id"]
        .as_u64()
        .expect("a face");
    refused(
        &s,
        a,
        json!({"op": "difference", "with": face}),
        404,
        Some("not-found"),
    );
}

#[test]
fn a_body_with_itself_or_its_own_parts_is_refused() {
    let s = TestServer::start();
    let a = make(&s, cube(2.0), [0.0; 3], None);
    let part = make(&s, cube(1.0), [0.0; 3], Some(a));
    let grandpart = make(&s, cube(0.5), [0.0; 3], Some(part));
    for (b1, b2) in [(a, a), (a, part), (part, a), (a, grandpart), (grandpart, a)] {
        for op in ["intersection", "union", "difference"] {
            let p = refused(
                &s,
                b1,
                json!({"op": op, "with": b2, "keep_with": true}),
                422,
                Some("boolean-refused"),
            );
            let detail = p["detail"].as_str().expect("a detail");
            assert!(
                detail.contains("itself or with one of its own parts"),
                "{b1} {op} {b2}: {detail}"
            );
        }
    }
    // The world body is no operand either.
    refused(&s, 1, json!({"op": "union", "with": a}), 422, None);
    refused(&s, a, json!({"op": "union", "with": 1}), 422, None);
}

#[test]
fn malformed_requests_are_bad_requests() {
    let s = TestServer::start();
    let a = make(&s, cube(2.0), [0.0; 3], None);
    let b = make(&s, cube(2.0), [1.0, 0.0, 0.0], None);
    for req in [
        json!({"op": "xor", "with": b}),
        json!({"with": b}),
        json!({"op": "union"}),
        json!({"op": "union", "with": b, "keep": true}),
        json!({"op": "union", "with": -1}),
        json!({"op": "union", "with": b, "keep_with": "yes"}),
    ] {
        refused(&s, a, req, 400, Some("bad-request"));
    }
    let before = world(&s);
    s.post_raw(&format!("/v1/bodies/{a}/boolean"), "text/plain", b"{}")
        .problem(415);
    assert_eq!(world(&s), before);
}

// ----- results (these need the kernel) -------------------------------------------------

#[test]
fn a_cylinder_through_a_box_makes_a_hole() {
    let s = TestServer::start();
    let a = make(&s, cube(2.0), [0.0; 3], None);
    let segments = 32;
    let c = make(
        &s,
        json!({"type": "cylinder", "radius": 0.5, "height": 4, "segments": segments}),
        [0.0; 3],
        None,
    );
    let before = s.get("/v1/world").ok()["revision"].as_u64().unwrap();
    let v = boolean(&s, a, json!({"op": "difference", "with": c})).ok();
    assert_eq!(v["id"], a, "{v}");
    assert_eq!(v["revision"], before + 1, "one write, one revision: {v}");
    assert_eq!(v["killed"], json!([c]), "{v}");
    let pieces = v["pieces"].as_array().expect("pieces");
    assert_eq!(pieces.len(), 1, "{v}");
    assert_eq!(pieces[0]["id"], a);
    let polygon = 0.5 * f64::from(segments) * 0.25 * (2.0 * PI / f64::from(segments)).sin();
    let volume = 8.0 - 2.0 * polygon;
    assert!(
        close(pieces[0]["volume"].as_f64().unwrap(), volume, 1e-9),
        "{v}"
    );

    let body = s.get(&format!("/v1/bodies/{a}")).ok();
    assert_eq!(body["euler"]["H"], 1, "a hole through the box: {body}");
    let (f, e, vx) = (
        body["euler"]["F"].as_i64().unwrap(),
        body["euler"]["E"].as_i64().unwrap(),
        body["euler"]["V"].as_i64().unwrap(),
    );
    assert_eq!(f - e + vx, 0, "F − E + V = 2(1 − H): {body}");
    assert_eq!(pieces[0]["faces"].as_i64(), Some(f));
    support::check_topology_dump(&s.get(&format!("/v1/bodies/{a}/topology")).ok(), 1);
    s.get(&format!("/v1/bodies/{c}")).problem(404);

    // Every face came from the box or the cylinder, and names a face it had.
    let sources = pieces[0]["sources"].as_array().expect("sources");
    assert_eq!(sources.len() as i64, f, "{v}");
    for src in sources {
        let from = src[1].as_u64().unwrap();
        assert!(from == a || from == c, "{src}");
    }
}

#[test]
fn two_overlapping_boxes_unite_into_one_and_the_change_is_published() {
    let s = TestServer::start();
    let a = make(&s, cube(2.0), [0.0; 3], None);
    let b = make(&s, cube(2.0), [1.0, 0.0, 0.0], None);
    let before = s.get("/v1/world").ok()["revision"].as_u64().unwrap();
    let v = boolean(&s, a, json!({"op": "union", "with": b})).ok();
    let pieces = v["pieces"].as_array().expect("pieces");
    assert_eq!(pieces.len(), 1, "{v}");
    assert!(
        close(pieces[0]["volume"].as_f64().unwrap(), 12.0, 1e-9),
        "{v}"
    );
    assert_eq!(v["killed"], json!([b]));
    let body = s.get(&format!("/v1/bodies/{a}")).ok();
    assert_eq!(body["euler"]["H"], 0, "{body}");
    let bounds = &body["bounds"];
    assert_eq!(bounds["min"], json!([-1.0, -1.0, -1.0]), "{body}");
    assert_eq!(bounds["max"], json!([2.0, 1.0, 1.0]), "{body}");

    let changes = s.get(&format!("/v1/world/changes?since={before}")).ok();
    let change = &changes["changes"][0];
    assert_eq!(change["edit"], "boolean", "{changes}");
    let entries = change["changes"].as_array().expect("entries");
    assert!(
        entries.contains(
            &json!({"action": "updated", "kind": "body", "id": a, "fields": ["topology"]})
        ),
        "{changes}"
    );
    assert!(
        entries.contains(&json!({"action": "removed", "kind": "body", "id": b})),
        "{changes}"
    );
}

#[test]
fn a_difference_that_leaves_nothing_kills_b1() {
    let s = TestServer::start();
    let a = make(&s, cube(1.0), [0.0; 3], None);
    let part = make(&s, cube(0.2), [0.0; 3], Some(a));
    let b = make(&s, cube(4.0), [0.0; 3], None);
    let v = boolean(&s, a, json!({"op": "difference", "with": b})).ok();
    assert_eq!(v["pieces"], json!([]), "{v}");
    let killed = v["killed"].as_array().expect("killed");
    for k in [a, part, b] {
        assert!(killed.contains(&json!(k)), "{k} killed: {v}");
        s.get(&format!("/v1/bodies/{k}")).problem(404);
    }
}

#[test]
fn keep_with_keeps_the_other_body() {
    let s = TestServer::start();
    let a = make(&s, cube(2.0), [0.0; 3], None);
    let b = make(&s, cube(2.0), [1.0, 0.0, 0.0], None);
    let other = s.get(&format!("/v1/bodies/{b}/topology")).ok();
    let v = boolean(
        &s,
        a,
        json!({"op": "intersection", "with": b, "keep_with": true}),
    )
    .ok();
    assert_eq!(v["killed"], json!([]), "{v}");
    assert!(
        close(v["pieces"][0]["volume"].as_f64().unwrap(), 4.0, 1e-9),
        "{v}"
    );
    let mut after = s.get(&format!("/v1/bodies/{b}/topology")).ok();
    after["revision"] = other["revision"].clone();
    assert_eq!(after, other, "B2 is as it was");
}

#[test]
fn a_result_in_two_pieces_puts_the_second_beside_b1() {
    let s = TestServer::start();
    let a = make(
        &s,
        json!({"type": "box", "size": [4, 1, 1]}),
        [0.0; 3],
        None,
    );
    s.patch(
        &format!("/v1/bodies/{a}"),
        &json!({"name": "bar", "color": "#102030"}),
    )
    .ok();
    // A cutter wider than the bar, so that no faces lie in one plane.
    let b = make(
        &s,
        json!({"type": "box", "size": [1, 2, 2]}),
        [0.0; 3],
        None,
    );
    let v = boolean(&s, a, json!({"op": "difference", "with": b})).ok();
    let pieces = v["pieces"].as_array().expect("pieces");
    assert_eq!(pieces.len(), 2, "{v}");
    for p in pieces {
        assert!(close(p["volume"].as_f64().unwrap(), 1.5, 1e-9), "{v}");
    }
    assert_eq!(pieces[0]["id"], a);
    let second = pieces[1]["id"].as_u64().unwrap();
    let (one, two) = (
        s.get(&format!("/v1/bodies/{a}")).ok(),
        s.get(&format!("/v1/bodies/{second}")).ok(),
    );
    assert_eq!(one["name"], "bar");
    assert_eq!(two["name"], Value::Null);
    for field in ["parent", "pose", "color"] {
        assert_eq!(one[field], two[field], "{field}");
    }
}

#[test]
fn open_bodies_are_refused() {
    let s = TestServer::start();
    let a = make(&s, cube(2.0), [0.0; 3], None);
    // A seminal body, then a wire of one edge, then a lamina of two faces.
    let seed = s
        .post(
            "/v1/bodies",
            &json!({"shape": {"type": "seminal", "position": [0, 0, 0]}}),
        )
        .ok();
    let (body, face, v0) = (
        seed["id"].as_u64().unwrap(),
        seed["face"].as_u64().unwrap(),
        seed["vertex"].as_u64().unwrap(),
    );
    refused(
        &s,
        a,
        json!({"op": "union", "with": body}),
        422,
        Some("boolean-refused"),
    );
    let euler = |op: Value| s.post(&format!("/v1/bodies/{body}/euler"), &op).ok();
    let v1 =
        euler(json!({"op": "mkev", "face": face, "vertex": v0, "position": [1, 0, 0]}))["vertex"]
            .as_u64()
            .unwrap();
    for (b1, b2) in [(a, body), (body, a)] {
        let p = refused(
            &s,
            b1,
            json!({"op": "union", "with": b2}),
            422,
            Some("boolean-refused"),
        );
        assert!(
            p["detail"].as_str().unwrap().contains("closed"),
            "wire: {p}"
        );
    }
    let v2 =
        euler(json!({"op": "mkev", "face": face, "vertex": v1, "position": [1, 1, 0]}))["vertex"]
            .as_u64()
            .unwrap();
    euler(json!({"op": "mkfe", "v1": v0, "face": face, "v2": v2}));
    for (b1, b2) in [(a, body), (body, a)] {
        let p = refused(
            &s,
            b1,
            json!({"op": "difference", "with": b2}),
            422,
            Some("boolean-refused"),
        );
        assert!(
            p["detail"].as_str().unwrap().contains(&body.to_string()),
            "lamina: {p}"
        );
    }
}

#[test]
fn a_self_intersecting_body_is_refused_naming_its_faces() {
    let s = TestServer::start();
    let a = make(&s, cube(4.0), [0.0; 3], None);
    // A prism over a figure-of-eight quadrilateral: one closed, consistently oriented
    // surface (the API takes it: geometry is not checked beyond the volume's sign)
    // whose side faces cross each other.
    let ring = [[0.0, 0.0], [0.0, 1.0], [2.0, 0.0], [2.0, 2.0]];
    let mut vertices = Vec::new();
    for z in [0.0, 1.0] {
        for [x, y] in ring {
            vertices.push(json!([x - 1.0, y - 1.0, z - 0.5]));
        }
    }
    let faces = json!([
        [3, 2, 1, 0],
        [4, 5, 6, 7],
        [0, 1, 5, 4],
        [1, 2, 6, 5],
        [2, 3, 7, 6],
        [3, 0, 4, 7]
    ]);
    let made = s.post(
        "/v1/bodies",
        &json!({"shape": {"type": "polyhedron", "vertices": vertices, "faces": faces}}),
    );
    assert_eq!(
        made.status, 201,
        "POST /v1/bodies refused the crossed prism before any boolean saw it: {}",
        made.text
    );
    let crossed = made.json()["id"].as_u64().unwrap();
    for (b1, b2) in [(a, crossed), (crossed, a)] {
        let p = refused(
            &s,
            b1,
            json!({"op": "intersection", "with": b2}),
            422,
            Some("boolean-refused"),
        );
        let detail = p["detail"].as_str().unwrap();
        assert!(
            detail.contains(&crossed.to_string()) && detail.contains("cross"),
            "{p}"
        );
    }
}

// ----- persistence --------------------------------------------------------------------

/// A body as the server shows it, without the revision it was read at.
fn body_dump(http: &ureq::Agent, base: &str, id: u64) -> (u16, Value) {
    let mut out = Vec::new();
    let mut status = 0;
    for path in [
        format!("/v1/bodies/{id}"),
        format!("/v1/bodies/{id}/topology"),
    ] {
        let mut res = http
            .get(&format!("{base}{path}"))
            .call()
            .expect("the server answers");
        status = res.status().as_u16();
        let mut v: Value = res.body_mut().read_json().expect("JSON");
        if let Some(o) = v.as_object_mut() {
            o.remove("revision");
        }
        out.push(v);
    }
    (status, Value::Array(out))
}

#[test]
fn a_boolean_survives_a_restart_with_the_same_bodies_and_ids() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let data = dir.path().join("world").display().to_string();
    let http = process::agent(Duration::from_secs(60));
    let post = |base: &str, path: &str, body: Value| -> Value {
        let mut res = http
            .post(&format!("{base}{path}"))
            .send_json(&body)
            .expect("the server answers");
        let status = res.status().as_u16();
        let v: Value = res.body_mut().read_json().expect("JSON");
        assert!((200..300).contains(&status), "{path}: {status} {v}");
        v
    };

    let server = process::Server::start(&["--data", &data]);
    let base = server.base.clone();
    let a = post(&base, "/v1/bodies", json!({"shape": cube(2.0)}))["id"]
        .as_u64()
        .unwrap();
    let c = post(
        &base,
        "/v1/bodies",
        json!({"shape": {"type": "cylinder", "radius": 0.5, "height": 4, "segments": 12}}),
    )["id"]
        .as_u64()
        .unwrap();
    let b = post(
        &base,
        "/v1/bodies",
        json!({"shape": cube(2.0), "pose": {"position": [1.5, 0.2, 0.1], "rotation": [0, 0, 0.2588190451, 0.9659258263]}}),
    )["id"]
        .as_u64()
        .unwrap();
    post(
        &base,
        &format!("/v1/bodies/{a}/boolean"),
        json!({"op": "difference", "with": c}),
    );
    let v = post(
        &base,
        &format!("/v1/bodies/{a}/boolean"),
        json!({"op": "union", "with": b, "keep_with": true}),
    );
    let ids: Vec<u64> = v["pieces"]
        .as_array()
        .expect("pieces")
        .iter()
        .map(|p| p["id"].as_u64().unwrap())
        .chain([b, c])
        .collect();
    let before: Vec<(u16, Value)> = ids.iter().map(|&id| body_dump(&http, &base, id)).collect();
    let world_before = http
        .get(&format!("{base}/v1/world"))
        .call()
        .expect("answers")
        .body_mut()
        .read_json::<Value>()
        .expect("JSON");
    // SIGKILL: no snapshot at the stop, so the restart replays the journal.
    server.kill();

    let server = process::Server::start(&["--data", &data]);
    let base = server.base.clone();
    let after: Vec<(u16, Value)> = ids.iter().map(|&id| body_dump(&http, &base, id)).collect();
    assert_eq!(
        after, before,
        "the same bodies, ids and loci after the replay"
    );
    let world_after = http
        .get(&format!("{base}/v1/world"))
        .call()
        .expect("answers")
        .body_mut()
        .read_json::<Value>()
        .expect("JSON");
    assert_eq!(world_after, world_before);
    // The next body takes the next id, as it would have without the restart.
    let next = post(&base, "/v1/bodies", json!({"shape": cube(1.0)}))["id"]
        .as_u64()
        .unwrap();
    assert!(next > *ids.iter().max().unwrap());
    drop(server);
    process::check_data(dir.path().join("world").as_path());
}
