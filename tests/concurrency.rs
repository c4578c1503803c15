//! Many clients at once: 16 clients × 200 mixed writes and reads over real HTTP.
//! Revisions rise by exactly one per write, no write is lost, and every read sees a
//! consistent body.

#[path = "support/http.rs"]
mod support;

use std::sync::Arc;

use serde_json::json;
use support::{TestServer, check_topology_dump};

const CLIENTS: usize = 16;
const REQUESTS: usize = 200;

#[test]
fn sixteen_clients_writing_and_reading_at_once() {
    let s = Arc::new(TestServer::start());
    let made = s.post(
        "/v1/bodies",
        &json!({"name": "shared", "shape": {"type": "box", "size": [2, 2, 2]}}),
    );
    assert_eq!(made.status, 201);
    let b = made.json()["id"].as_u64().unwrap();
    let r0 = made.json()["revision"].as_u64().unwrap();
    let t = s.get(&format!("/v1/bodies/{b}/topology")).ok();
    // ESPLIT never kills the edge it splits, so the cube's first edges stay valid.
    let edges: Vec<u64> = t["edges"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["id"].as_u64().unwrap())
        .collect();
    let edges = Arc::new(edges);

    let workers: Vec<_> = (0..CLIENTS)
        .map(|c| {
            let (s, edges) = (s.clone(), edges.clone());
            std::thread::spawn(move || {
                let mut revisions = Vec::new();
                let mut splits = 0usize;
                for i in 0..REQUESTS {
                    match (c + i) % 4 {
                        0 => {
                            let e = edges[(c * 7 + i) % edges.len()];
                            let a = s
                                .post(
                                    &format!("/v1/bodies/{b}/euler"),
                                    &json!({"op": "esplit", "edge": e}),
                                )
                                .ok();
                            revisions.push(a["revision"].as_u64().unwrap());
                            splits += 1;
                        }
                        1 => {
                            let a = s
                                .post(
                                    &format!("/v1/bodies/{b}/transform"),
                                    &json!({"op": "translate", "vector": [0.001, 0, 0]}),
                                )
                                .ok();
                            revisions.push(a["revision"].as_u64().unwrap());
                        }
                        2 => {
                            let t = s.get(&format!("/v1/bodies/{b}/topology")).ok();
                            check_topology_dump(&t, 0);
                            let v = t["vertices"].as_array().unwrap().len();
                            assert!((8..=8 + CLIENTS * REQUESTS).contains(&v));
                        }
                        _ => {
                            let body = s.get(&format!("/v1/bodies/{b}")).ok();
                            let e = &body["euler"];
                            let chi = e["F"].as_i64().unwrap() - e["E"].as_i64().unwrap()
                                + e["V"].as_i64().unwrap();
                            assert_eq!(chi, 2);
                        }
                    }
                }
                assert!(
                    revisions.windows(2).all(|w| w[0] < w[1]),
                    "a client sees its writes in order"
                );
                (revisions, splits)
            })
        })
        .collect();
    let mut all = Vec::new();
    let mut splits = 0;
    for w in workers {
        let (r, n) = w.join().expect("a client thread");
        all.extend(r);
        splits += n;
    }
    all.sort_unstable();
    let writes = all.len() as u64;
    assert_eq!(writes, (CLIENTS * REQUESTS / 2) as u64);
    let expected: Vec<u64> = (r0 + 1..=r0 + writes).collect();
    assert_eq!(
        all, expected,
        "one revision per write, none skipped, none repeated"
    );
    assert_eq!(
        s.get("/v1/world").ok()["revision"].as_u64(),
        Some(r0 + writes)
    );
    let body = s.get(&format!("/v1/bodies/{b}")).ok();
    assert_eq!(
        body["euler"]["V"].as_u64(),
        Some(8 + splits as u64),
        "no split was lost"
    );
    let x = body["world_pose"]["position"][0].as_f64().unwrap();
    let moves = writes as usize - splits;
    assert!(
        (x - 0.001 * moves as f64).abs() < 1e-9,
        "no move was lost: {x}"
    );
    check_topology_dump(&s.get(&format!("/v1/bodies/{b}/topology")).ok(), 0);
}

/// The `winged_edits_planning` gauge: large edits being built beside the world's owner.
fn planning(s: &TestServer) -> u64 {
    let text = s.get("/metrics").text;
    text.lines()
        .find_map(|l| l.strip_prefix("winged_edits_planning "))
        .and_then(|v| v.trim().parse().ok())
        .expect("the planning gauge is exported")
}

/// A large body is built beside the world's owner: while a sphere of 500,000 faces is
/// being built (seen on the planning gauge), a PATCH of another body's pose and reads
/// are answered, and the PATCH's revision comes before the sphere's. Order of events
/// only; no timing.
#[test]
fn small_writes_pass_a_large_body_being_built() {
    let s = Arc::new(TestServer::start());
    let small = s.post(
        "/v1/bodies",
        &json!({"name": "small", "shape": {"type": "box", "size": [1, 1, 1]}}),
    );
    assert_eq!(small.status, 201);
    let small = small.json()["id"].as_u64().unwrap();
    assert_eq!(planning(&s), 0);

    let maker = s.clone();
    let creating = std::thread::spawn(move || {
        maker.post(
            "/v1/bodies",
            &json!({"name": "ball", "shape": {"type": "sphere", "radius": 1, "segments": 1000, "rings": 500}}),
        )
    });
    while planning(&s) == 0 {
        assert!(
            !creating.is_finished(),
            "the sphere was made before its build could be seen"
        );
        std::thread::yield_now();
    }
    let moved = s.patch(
        &format!("/v1/bodies/{small}"),
        &json!({"pose": {"position": [5, 0, 0]}}),
    );
    assert_eq!(moved.status, 200, "{}", moved.text);
    let moved_at = moved.json()["revision"].as_u64().unwrap();
    let read = s.get(&format!("/v1/bodies/{small}")).ok();
    assert_eq!(read["pose"]["position"], json!([5.0, 0.0, 0.0]));
    let world = s.get("/v1/world").ok();
    assert!(
        world["revision"].as_u64().unwrap() >= moved_at,
        "a read sees the write it follows"
    );

    let made = creating.join().expect("the creating client");
    assert_eq!(made.status, 201, "{}", made.text);
    let made = made.json();
    assert!(
        moved_at < made["revision"].as_u64().unwrap(),
        "the small write went before the large one: {moved_at} vs {}",
        made["revision"]
    );
    assert_eq!(made["faces"], json!(500_000));
    assert_eq!(planning(&s), 0);
    let ball = s.get(&format!("/v1/bodies/{}", made["id"])).ok();
    assert_eq!(ball["name"], "ball");
}

/// A large body refused, whether by its own parameters while it is built beside the
/// owner or by the world when it is inserted (a taken name, an unknown parent), is
/// answered with a problem and leaves the world as it was: same revision, and the next
/// body gets the ids it would have had.
#[test]
fn a_large_body_refused_changes_nothing() {
    let s = TestServer::start();
    let first = s.post(
        "/v1/bodies",
        &json!({"name": "taken", "shape": {"type": "box", "size": [1, 1, 1]}}),
    );
    assert_eq!(first.status, 201);
    let before = s.get("/v1/world").ok();
    let sphere = |extra: serde_json::Value, radius: f64| {
        let mut body =
            json!({"shape": {"type": "sphere", "radius": radius, "segments": 128, "rings": 64}});
        for (k, v) in extra.as_object().unwrap() {
            body[k] = v.clone();
        }
        s.post("/v1/bodies", &body)
    };
    let bad_radius = sphere(json!({}), -1.0);
    bad_radius.problem(422);
    let taken = sphere(json!({"name": "taken"}), 1.0).problem(409);
    assert_eq!(taken["type"], "urn:winged:problem:name-taken");
    let orphan = sphere(json!({"parent": 999_999}), 1.0);
    orphan.problem(404);
    assert_eq!(s.get("/v1/world").ok(), before, "nothing changed");

    // The next body's ids are those of a world that never saw the refusals.
    let made = sphere(json!({"name": "ball"}), 1.0).ok();
    let fresh = TestServer::start();
    fresh.post(
        "/v1/bodies",
        &json!({"name": "taken", "shape": {"type": "box", "size": [1, 1, 1]}}),
    );
    let reference = fresh
        .post(
            "/v1/bodies",
            &json!({"name": "ball", "shape": {"type": "sphere", "radius": 1.0, "segments": 128, "rings": 64}}),
        )
        .ok();
    assert_eq!(made["id"], reference["id"]);
    let topology = |srv: &TestServer, id: &serde_json::Value| {
        srv.get(&format!("/v1/bodies/{id}/topology")).ok()["faces"][0].clone()
    };
    assert_eq!(
        topology(&s, &made["id"]),
        topology(&fresh, &reference["id"])
    );
}
