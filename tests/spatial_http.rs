//! Spatial access over real HTTP: sphere, box, nearest and ray queries against boxes
//! whose answers are worked out by hand; the answers follow moves and deletions with
//! the new revision; bad requests are refused with problem+json and change nothing.

#[path = "support/http.rs"]
mod support;

use serde_json::{Value, json};
use support::TestServer;

const EPS: f64 = 1e-9;

/// A 2×2×2 box (−1..1 on each axis in its own frame) at `at`; answers its id.
fn add_box(s: &TestServer, name: &str, at: [f64; 3]) -> u64 {
    let r = s.post(
        "/v1/bodies",
        &json!({"name": name, "pose": {"position": at}, "shape": {"type": "box", "size": [2, 2, 2]}}),
    );
    r.ok()["id"].as_u64().expect("an id")
}

fn revision(s: &TestServer) -> u64 {
    s.get("/v1/world").ok()["revision"]
        .as_u64()
        .expect("a revision")
}

fn vec3(v: &Value) -> [f64; 3] {
    let a = v.as_array().unwrap_or_else(|| panic!("not a vector: {v}"));
    assert_eq!(a.len(), 3, "{v}");
    [
        a[0].as_f64().expect("x"),
        a[1].as_f64().expect("y"),
        a[2].as_f64().expect("z"),
    ]
}

fn close(a: [f64; 3], b: [f64; 3]) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() < 1e-9)
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

fn ids(list: &Value) -> Vec<u64> {
    let mut v: Vec<u64> = list
        .as_array()
        .unwrap_or_else(|| panic!("not a list: {list}"))
        .iter()
        .map(|x| x["id"].as_u64().expect("an id"))
        .collect();
    v.sort_unstable();
    v
}

/// The ids of a body's faces, edges and vertices, as its topology gives them.
struct Topology {
    /// (id, outward normal).
    faces: Vec<(u64, [f64; 3])>,
    /// (id, nvt, pvt).
    edges: Vec<(u64, u64, u64)>,
    /// (id, position in the body's frame).
    vertices: Vec<(u64, [f64; 3])>,
}

impl Topology {
    fn of(s: &TestServer, body: u64) -> Topology {
        let t = s.get(&format!("/v1/bodies/{body}/topology")).ok();
        let list = |k: &str| t[k].as_array().expect("a list").clone();
        Topology {
            faces: list("faces")
                .iter()
                .map(|f| {
                    let p = f["plane"].as_array().expect("a plane");
                    let n = [0, 1, 2].map(|k| p[k].as_f64().expect("a number"));
                    (f["id"].as_u64().expect("an id"), n)
                })
                .collect(),
            edges: list("edges")
                .iter()
                .map(|e| {
                    let id = |k: &str| e[k].as_u64().expect("an id");
                    (id("id"), id("nvt"), id("pvt"))
                })
                .collect(),
            vertices: list("vertices")
                .iter()
                .map(|v| (v["id"].as_u64().expect("an id"), vec3(&v["position"])))
                .collect(),
        }
    }

    /// The face whose outward normal is `n`.
    fn face(&self, n: [f64; 3]) -> u64 {
        self.faces
            .iter()
            .find(|(_, m)| close(*m, n))
            .unwrap_or_else(|| panic!("no face faces {n:?}"))
            .0
    }

    fn vertex(&self, p: [f64; 3]) -> u64 {
        self.vertices
            .iter()
            .find(|(_, q)| close(*q, p))
            .unwrap_or_else(|| panic!("no vertex at {p:?}"))
            .0
    }

    /// The edges that meet vertex `v`, sorted.
    fn edges_at(&self, v: u64) -> Vec<u64> {
        let mut e: Vec<u64> = self
            .edges
            .iter()
            .filter(|(_, a, b)| *a == v || *b == v)
            .map(|(id, _, _)| *id)
            .collect();
        e.sort_unstable();
        e
    }
}

/// Checks the corner answer: a 2×2×2 box centred at `c`, a region reaching in around its
/// (+1, +1, +1) corner by 0.5 along each edge.
fn check_corner(hit: &Value, t: &Topology, c: [f64; 3]) {
    let corner = [c[0] + 1.0, c[1] + 1.0, c[2] + 1.0];
    let v = t.vertex([1.0, 1.0, 1.0]);
    let vertices = hit["vertices"].as_array().expect("vertices");
    assert_eq!(vertices.len(), 1, "{hit}");
    assert_eq!(vertices[0]["id"], v);
    assert!(close(vec3(&vertices[0]["position"]), corner), "{hit}");
    assert_eq!(ids(&hit["edges"]), t.edges_at(v), "{hit}");
    for e in hit["edges"].as_array().expect("edges") {
        let a = vec3(&e["segment"][0]);
        let b = vec3(&e["segment"][1]);
        assert!((dist(a, b) - 0.5).abs() < EPS, "clipped to 0.5: {e}");
        assert!(
            close(a, corner) || close(b, corner),
            "one end at the corner: {e}"
        );
    }
    let mut faces = vec![
        t.face([1.0, 0.0, 0.0]),
        t.face([0.0, 1.0, 0.0]),
        t.face([0.0, 0.0, 1.0]),
    ];
    faces.sort_unstable();
    assert_eq!(ids(&hit["faces"]), faces, "{hit}");
}

#[test]
fn a_sphere_at_a_corner_answers_the_vertex_its_three_edges_clipped_and_three_faces() {
    let s = TestServer::start();
    let b = add_box(&s, "block", [0.0; 3]);
    let rev = revision(&s);
    let t = Topology::of(&s, b);

    let r = s.post(
        "/v1/spatial/sphere",
        &json!({"center": [1, 1, 1], "radius": 0.5}),
    );
    let a = r.ok();
    assert_eq!(r.header("etag"), format!("\"{rev}\""));
    assert_eq!(a["revision"], rev);
    assert_eq!(a["detail"], "features");
    assert_eq!(a["radius"], 0.5);
    let bodies = a["bodies"].as_array().expect("bodies");
    assert_eq!(bodies.len(), 1, "{a}");
    let hit = &bodies[0];
    assert_eq!(hit["id"], b);
    assert_eq!(hit["name"], "block");
    // The centre is on the surface: in the solid, at distance 0.
    assert_eq!(hit["inside"], true);
    assert_eq!(hit["distance"], 0.0);
    check_corner(hit, &t, [0.0; 3]);

    // The GET form answers the same.
    let g = s.get("/v1/spatial/sphere?x=1&y=1&z=1&r=0.5");
    assert_eq!(g.ok(), a);
    assert_eq!(g.header("etag"), r.header("etag"));

    // Bodies only.
    let only = s
        .get("/v1/spatial/sphere?x=1&y=1&z=1&r=0.5&detail=bodies")
        .ok();
    let hit = &only["bodies"][0];
    assert_eq!(hit["id"], b);
    assert!(
        hit.get("faces").is_none() && hit.get("edges").is_none(),
        "{only}"
    );
}

#[test]
fn a_centre_inside_is_at_distance_zero_and_a_centre_outside_at_its_distance() {
    let s = TestServer::start();
    let b = add_box(&s, "block", [0.0; 3]);
    let t = Topology::of(&s, b);

    let a = s
        .post(
            "/v1/spatial/sphere",
            &json!({"center": [0.2, 0.1, 0], "radius": 0.3, "detail": "bodies"}),
        )
        .ok();
    assert_eq!(a["bodies"][0]["inside"], true, "{a}");
    assert_eq!(a["bodies"][0]["distance"], 0.0, "{a}");

    // From (3, 0, 0) the box is 2 away; a radius of 2.1 reaches the +x face only (its
    // edges are √5 ≈ 2.236 away). The face's portion is the circle of radius
    // √(2.1² − 2²) about (1, 0, 0), within the tolerance.
    let a = s
        .post(
            "/v1/spatial/sphere",
            &json!({"center": [3, 0, 0], "radius": 2.1, "detail": "portions", "tolerance": 0.001}),
        )
        .ok();
    let hit = &a["bodies"][0];
    assert_eq!(hit["inside"], false, "{a}");
    assert!((hit["distance"].as_f64().expect("distance") - 2.0).abs() < EPS);
    let faces = hit["faces"].as_array().expect("faces");
    assert_eq!(faces.len(), 1, "{a}");
    assert_eq!(faces[0]["id"], t.face([1.0, 0.0, 0.0]));
    assert!((faces[0]["distance"].as_f64().expect("distance") - 2.0).abs() < EPS);
    assert_eq!(hit["edges"], json!([]));
    assert_eq!(hit["vertices"], json!([]));
    let tolerance = a["tolerance"].as_f64().expect("the tolerance answered");
    assert!(tolerance >= 0.001, "{a}");
    let rho = (2.1f64 * 2.1 - 4.0).sqrt();
    let loops = faces[0]["portion"].as_array().expect("a portion");
    assert_eq!(loops.len(), 1, "{a}");
    let points = loops[0].as_array().expect("a loop");
    assert!(points.len() >= 8, "a circle, not a few chords: {a}");
    for p in points {
        let p = vec3(p);
        assert!((p[0] - 1.0).abs() < EPS, "on the face's plane: {p:?}");
        let r = dist(p, [1.0, 0.0, 0.0]);
        assert!(r <= rho + EPS && r >= rho - tolerance - EPS, "{r} vs {rho}");
    }
}

#[test]
fn box_nearest_and_ray_answer_what_is_worked_out_by_hand() {
    let s = TestServer::start();
    let b = add_box(&s, "block", [0.0; 3]);
    let rev = revision(&s);
    let t = Topology::of(&s, b);

    // A box over the (+1, +1, +1) corner, 0.5 into the block on each axis.
    let r = s.post(
        "/v1/spatial/box",
        &json!({"min": [0.5, 0.5, 0.5], "max": [2, 2, 2]}),
    );
    let a = r.ok();
    assert_eq!(r.header("etag"), format!("\"{rev}\""));
    assert_eq!(a["revision"], rev);
    let hit = &a["bodies"][0];
    assert_eq!(hit["id"], b);
    assert_eq!(
        hit["inside"], false,
        "the box's centre (1.25, 1.25, 1.25) is outside"
    );
    check_corner(hit, &t, [0.0; 3]);
    let g = s.get("/v1/spatial/box?min_x=0.5&min_y=0.5&min_z=0.5&max_x=2&max_y=2&max_z=2");
    assert_eq!(g.ok(), a);
    // A box around the whole block holds everything of it.
    let all = s
        .get("/v1/spatial/box?min_x=-3&min_y=-3&min_z=-3&max_x=3&max_y=3&max_z=3")
        .ok();
    let hit = &all["bodies"][0];
    assert_eq!(hit["inside"], true);
    assert_eq!(
        [&hit["faces"], &hit["edges"], &hit["vertices"]].map(|l| l.as_array().map(Vec::len)),
        [Some(6), Some(12), Some(8)]
    );
    // A box beside it meets nothing.
    let none = s
        .post(
            "/v1/spatial/box",
            &json!({"min": [1.5, -1, -1], "max": [3, 1, 1]}),
        )
        .ok();
    assert_eq!(none["bodies"], json!([]));

    // Nearest to (4, 0.5, 0): (1, 0.5, 0) on the +x face, 3 away.
    let r = s.post("/v1/spatial/nearest", &json!({"point": [4, 0.5, 0]}));
    let n = r.ok();
    assert_eq!(r.header("etag"), format!("\"{rev}\""));
    assert_eq!(n["revision"], rev);
    let hit = &n["hit"];
    assert_eq!(hit["id"], b);
    assert_eq!(hit["name"], "block");
    assert_eq!(hit["inside"], false);
    assert!((hit["distance"].as_f64().expect("distance") - 3.0).abs() < EPS);
    assert!((hit["surface_distance"].as_f64().expect("distance") - 3.0).abs() < EPS);
    assert!(close(vec3(&hit["point"]), [1.0, 0.5, 0.0]), "{n}");
    assert_eq!(hit["face"], t.face([1.0, 0.0, 0.0]));
    assert_eq!(s.get("/v1/spatial/nearest?x=4&y=0.5&z=0").ok(), n);
    // Inside: distance 0, the surface 0.8 away at (0.2, 1, 0).
    let n = s.get("/v1/spatial/nearest?x=0.2&y=0.2&z=0").ok();
    assert_eq!(n["hit"]["inside"], true);
    assert_eq!(n["hit"]["distance"], 0.0);
    assert!((n["hit"]["surface_distance"].as_f64().expect("distance") - 0.8).abs() < EPS);
    // Nothing within 2.5 of (4, 0.5, 0).
    let n = s
        .get("/v1/spatial/nearest?x=4&y=0.5&z=0&max_distance=2.5")
        .ok();
    assert_eq!(n["hit"], Value::Null, "{n}");
    assert_eq!(n["revision"], rev);

    // A ray along +x from (−5, 0.2, 0.3) enters the −x face at (−1, 0.2, 0.3), 4 along.
    let r = s.post(
        "/v1/spatial/ray",
        &json!({"origin": [-5, 0.2, 0.3], "direction": [2, 0, 0]}),
    );
    let h = r.ok();
    assert_eq!(r.header("etag"), format!("\"{rev}\""));
    let hit = &h["hit"];
    assert_eq!(hit["id"], b);
    assert_eq!(hit["face"], t.face([-1.0, 0.0, 0.0]));
    assert!(close(vec3(&hit["point"]), [-1.0, 0.2, 0.3]), "{h}");
    assert!((hit["distance"].as_f64().expect("distance") - 4.0).abs() < EPS);
    assert!(close(vec3(&hit["normal"]), [-1.0, 0.0, 0.0]), "{h}");
    assert_eq!(hit["entering"], true);
    assert_eq!(
        s.get("/v1/spatial/ray?x=-5&y=0.2&z=0.3&dx=2&dy=0&dz=0")
            .ok(),
        h
    );
    // From inside, up: leaves through the top face at (0, 0, 1).
    let h = s.get("/v1/spatial/ray?x=0&y=0&z=0&dx=0&dy=0&dz=1").ok();
    assert_eq!(h["hit"]["face"], t.face([0.0, 0.0, 1.0]));
    assert!((h["hit"]["distance"].as_f64().expect("distance") - 1.0).abs() < EPS);
    assert_eq!(h["hit"]["entering"], false);
    // Beside it, and short of it: no hit.
    let h = s.get("/v1/spatial/ray?x=-5&y=5&z=0&dx=1&dy=0&dz=0").ok();
    assert_eq!(h["hit"], Value::Null, "{h}");
    let h = s
        .post(
            "/v1/spatial/ray",
            &json!({"origin": [-5, 0, 0], "direction": [1, 0, 0], "max_distance": 3.5}),
        )
        .ok();
    assert_eq!(h["hit"], Value::Null, "{h}");
}

#[test]
fn answers_follow_a_moved_body_with_the_new_revision() {
    let s = TestServer::start();
    let a = add_box(&s, "a", [0.0; 3]);
    let b = add_box(&s, "b", [5.0, 0.0, 0.0]);
    let t = Topology::of(&s, a);
    let corner = json!({"center": [1, 1, 1], "radius": 0.5});
    // The index is built by this query.
    let first = s.post("/v1/spatial/sphere", &corner).ok();
    assert_eq!(ids(&first["bodies"]), vec![a]);
    let near = s.get("/v1/spatial/nearest?x=2.4&y=0&z=0").ok();
    assert_eq!(near["hit"]["id"], a, "1.4 from a, 1.6 from b");

    // Move a to (10, 0, 0).
    let moved = s.patch(
        &format!("/v1/bodies/{a}"),
        &json!({"pose": {"position": [10, 0, 0]}}),
    );
    let rev = moved.ok()["revision"].as_u64().expect("a revision");
    let r = s.post("/v1/spatial/sphere", &corner);
    let old = r.ok();
    assert_eq!(old["revision"], rev, "the answer is at the move's revision");
    assert_eq!(r.header("etag"), format!("\"{rev}\""));
    assert_eq!(old["bodies"], json!([]), "the old place is empty: {old}");
    let new = s
        .post(
            "/v1/spatial/sphere",
            &json!({"center": [11, 1, 1], "radius": 0.5}),
        )
        .ok();
    assert_eq!(new["revision"], rev);
    assert_eq!(ids(&new["bodies"]), vec![a]);
    check_corner(&new["bodies"][0], &t, [10.0, 0.0, 0.0]);
    let near = s.get("/v1/spatial/nearest?x=2.4&y=0&z=0").ok();
    assert_eq!(near["hit"]["id"], b, "a has gone: {near}");
    let h = s.get("/v1/spatial/ray?x=20&y=0&z=0&dx=-1&dy=0&dz=0").ok();
    assert_eq!(h["hit"]["id"], a);
    assert!(close(vec3(&h["hit"]["point"]), [11.0, 0.0, 0.0]), "{h}");

    // A translate moves it again (a transform rather than a PATCH).
    let moved = s.post(
        &format!("/v1/bodies/{a}/transform"),
        &json!({"op": "translate", "vector": [0, 10, 0]}),
    );
    let rev = moved.ok()["revision"].as_u64().expect("a revision");
    let here = s.get("/v1/spatial/sphere?x=11&y=11&z=1&r=0.5").ok();
    assert_eq!(here["revision"], rev);
    assert_eq!(ids(&here["bodies"]), vec![a]);
    let gone = s.get("/v1/spatial/sphere?x=11&y=1&z=1&r=0.5").ok();
    assert_eq!(gone["bodies"], json!([]));

    // A body made after the index was built is found too.
    let c = add_box(&s, "c", [0.0, -5.0, 0.0]);
    let found = s.get("/v1/spatial/box?min_x=-1&min_y=-7&min_z=-1&max_x=1&max_y=-3&max_z=1");
    assert_eq!(ids(&found.ok()["bodies"]), vec![c]);

    // A new name is answered at once, at every detail and by every query.
    s.patch(&format!("/v1/bodies/{a}"), &json!({"name": "renamed"}))
        .ok();
    for detail in ["bodies", "features"] {
        let named = s
            .get(&format!(
                "/v1/spatial/sphere?x=11&y=11&z=1&r=0.5&detail={detail}"
            ))
            .ok();
        assert_eq!(named["bodies"][0]["name"], "renamed", "{named}");
    }
    let near = s.get("/v1/spatial/nearest?x=11&y=13&z=0").ok();
    assert_eq!(near["hit"]["name"], "renamed", "{near}");
    let h = s.get("/v1/spatial/ray?x=20&y=10&z=0&dx=-1&dy=0&dz=0").ok();
    assert_eq!(h["hit"]["name"], "renamed", "{h}");
}

#[test]
fn a_deleted_body_leaves_the_answers() {
    let s = TestServer::start();
    let a = add_box(&s, "a", [0.0; 3]);
    let b = add_box(&s, "b", [5.0, 0.0, 0.0]);
    let everything =
        "/v1/spatial/box?min_x=-10&min_y=-10&min_z=-10&max_x=10&max_y=10&max_z=10&detail=bodies";
    assert_eq!(ids(&s.get(everything).ok()["bodies"]), vec![a, b]);
    let rev = s.delete(&format!("/v1/bodies/{a}")).ok()["revision"]
        .as_u64()
        .expect("a revision");
    let after = s.get(everything).ok();
    assert_eq!(after["revision"], rev);
    assert_eq!(ids(&after["bodies"]), vec![b]);
    let s2 = s.get("/v1/spatial/sphere?x=0&y=0&z=0&r=1").ok();
    assert_eq!(s2["bodies"], json!([]));
    let near = s.get("/v1/spatial/nearest?x=0&y=0&z=0").ok();
    assert_eq!(near["hit"]["id"], b);
    assert!((near["hit"]["distance"].as_f64().expect("distance") - 4.0).abs() < EPS);
    let h = s.get("/v1/spatial/ray?x=-5&y=0&z=0&dx=1&dy=0&dz=0").ok();
    assert_eq!(h["hit"]["id"], b);
    // A skew ray through where a was.
    let h = s
        .get("/v1/spatial/ray?x=-5&y=0&z=0&dx=1&dy=0.01&dz=0.02")
        .ok();
    assert_eq!(h["hit"]["id"], b, "{h}");
    assert!(
        (h["hit"]["point"][0].as_f64().expect("x") - 4.0).abs() < EPS,
        "{h}"
    );
}

#[test]
fn an_index_older_than_the_change_history_catches_up_by_comparing_every_body() {
    // A history of one change: two writes after the index's revision cannot be read
    // back from the feed.
    let limits = winged::server::Limits {
        history: 1,
        ..winged::server::Limits::default()
    };
    let s = TestServer::with_limits(winged::model::World::new(), limits);
    let a = add_box(&s, "a", [0.0; 3]);
    assert_eq!(
        ids(&s
            .get("/v1/spatial/sphere?x=0&y=0&z=0&r=1&detail=bodies")
            .ok()["bodies"]),
        vec![a]
    );
    s.patch(
        &format!("/v1/bodies/{a}"),
        &json!({"pose": {"position": [0, 0, 50]}}),
    )
    .ok();
    let b = add_box(&s, "b", [0.0; 3]);
    let rev = revision(&s);
    let here = s
        .get("/v1/spatial/sphere?x=0&y=0&z=0&r=1&detail=bodies")
        .ok();
    assert_eq!(here["revision"], rev);
    assert_eq!(ids(&here["bodies"]), vec![b]);
    let up = s
        .get("/v1/spatial/sphere?x=0&y=0&z=50&r=1&detail=bodies")
        .ok();
    assert_eq!(ids(&up["bodies"]), vec![a]);
}

/// The value of the spatial index build counter for `how`, from `GET /metrics` (0 when
/// no such build was counted yet).
fn index_builds(s: &TestServer, how: &str) -> u64 {
    let r = s.get("/metrics");
    assert_eq!(r.status, 200, "{}", r.text);
    let prefix = format!("winged_spatial_index_builds_total{{how=\"{how}\"}} ");
    r.text
        .lines()
        .find_map(|l| l.strip_prefix(&prefix))
        .map_or(0, |v| v.trim().parse().expect("a count"))
}

#[test]
fn a_worn_index_is_rebuilt_off_the_lock_while_answers_follow_every_write() {
    let s = TestServer::start();
    let origin = add_box(&s, "origin", [0.0; 3]);
    let all = "/v1/spatial/box?min_x=-2&min_y=-2&min_z=-2&max_x=400&max_y=2&max_z=2&detail=bodies";
    assert_eq!(ids(&s.get(all).ok()["bodies"]), vec![origin]);
    assert_eq!(index_builds(&s, "first"), 1);
    // More new bodies than the index keeps loose: the query that syncs them finds the
    // index worn and starts a rebuild off the lock; it answers from the worn index.
    let row: Vec<u64> = (1..=80)
        .map(|k| add_box(&s, &format!("row {k}"), [4.0 * f64::from(k), 0.0, 0.0]))
        .collect();
    let mut expected = vec![origin];
    expected.extend(&row);
    let found = s.get(all).ok();
    assert_eq!(found["revision"], revision(&s));
    assert_eq!(ids(&found["bodies"]), expected);
    // Writes while the rebuild may run are answered at once, and the fresh index
    // catches up with them before it takes the worn one's place.
    let mut moved = Vec::new();
    let left = |moved: &[u64]| -> Vec<u64> {
        expected
            .iter()
            .copied()
            .filter(|i| !moved.contains(i))
            .collect()
    };
    for (k, &id) in row.iter().enumerate().step_by(10) {
        s.patch(
            &format!("/v1/bodies/{id}"),
            &json!({"pose": {"position": [4.0 * (k + 1) as f64, 50.0, 0.0]}}),
        )
        .ok();
        moved.push(id);
        let here = s.get(all).ok();
        assert_eq!(here["revision"], revision(&s));
        assert_eq!(ids(&here["bodies"]), left(&moved));
    }
    let started = std::time::Instant::now();
    while index_builds(&s, "background") == 0 {
        assert!(
            started.elapsed().as_secs() < 60,
            "no background rebuild counted in a minute"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    assert_eq!(
        index_builds(&s, "in_place"),
        0,
        "no query waited for a rebuild"
    );
    // The fresh index answers every write, those made during its build included.
    let rev = revision(&s);
    let after = s.get(all).ok();
    assert_eq!(after["revision"], rev);
    assert_eq!(ids(&after["bodies"]), left(&moved));
    let up = s
        .get("/v1/spatial/box?min_x=-2&min_y=48&min_z=-2&max_x=400&max_y=52&max_z=2&detail=bodies")
        .ok();
    let mut moved_sorted = moved.clone();
    moved_sorted.sort_unstable();
    assert_eq!(ids(&up["bodies"]), moved_sorted);
    // And goes on following writes.
    let last = row[79];
    s.delete(&format!("/v1/bodies/{last}")).ok();
    let gone = s
        .get("/v1/spatial/sphere?x=320&y=0&z=0&r=1.5&detail=bodies")
        .ok();
    assert_eq!(gone["bodies"], json!([]), "{gone}");
    let near = s.get("/v1/spatial/nearest?x=330&y=0&z=0").ok();
    assert_eq!(near["hit"]["id"], row[78], "{near}");
}

#[test]
fn bad_requests_are_problems_and_change_nothing() {
    let s = TestServer::start();
    add_box(&s, "block", [0.0; 3]);
    let rev = revision(&s);
    // (what, reply, status, a word the detail must hold)
    let cases: Vec<(&str, support::Reply, u16, &str)> = vec![
        (
            "NaN centre in a query string",
            s.get("/v1/spatial/sphere?x=NaN&y=0&z=0&r=1"),
            422,
            "x, y and z",
        ),
        (
            "infinite radius in a query string",
            s.get("/v1/spatial/sphere?x=0&y=0&z=0&r=inf"),
            422,
            "r ",
        ),
        (
            "negative radius",
            s.post(
                "/v1/spatial/sphere",
                &json!({"center": [0, 0, 0], "radius": -1}),
            ),
            422,
            "radius",
        ),
        (
            "zero tolerance",
            s.post(
                "/v1/spatial/sphere",
                &json!({"center": [0, 0, 0], "radius": 1, "tolerance": 0}),
            ),
            422,
            "tolerance",
        ),
        (
            "unknown field",
            s.post(
                "/v1/spatial/sphere",
                &json!({"center": [0, 0, 0], "radius": 1, "colour": "red"}),
            ),
            400,
            "colour",
        ),
        (
            "unknown query parameter",
            s.get("/v1/spatial/sphere?x=0&y=0&z=0&r=1&radius=2"),
            400,
            "radius",
        ),
        (
            "missing radius",
            s.get("/v1/spatial/sphere?x=0&y=0&z=0"),
            400,
            "r",
        ),
        (
            "unknown detail",
            s.get("/v1/spatial/sphere?x=0&y=0&z=0&r=1&detail=everything"),
            400,
            "everything",
        ),
        (
            "broken JSON",
            s.post_raw(
                "/v1/spatial/sphere",
                "application/json",
                br#"{"center": [0, 0, 0], "radius": 1"#,
            ),
            400,
            "JSON",
        ),
        (
            "no JSON content type",
            s.post_raw(
                "/v1/spatial/sphere",
                "text/plain",
                br#"{"center": [0, 0, 0], "radius": 1}"#,
            ),
            415,
            "Content-Type",
        ),
        (
            "too many features",
            s.post(
                "/v1/spatial/sphere",
                &json!({"center": [1, 1, 1], "radius": 0.5, "max_features": 3}),
            ),
            422,
            "more than 3",
        ),
        (
            "empty box in a query string",
            s.get("/v1/spatial/box?min_x=0&min_y=2&min_z=0&max_x=1&max_y=1&max_z=1"),
            422,
            "min_y (2) exceeds max_y (1)",
        ),
        (
            "empty box",
            s.post(
                "/v1/spatial/box",
                &json!({"min": [3, 0, 0], "max": [1, 1, 1]}),
            ),
            422,
            "min[0] (3) exceeds max[0] (1)",
        ),
        (
            "NaN box corner in a query string",
            s.get("/v1/spatial/box?min_x=0&min_y=0&min_z=NaN&max_x=1&max_y=1&max_z=1"),
            422,
            "min_z",
        ),
        (
            "box with an unknown field",
            s.post(
                "/v1/spatial/box",
                &json!({"min": [0, 0, 0], "max": [1, 1, 1], "tolerance": 0.1}),
            ),
            400,
            "tolerance",
        ),
        (
            "NaN point in a query string",
            s.get("/v1/spatial/nearest?x=0&y=NaN&z=0"),
            422,
            "x, y and z",
        ),
        (
            "negative max_distance",
            s.post(
                "/v1/spatial/nearest",
                &json!({"point": [0, 0, 0], "max_distance": -1}),
            ),
            422,
            "max_distance",
        ),
        (
            "NaN max_distance in a query string",
            s.get("/v1/spatial/nearest?x=0&y=0&z=0&max_distance=NaN"),
            422,
            "max_distance",
        ),
        (
            "nearest with a short point",
            s.post("/v1/spatial/nearest", &json!({"point": [0, 0]})),
            400,
            "point",
        ),
        (
            "zero direction in a query string",
            s.get("/v1/spatial/ray?x=0&y=0&z=0&dx=0&dy=0&dz=0"),
            422,
            "dx, dy and dz",
        ),
        (
            "zero direction",
            s.post(
                "/v1/spatial/ray",
                &json!({"origin": [0, 0, 0], "direction": [0, 0, 0]}),
            ),
            422,
            "direction",
        ),
        (
            "NaN origin in a query string",
            s.get("/v1/spatial/ray?x=NaN&y=0&z=0&dx=1&dy=0&dz=0"),
            422,
            "x, y and z",
        ),
        (
            "broken ray JSON",
            s.post_raw("/v1/spatial/ray", "application/json", b"{\"origin\": [0, 0"),
            400,
            "JSON",
        ),
        (
            "ray with an unknown field",
            s.post(
                "/v1/spatial/ray",
                &json!({"origin": [0, 0, 0], "direction": [1, 0, 0], "radius": 1}),
            ),
            400,
            "radius",
        ),
    ];
    for (what, r, status, word) in cases {
        let p = r.problem(status);
        let detail = p["detail"].as_str().unwrap_or_default();
        assert!(detail.contains(word), "{what}: {detail:?} lacks {word:?}");
        match status {
            422 if word.starts_with("more than") => {
                assert_eq!(p["type"], "urn:winged:problem:too-many-features", "{what}")
            }
            422 => assert_eq!(p["type"], "urn:winged:problem:invalid-query", "{what}"),
            _ => {}
        }
    }
    assert_eq!(revision(&s), rev, "refused queries change nothing");
    let a = s.get("/v1/spatial/sphere?x=1&y=1&z=1&r=0.5").ok();
    assert_eq!(a["revision"], rev);
    assert_eq!(a["bodies"].as_array().map(Vec::len), Some(1));
    // A max_features above the server's maximum is taken as the maximum.
    let big = s
        .post(
            "/v1/spatial/sphere",
            &json!({"center": [1, 1, 1], "radius": 0.5, "max_features": 1_000_000_000_000u64}),
        )
        .ok();
    assert_eq!(big, a);
}

#[test]
fn concurrent_queries_see_each_revision_as_it_was() {
    use std::collections::BTreeMap;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

    let s = TestServer::start();
    let a = add_box(&s, "a", [0.0; 3]);
    // Where a is at each revision from its creation on: x = 0 or x = 10.
    let mut at: BTreeMap<u64, f64> = BTreeMap::new();
    at.insert(revision(&s), 0.0);
    let done = AtomicBool::new(false);
    let answers = AtomicUsize::new(0);
    let url = s.url("/v1/spatial/sphere?x=0&y=0&z=0&r=0.5&detail=bodies");
    let seen: Vec<(u64, bool, String)> = std::thread::scope(|scope| {
        let askers: Vec<_> = (0..3)
            .map(|_| {
                let agent = s.agent();
                let (url, done, answers) = (&url, &done, &answers);
                scope.spawn(move || {
                    let mut seen = Vec::new();
                    while !done.load(Ordering::Relaxed) {
                        let mut res = agent.get(url).call().expect("an answer");
                        assert_eq!(res.status(), 200);
                        let etag = res
                            .headers()
                            .get("etag")
                            .and_then(|v| v.to_str().ok())
                            .unwrap_or_default()
                            .to_owned();
                        let v: Value = res.body_mut().read_json().expect("JSON");
                        let rev = v["revision"].as_u64().expect("a revision");
                        let found = !v["bodies"].as_array().expect("bodies").is_empty();
                        assert_eq!(etag, format!("\"{rev}\""));
                        seen.push((rev, found, v.to_string()));
                        answers.fetch_add(1, Ordering::Relaxed);
                    }
                    seen
                })
            })
            .collect();
        // The writes begin once every asker is under way (on a busy machine the thirty
        // writes could otherwise all be over before the first answer).
        let start = std::time::Instant::now();
        while answers.load(Ordering::Relaxed) < 3 {
            assert!(
                start.elapsed() < std::time::Duration::from_secs(30),
                "no answers"
            );
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        for k in 1..=30 {
            let x = if k % 2 == 1 { 10.0 } else { 0.0 };
            let r = s.patch(
                &format!("/v1/bodies/{a}"),
                &json!({"pose": {"position": [x, 0, 0]}}),
            );
            at.insert(r.ok()["revision"].as_u64().expect("a revision"), x);
        }
        done.store(true, Ordering::Relaxed);
        askers
            .into_iter()
            .flat_map(|h| h.join().expect("an asker"))
            .collect()
    });
    assert!(!seen.is_empty());
    for (rev, found, answer) in &seen {
        let x = at
            .get(rev)
            .unwrap_or_else(|| panic!("revision {rev} is no write's: {answer}"));
        assert_eq!(
            *found,
            *x == 0.0,
            "at revision {rev} a is at x = {x}: {answer}"
        );
    }
    let last = *at.keys().last().expect("revisions");
    let now = s
        .get("/v1/spatial/sphere?x=0&y=0&z=0&r=0.5&detail=bodies")
        .ok();
    assert_eq!(now["revision"], last);
    assert_eq!(ids(&now["bodies"]), vec![a]);
}

/// Answers larger than what is computed on the async threads (thousands of faces, or
/// hundreds of bodies) come back whole, and `max_features` still refuses what is over it.
#[test]
fn large_answers_are_whole_and_limits_still_refuse() {
    let s = TestServer::start();
    let sphere = json!({"shape": {"type": "sphere", "radius": 2.0, "segments": 64, "rings": 40}});
    s.post("/v1/bodies", &sphere).ok();
    let mut boxes = Vec::new();
    for i in 0..300 {
        boxes.push(add_box(
            &s,
            &format!("b{i}"),
            [10.0 + 3.0 * (i % 20) as f64, 3.0 * (i / 20) as f64, 0.0],
        ));
    }
    // Every face, edge and vertex of the sphere body: over 2,560 faces.
    let all = s.get("/v1/spatial/sphere?x=0&y=0&z=0&r=3").ok();
    let faces = all["bodies"][0]["faces"].as_array().expect("faces").len();
    assert_eq!(faces, 64 * 40);
    // 300 boxes at bodies detail.
    let many = s
        .get("/v1/spatial/box?min_x=5&min_y=-5&min_z=-5&max_x=80&max_y=60&max_z=5&detail=bodies")
        .ok();
    assert_eq!(ids(&many["bodies"]), boxes);
    let refused = s
        .get("/v1/spatial/sphere?x=0&y=0&z=0&r=3&max_features=100")
        .problem(422);
    assert_eq!(refused["type"], "urn:winged:problem:too-many-features");
}
