//! Mesh files over real HTTP: imports (`POST /v1/bodies/import` with the file as the
//! body, `POST /v1/bodies` with a base64 `mesh` shape), exports (`GET
//! /v1/bodies/{id}/mesh`, `GET /v1/world/mesh`), round trips, and refusals that leave the
//! world unchanged.
//!
//! Every file exported here is also written, with the volume winged reports, to
//! `$CARGO_TARGET_TMPDIR/mesh-exports/`, where CI's independent readers (trimesh and
//! the Khronos glTF Validator, `bench/mesh/readers.sh`) check them.

#[path = "support/http.rs"]
mod support;

use std::path::PathBuf;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as BASE64;
use glam::DQuat;
use serde_json::{Value, json};
use support::TestServer;

/// The directory the exports are written to for CI's readers.
fn exports_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mesh-exports");
    std::fs::create_dir_all(&dir).expect("the exports directory");
    dir
}

/// Writes an exported file and its expected volume for the independent readers.
fn keep(name: &str, bytes: &[u8], volume: f64) {
    let dir = exports_dir();
    std::fs::write(dir.join(name), bytes).expect("an export");
    std::fs::write(dir.join(format!("{name}.volume")), format!("{volume:e}\n")).expect("a volume");
}

/// A binary STL of the triangles.
fn stl(tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut out = vec![0u8; 80];
    out.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in tris {
        out.extend_from_slice(&[0u8; 12]);
        for v in t {
            for c in v {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    out
}

/// A box from `lo` to `hi` as 12 triangles, counter-clockwise seen from outside.
fn box_stl(lo: [f32; 3], hi: [f32; 3]) -> Vec<u8> {
    let c = |i: usize| {
        [
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let tris: Vec<[[f32; 3]; 3]> = quads
        .iter()
        .flat_map(|q| [[c(q[0]), c(q[1]), c(q[2])], [c(q[0]), c(q[2]), c(q[3])]])
        .collect();
    stl(&tris)
}

fn post_file(s: &TestServer, query: &str, bytes: &[u8]) -> support::Reply {
    s.post_raw(
        &format!("/v1/bodies/import?{query}"),
        "application/octet-stream",
        bytes,
    )
}

fn revision(s: &TestServer) -> u64 {
    s.get("/v1/world").ok()["revision"]
        .as_u64()
        .expect("a revision")
}

/// The topology dump's vertex loci (as bits, sorted: OBJ readers number vertices in the
/// order faces first use them) and faces in order, each a ring of loci started at its
/// least locus.
fn geometry(s: &TestServer, id: u64) -> (Vec<[u64; 3]>, Vec<Vec<[u64; 3]>>) {
    let t = s.get(&format!("/v1/bodies/{id}/topology")).ok();
    let mut at = std::collections::HashMap::new();
    let mut loci = Vec::new();
    for v in t["vertices"].as_array().expect("vertices") {
        let p: Vec<u64> = v["position"]
            .as_array()
            .expect("a position")
            .iter()
            .map(|c| c.as_f64().expect("a number").to_bits())
            .collect();
        let p = [p[0], p[1], p[2]];
        at.insert(v["id"].as_u64().expect("an id"), p);
        loci.push(p);
    }
    let faces = t["faces"]
        .as_array()
        .expect("faces")
        .iter()
        .map(|f| {
            let mut ring: Vec<[u64; 3]> = f["vertices"]
                .as_array()
                .expect("a ring")
                .iter()
                .map(|v| at[&v.as_u64().expect("an id")])
                .collect();
            let least = (0..ring.len()).min_by_key(|&k| ring[k]).unwrap_or(0);
            ring.rotate_left(least);
            ring
        })
        .collect();
    loci.sort_unstable();
    (loci, faces)
}

#[test]
fn a_twelve_triangle_stl_box_is_a_body_of_six_faces() {
    let s = TestServer::start();
    let r = post_file(
        &s,
        "format=stl&name=crate",
        &box_stl([0.0; 3], [0.4, 0.3, 0.2]),
    );
    assert_eq!(r.status, 201, "{}", r.text);
    let a = r.json();
    let b = &a["bodies"][0];
    assert_eq!(a["bodies"].as_array().map(Vec::len), Some(1));
    assert_eq!(b["name"], "crate");
    assert_eq!(b["faces"], 6);
    assert_eq!(b["edges"], 12);
    assert_eq!(b["vertices"], 8);
    assert_eq!(b["faces_read"], 12);
    let v = b["volume"].as_f64().expect("a volume");
    assert!((v - 0.024).abs() < 1e-7, "volume {v}");
    let got = s.get(&format!("/v1/bodies/{}", a["id"])).ok();
    assert_eq!(got["name"], "crate");
    // Without merging, the twelve triangles stay.
    let r = post_file(
        &s,
        "format=stl&name=tri&merge_coplanar=false&unit=mm",
        &box_stl([0.0; 3], [400.0, 300.0, 200.0]),
    );
    let b = &r.ok()["bodies"][0];
    assert_eq!(b["faces"], 12);
    assert!((b["volume"].as_f64().expect("a volume") - 0.024).abs() < 1e-9);
}

#[test]
fn a_base64_mesh_shape_takes_the_usual_fields() {
    let s = TestServer::start();
    let holder = s
        .post(
            "/v1/bodies",
            &json!({"name": "table", "shape": {"type": "box", "size": [1, 1, 0.1]}}),
        )
        .ok()["id"]
        .as_u64()
        .expect("an id");
    let off = "OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
    let r = s.post(
        "/v1/bodies",
        &json!({
            "name": "wedge",
            "parent": holder,
            "pose": {"position": [0.1, 0.2, 0.3]},
            "color": "#ff8000",
            "shape": {"type": "mesh", "format": "off", "data": BASE64.encode(off)},
        }),
    );
    assert_eq!(r.status, 201, "{}", r.text);
    let id = r.json()["id"].as_u64().expect("an id");
    let body = s.get(&format!("/v1/bodies/{id}")).ok();
    assert_eq!(body["parent"], holder);
    assert_eq!(body["color"], "#ff8000");
    assert_eq!(body["pose"]["position"], json!([0.1, 0.2, 0.3]));
    assert_eq!(body["euler"]["F"], 4);
}

#[test]
fn polygon_formats_round_trip_bit_for_bit() {
    let s = TestServer::start();
    // An L-shaped prism (a concave face), turned and moved so that coordinates are not
    // round numbers, and a sphere.
    let made = [
        s.post(
            "/v1/bodies",
            &json!({"name": "ell", "pose": {"position": [0.3, -1.7, 0.05],
                "rotation": [0.1, 0.2, 0.3, 0.9273618495495703]},
                "shape": {"type": "prism", "height": 0.37,
                "polygon": [[0, 0], [0.7, 0], [0.7, 0.1], [0.13, 0.1], [0.13, 0.5], [0, 0.5]]}}),
        )
        .ok(),
        s.post(
            "/v1/bodies",
            &json!({"name": "ball", "pose": {"position": [1.1, 0.2, 0.3]},
                "shape": {"type": "sphere", "radius": 0.21, "segments": 12, "rings": 7}}),
        )
        .ok(),
    ];
    for m in &made {
        let id = m["id"].as_u64().expect("an id");
        let body = s.get(&format!("/v1/bodies/{id}")).ok();
        let name = body["name"].as_str().expect("a name").to_string();
        let volume = body["volume"].as_f64().expect("a volume");
        for format in ["obj", "ply", "off"] {
            for frame in ["body", "world"] {
                let r = s.get(&format!(
                    "/v1/bodies/{id}/mesh?format={format}&frame={frame}"
                ));
                assert_eq!(r.status, 200, "{}", r.text);
                assert!(
                    r.header("content-disposition")
                        .contains(&format!("{name}.{format}"))
                );
                keep(&format!("{name}-{frame}.{format}"), &r.bytes, volume);
                let back = post_file(
                    &s,
                    &format!("format={format}&merge_coplanar=false&name={name}-{format}-{frame}"),
                    &r.bytes,
                );
                assert_eq!(back.status, 201, "{format} {frame}: {}", back.text);
                let back_id = back.json()["id"].as_u64().expect("an id");
                if frame == "body" {
                    assert_eq!(
                        geometry(&s, back_id),
                        geometry(&s, id),
                        "{name} through {format}"
                    );
                }
                let v = s.get(&format!("/v1/bodies/{back_id}")).ok()["volume"]
                    .as_f64()
                    .expect("a volume");
                assert!(
                    (v - volume).abs() <= 1e-12 * volume.abs().max(1.0),
                    "{format} {frame}: {v} vs {volume}"
                );
            }
        }
        // Merging coplanar faces changes nothing on a body without coplanar neighbours.
        let r = s.get(&format!("/v1/bodies/{id}/mesh?format=off&frame=body"));
        let back = post_file(&s, &format!("format=off&name={name}-merged"), &r.bytes).ok();
        assert_eq!(
            geometry(&s, back["id"].as_u64().expect("an id")),
            geometry(&s, id)
        );
    }
}

#[test]
fn triangulated_formats_keep_the_volume() {
    let s = TestServer::start();
    let torus = json!({"name": "torus", "shape": {"type": "torus", "major_radius": 0.3,
        "minor_radius": 0.1, "segments": 16, "rings": 8}});
    // A concave face: its triangles come from the ear clipper, not a fan.
    let ell = json!({"name": "ell", "pose": {"position": [0.5, 0.25, -1]},
        "shape": {"type": "prism", "height": 0.2,
        "polygon": [[0, 0], [0.7, 0], [0.7, 0.1], [0.13, 0.1], [0.13, 0.5], [0, 0.5]]}});
    for (body, faces) in [(torus, 128), (ell, 8)] {
        let id = s.post("/v1/bodies", &body).ok()["id"]
            .as_u64()
            .expect("an id");
        let name = body["name"].as_str().expect("a name");
        let volume = s.get(&format!("/v1/bodies/{id}")).ok()["volume"]
            .as_f64()
            .expect("a volume");
        for format in ["stl", "glb", "3mf"] {
            let r = s.get(&format!("/v1/bodies/{id}/mesh?format={format}"));
            assert_eq!(r.status, 200, "{format}: {}", r.text);
            keep(&format!("{name}.{format}"), &r.bytes, volume);
            let back = post_file(
                &s,
                &format!("format={format}&name={name}-{format}"),
                &r.bytes,
            );
            assert_eq!(back.status, 201, "{format}: {}", back.text);
            let b = &back.json()["bodies"][0];
            let v = b["volume"].as_f64().expect("a volume");
            assert!(
                (v - volume).abs() < 1e-4 * volume,
                "{format}: {v} vs {volume}"
            );
            // The faces were cut into triangles for the file and merge back.
            assert_eq!(b["faces"], faces, "{name}.{format}");
        }
    }
}

#[test]
fn the_world_as_glb_keeps_the_parts_tree_and_world_poses() {
    let s = TestServer::start();
    let q = DQuat::from_rotation_z(0.4) * DQuat::from_rotation_x(0.2);
    let base = s
        .post(
            "/v1/bodies",
            &json!({"name": "base", "color": "#3366cc",
                "pose": {"position": [1, 2, 0.5], "rotation": q.to_array()},
                "shape": {"type": "box", "size": [1, 0.6, 0.2]}}),
        )
        .ok()["id"]
        .as_u64()
        .expect("an id");
    let arm = s
        .post(
            "/v1/bodies",
            &json!({"name": "arm", "parent": base,
                "pose": {"position": [0.2, 0, 0.3], "rotation": DQuat::from_rotation_y(0.5).to_array()},
                "shape": {"type": "cylinder", "radius": 0.05, "height": 0.5, "segments": 10}}),
        )
        .ok()["id"]
        .as_u64()
        .expect("an id");
    s.post(
        "/v1/bodies",
        &json!({"name": "gripper", "parent": arm, "pose": {"position": [0, 0, 0.3]},
            "shape": {"type": "tetrahedron", "radius": 0.05}}),
    )
    .ok();
    s.put(
        "/v1/cameras/overhead",
        &support::camera_json(&support::demo_camera()),
    )
    .ok();
    let r = s.get("/v1/world/mesh?format=glb");
    assert_eq!(r.status, 200, "{}", r.text);
    assert_eq!(r.content_type, "model/gltf-binary");
    assert_eq!(&r.bytes[..4], b"glTF");
    let world_before: Vec<Value> = ["base", "arm", "gripper"]
        .iter()
        .map(|n| s.get(&format!("/v1/bodies?name={n}")).ok()["bodies"][0].clone())
        .collect();
    let total: f64 = world_before
        .iter()
        .map(|b| b["volume"].as_f64().expect("a volume"))
        .sum();
    keep("world.glb", &r.bytes, total);
    // Into an empty world: the same tree, the same world poses (f32 in the file).
    let t = TestServer::start();
    let back = post_file(&t, "format=glb", &r.bytes);
    assert_eq!(back.status, 201, "{}", back.text);
    let bodies = back.json()["bodies"].as_array().expect("bodies").clone();
    assert_eq!(bodies.len(), 3);
    for before in &world_before {
        let name = before["name"].as_str().expect("a name");
        let after = t.get(&format!("/v1/bodies?name={name}")).ok()["bodies"][0].clone();
        assert_eq!(after["name"], name);
        let parent_name = |srv: &TestServer, b: &Value| {
            let p = b["parent"].as_u64().expect("a parent");
            srv.get(&format!("/v1/bodies/{p}")).json()["name"].clone()
        };
        assert_eq!(
            parent_name(&t, &after),
            parent_name(&s, before),
            "{name}'s parent"
        );
        let (p0, q0) = support::pose_of(&before["world_pose"]);
        let (p1, q1) = support::pose_of(&after["world_pose"]);
        assert!(p0.distance(p1) < 1e-6, "{name}: {p0} vs {p1}");
        assert!(q0.dot(q1).abs() > 1.0 - 1e-9, "{name}: {q0} vs {q1}");
        let (v0, v1) = (
            before["volume"].as_f64().expect("a volume"),
            after["volume"].as_f64().expect("a volume"),
        );
        assert!((v0 - v1).abs() < 1e-4 * v0, "{name}: {v0} vs {v1}");
    }
    let base_after = t.get("/v1/bodies?name=base").ok()["bodies"][0].clone();
    assert_eq!(base_after["color"], "#3366cc");
}

#[test]
fn bad_files_are_refused_and_the_world_is_unchanged() {
    let s = TestServer::start();
    s.post(
        "/v1/bodies",
        &json!({"name": "keep", "shape": {"type": "box", "size": [1, 1, 1]}}),
    )
    .ok();
    let before = revision(&s);
    let open_off = "OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n";
    let p = post_file(&s, "format=off", open_off.as_bytes()).problem(422);
    assert_eq!(p["defect"], "open");
    assert_eq!(
        p["where"]["vertices"].as_array().map(Vec::len),
        Some(2),
        "{p}"
    );
    let nan = "OFF\n4 4 6\n0 0 0\n1 0 0\n0 nan 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
    let p = post_file(&s, "format=off", nan.as_bytes()).problem(422);
    assert_eq!(p["defect"], "not-finite", "{p}");
    assert_eq!(p["where"]["vertices"], json!([2]));
    // A broken binary STL, a broken GLB, a 3MF that is not a zip, an OBJ with a bad
    // index, PLY garbage.
    let mut short = box_stl([0.0; 3], [1.0; 3]);
    short.truncate(300);
    post_file(&s, "format=stl", &short).problem(422);
    post_file(
        &s,
        "format=glb",
        b"glTF\x02\x00\x00\x00\x10\x00\x00\x00garbage",
    )
    .problem(422);
    post_file(&s, "format=3mf", b"PK\x03\x04 not really").problem(422);
    post_file(&s, "format=obj", b"v 0 0 0\nf 1 2 3\n").problem(422);
    post_file(
        &s,
        "format=ply",
        b"ply\nformat ascii 1.0\nelement vertex 9\n",
    )
    .problem(422);
    // Unknown format, unknown option, bad option values.
    post_file(&s, "format=dxf", b"0\nSECTION\n").problem(400);
    post_file(&s, "format=stl&colour=red", &box_stl([0.0; 3], [1.0; 3])).problem(400);
    post_file(&s, "format=stl&weld=-1", &box_stl([0.0; 3], [1.0; 3])).problem(400);
    // A name already taken, and a parent that does not exist.
    post_file(&s, "format=stl&name=keep", &box_stl([0.0; 3], [1.0; 3])).problem(409);
    post_file(&s, "format=stl&parent=999999", &box_stl([0.0; 3], [1.0; 3])).problem(404);
    // Bad base64 in JSON.
    s.post(
        "/v1/bodies",
        &json!({"shape": {"type": "mesh", "format": "stl", "data": "%%%"}}),
    )
    .problem(400);
    assert_eq!(revision(&s), before, "refusals change nothing");
    // Exports of what is not there.
    s.get("/v1/bodies/999999/mesh?format=obj").problem(404);
    s.get("/v1/bodies/1/mesh?format=obj").problem(404);
    s.get("/v1/bodies/2/mesh?format=gltf").problem(400);
    s.get("/v1/world/mesh?format=stl").problem(400);
    assert_eq!(s.get("/healthz").status, 200);
}

#[test]
fn a_file_over_the_body_size_limit_is_413() {
    let s = TestServer::start();
    // A binary STL header that counts more triangles than any body may have.
    let mut file = vec![0u8; 80];
    file.extend_from_slice(&u32::MAX.to_le_bytes());
    file.extend_from_slice(&[0u8; 50]);
    post_file(&s, "format=stl", &file).problem(413);
}
