use base64::Engine;
use glam::{DQuat, DVec3};
use serde_json::{Value, json};

use super::*;
use crate::mesh::RawObject;
use crate::model::camera::{Camera, Intrinsics};
use crate::model::solids::box_solid;
use crate::model::{Color, World};

// ------------------------------------------------------------------ helpers

/// The unit cube's corners and its twelve triangles, counter-clockwise from outside.
const CUBE: [[f32; 3]; 8] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [1.0, 1.0, 1.0],
    [0.0, 1.0, 1.0],
];
const CUBE_TRIANGLES: [[u32; 3]; 12] = [
    [0, 2, 1],
    [0, 3, 2],
    [4, 5, 6],
    [4, 6, 7],
    [0, 1, 5],
    [0, 5, 4],
    [3, 7, 6],
    [3, 6, 2],
    [0, 4, 7],
    [0, 7, 3],
    [1, 2, 6],
    [1, 6, 5],
];

/// The bytes of the cube's positions then its u32 indices.
fn cube_bytes() -> Vec<u8> {
    let mut bytes = Vec::new();
    for p in CUBE.iter().flatten() {
        bytes.extend_from_slice(&p.to_le_bytes());
    }
    for i in CUBE_TRIANGLES.iter().flatten() {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    bytes
}

/// A glTF document holding the cube as mesh 0 ("cube": accessor 0 positions, accessor 1
/// indices, one data-URI buffer), with `nodes` and one scene of `roots`.
fn cube_doc(nodes: Value, roots: Value) -> Value {
    let bytes = cube_bytes();
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bytes)
    );
    json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bytes.len(), "uri": uri}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 96, "target": 34962},
            {"buffer": 0, "byteOffset": 96, "byteLength": 144, "target": 34963}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]},
            {"bufferView": 1, "componentType": 5125, "count": 36, "type": "SCALAR"}
        ],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.2, 0.1, 1.0]}}],
        "meshes": [{"name": "cube", "primitives": [
            {"attributes": {"POSITION": 0}, "indices": 1, "material": 0}
        ]}],
        "nodes": nodes,
        "scenes": [{"nodes": roots}],
        "scene": 0
    })
}

fn bytes_of(doc: &Value) -> Vec<u8> {
    serde_json::to_vec(doc).expect("json")
}

fn read_default(bytes: &[u8]) -> Result<RawScene, ImportError> {
    read(bytes, &ImportOptions::default())
}

/// Each object's world pose, composed down its parents.
fn world_poses(scene: &RawScene) -> Vec<Pose> {
    let mut out: Vec<Pose> = Vec::new();
    for o in &scene.objects {
        let w = match o.parent {
            Some(p) => {
                assert!(p < out.len(), "a parent comes before its parts");
                out[p].compose(&o.pose)
            }
            None => o.pose,
        };
        out.push(w);
    }
    out
}

/// The signed volume of an object's triangles, in its own frame.
fn volume(o: &RawObject) -> f64 {
    o.faces
        .iter()
        .map(|f| {
            let p = |k: usize| o.positions[f[k] as usize];
            p(0).dot(p(1).cross(p(2))) / 6.0
        })
        .sum()
}

/// Whether a pose is rigid: a unit quaternion, finite.
fn is_rigid(p: &Pose) -> bool {
    p.is_finite() && (p.rotation.length() - 1.0).abs() < 1e-12
}

fn parse_detail(e: &ImportError) -> &str {
    match e {
        ImportError::Parse { format, detail } => {
            assert_eq!(*format, "gltf");
            detail
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
}

/// A world with a posed, coloured box "arm" holding a posed part "hand", an unnamed box
/// beside it, and a camera.
fn sample_world() -> (World, BodyId, BodyId, BodyId) {
    let mut w = World::new();
    let root = w.root();
    let arm_pose = Pose::new(DVec3::new(1.0, 2.0, 3.0), DQuat::from_rotation_z(0.7)).unwrap();
    let arm = w
        .insert_colored_with(
            Some("arm"),
            root,
            arm_pose,
            Some(Color([200, 30, 90])),
            |s| box_solid(s, DVec3::new(1.0, 2.0, 3.0)),
        )
        .expect("arm");
    let hand_pose = Pose::new(
        DVec3::new(0.5, -0.25, 2.0),
        DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.2, 1.1),
    )
    .unwrap();
    let hand = w
        .insert_with(Some("hand"), arm, hand_pose, |s| {
            box_solid(s, DVec3::new(0.5, 0.5, 0.25))
        })
        .expect("hand");
    let other = w
        .insert_with(
            None,
            root,
            Pose::from_translation(DVec3::new(-4.0, 0.0, 0.0)),
            |s| box_solid(s, DVec3::new(2.0, 2.0, 2.0)),
        )
        .expect("other");
    let camera = Camera::look_at(
        DVec3::new(5.0, -6.0, 4.0),
        DVec3::ZERO,
        DVec3::Z,
        Intrinsics::new(640, 480, 500.0, 510.0, 320.0, 240.0).unwrap(),
    )
    .unwrap();
    w.set_camera("main", camera).expect("camera");
    (w, arm, hand, other)
}

fn solid_of(w: &World, b: BodyId) -> Solid {
    Solid::of(w, b, crate::mesh::write::Frame::Body).expect("solid")
}

// ------------------------------------------------------------------ writing and reading back

#[test]
fn a_solid_round_trips() {
    let (w, arm, _, _) = sample_world();
    let solid = solid_of(&w, arm);
    let glb = write_solid(&solid).expect("writes");
    assert_eq!(&glb[..4], b"glTF");
    assert_eq!(
        u32::from_le_bytes(glb[8..12].try_into().unwrap()) as usize,
        glb.len()
    );
    assert_eq!(glb.len() % 4, 0);
    ::gltf::Gltf::from_slice(&glb).expect("the gltf crate accepts it");
    let scene = read_default(&glb).expect("reads");
    assert_eq!(scene.objects.len(), 1);
    let o = &scene.objects[0];
    assert_eq!(o.name.as_deref(), Some("arm"));
    assert_eq!(o.parent, None);
    assert_eq!(o.pose, Pose::IDENTITY);
    assert_eq!(o.first_vertex, None);
    let expected: Vec<DVec3> = solid
        .positions
        .iter()
        .map(|p| p.as_vec3().as_dvec3())
        .collect();
    assert_eq!(
        o.positions, expected,
        "vertices shared, in order, f32-rounded"
    );
    let triangles = solid.triangles();
    assert_eq!(o.faces.len(), triangles.len());
    for (f, t) in o.faces.iter().zip(&triangles) {
        assert_eq!(f, t);
    }
    let c = o.color.expect("a colour");
    for k in 0..3 {
        assert!((i32::from(c.0[k]) - i32::from(solid.color.0[k])).abs() <= 1);
    }
    assert!(volume(o) > 0.0);
}

#[test]
fn the_glb_layout_is_as_the_spec_asks() {
    let (w, arm, _, _) = sample_world();
    let glb = write_solid(&solid_of(&w, arm)).expect("writes");
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    assert_eq!(&glb[16..20], b"JSON");
    assert_eq!(json_len % 4, 0);
    let json_chunk = &glb[20..20 + json_len];
    let doc: Value = serde_json::from_slice(json_chunk).expect("json (space padded)");
    let bin_at = 20 + json_len;
    let bin_len = u32::from_le_bytes(glb[bin_at..bin_at + 4].try_into().unwrap()) as usize;
    assert_eq!(&glb[bin_at + 4..bin_at + 8], b"BIN\0");
    assert_eq!(bin_len % 4, 0);
    assert_eq!(bin_at + 8 + bin_len, glb.len());
    assert_eq!(doc["asset"]["version"], "2.0");
    assert_eq!(doc["asset"]["generator"], "winged");
    let byte_length = doc["buffers"][0]["byteLength"].as_u64().unwrap() as usize;
    assert!(byte_length <= bin_len && bin_len - byte_length < 4);
    for view in doc["bufferViews"].as_array().unwrap() {
        assert_eq!(view["byteOffset"].as_u64().unwrap_or(0) % 4, 0);
    }
    assert_eq!(doc["bufferViews"][1]["target"], 34963);
    assert_eq!(doc["accessors"][0]["type"], "VEC3");
    assert_eq!(doc["accessors"][0]["componentType"], 5126);
    assert!(doc["accessors"][0]["min"].is_array() && doc["accessors"][0]["max"].is_array());
    assert_eq!(doc["accessors"][1]["componentType"], 5125);
    let material = &doc["materials"][0];
    assert_eq!(material["pbrMetallicRoughness"]["metallicFactor"], 0.0);
    assert!(material["doubleSided"].as_bool() != Some(true));
}

#[test]
fn a_world_round_trips_with_its_hierarchy_poses_names_and_colours() {
    let (w, arm, hand, other) = sample_world();
    let glb = write_world(&w).expect("writes");
    ::gltf::Gltf::from_slice(&glb).expect("the gltf crate accepts it");
    let scene = read_default(&glb).expect("reads");
    assert_eq!(scene.objects.len(), 3, "the camera node has no mesh");
    let names: Vec<_> = scene.objects.iter().map(|o| o.name.clone()).collect();
    let other_name = format!("body-{}", other.get());
    assert_eq!(
        names,
        [
            Some("arm".to_owned()),
            Some("hand".to_owned()),
            Some(other_name)
        ]
    );
    assert_eq!(scene.objects[0].parent, None);
    assert_eq!(scene.objects[1].parent, Some(0));
    assert_eq!(scene.objects[2].parent, None);
    let poses = world_poses(&scene);
    for (k, b) in [arm, hand, other].into_iter().enumerate() {
        let want = w.world_pose(b).unwrap();
        assert!(
            poses[k].approx_eq(&want, 1e-6, 1e-6),
            "body {k}: {:?} vs {want:?}",
            poses[k]
        );
        let solid = solid_of(&w, b);
        let o = &scene.objects[k];
        assert_eq!(o.faces.len(), solid.triangles().len());
        assert_eq!(o.positions.len(), solid.positions.len());
        for (p, q) in o.positions.iter().zip(&solid.positions) {
            assert_eq!(*p, q.as_vec3().as_dvec3());
        }
        let c = o.color.expect("colour");
        for ch in 0..3 {
            assert!((i32::from(c.0[ch]) - i32::from(solid.color.0[ch])).abs() <= 1);
        }
        assert!(volume(o) > 0.0);
    }
    assert_eq!(scene.objects[0].color, Some(Color([200, 30, 90])));
}

#[test]
fn cameras_are_written_as_perspective_cameras() {
    let (w, _, _, _) = sample_world();
    let glb = write_world(&w).expect("writes");
    let gltf = ::gltf::Gltf::from_slice(&glb).expect("valid");
    let root = gltf.document.as_json();
    assert_eq!(root.cameras.len(), 1);
    let p = root.cameras[0].perspective.as_ref().expect("perspective");
    let want = 2.0 * (240.0f64 / 510.0).atan();
    assert!((f64::from(p.yfov) - want).abs() < 1e-6);
    assert!((f64::from(p.aspect_ratio.unwrap()) - 640.0 / 480.0).abs() < 1e-6);
    assert_eq!(p.znear, 0.05);
    assert!(p.zfar.is_none());
    let node = root
        .nodes
        .iter()
        .find(|n| n.camera.is_some())
        .expect("a camera node");
    assert_eq!(node.name.as_deref(), Some("main"));
    let camera = w.camera("main").unwrap();
    let [x, y, z, qw] = node.rotation.unwrap().0.map(f64::from);
    let q = DQuat::from_xyzw(x, y, z, qw);
    // glTF's camera looks down its −z: winged's view direction.
    assert!((q * -DVec3::Z).distance(camera.view_direction()) < 1e-6);
    let t = node.translation.unwrap().map(f64::from);
    assert!(DVec3::from_array(t).distance(camera.position()) < 1e-5);
    let scene = &root.scenes[0];
    assert_eq!(scene.nodes.len(), 3, "two top-level bodies and the camera");
}

#[test]
fn an_empty_world_is_a_valid_glb_without_nodes() {
    let glb = write_world(&World::new()).expect("writes");
    let gltf = ::gltf::Gltf::from_slice(&glb).expect("valid");
    assert!(gltf.blob.is_none());
    let root = gltf.document.as_json();
    assert!(root.buffers.is_empty());
    assert!(root.nodes.is_empty());
    assert!(root.scenes.iter().all(|s| s.nodes.is_empty()));
    let scene = read_default(&glb).expect("reads");
    assert!(scene.objects.is_empty());
}

#[test]
fn a_body_without_faces_is_a_node_without_a_mesh_and_its_parts_fold_up() {
    let mut w = World::new();
    let (seed, _, _) = w.mkbfv(DVec3::new(1.0, 0.0, 0.0)).expect("seed");
    w.set_pose(seed, Pose::from_translation(DVec3::new(0.0, 3.0, 0.0)))
        .expect("pose");
    let part = w
        .insert_with(Some("part"), seed, Pose::from_translation(DVec3::X), |s| {
            box_solid(s, DVec3::ONE)
        })
        .expect("part");
    let glb = write_world(&w).expect("writes");
    ::gltf::Gltf::from_slice(&glb).expect("valid");
    let single = write_solid(&solid_of(&w, seed)).expect("writes a meshless node");
    ::gltf::Gltf::from_slice(&single).expect("valid");
    let scene = read_default(&glb).expect("reads");
    assert_eq!(scene.objects.len(), 1);
    assert_eq!(scene.objects[0].parent, None);
    assert!(
        scene.objects[0]
            .pose
            .approx_eq(&w.world_pose(part).unwrap(), 1e-9, 1e-9)
    );
}

// ------------------------------------------------------------------ hand-written files

#[test]
fn a_two_level_hierarchy_reads_with_rigid_poses_and_scaled_positions() {
    let rotation = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
    let doc = cube_doc(
        json!([
            {"name": "parent", "mesh": 0, "translation": [1.0, 2.0, 3.0],
             "rotation": [rotation.x, rotation.y, rotation.z, rotation.w], "children": [1]},
            {"name": "child", "mesh": 0, "translation": [0.0, 0.0, 5.0], "scale": [2.0, 2.0, 2.0]}
        ]),
        json!([0]),
    );
    let scene = read_default(&bytes_of(&doc)).expect("reads");
    assert_eq!(scene.objects.len(), 2);
    let (parent, child) = (&scene.objects[0], &scene.objects[1]);
    assert_eq!(parent.name.as_deref(), Some("parent"));
    assert_eq!(child.name.as_deref(), Some("child"));
    assert_eq!(parent.parent, None);
    assert_eq!(child.parent, Some(0));
    assert!(is_rigid(&parent.pose) && is_rigid(&child.pose));
    assert!(parent.pose.approx_eq(
        &Pose::new(DVec3::new(1.0, 2.0, 3.0), rotation).unwrap(),
        1e-7,
        1e-7
    ));
    // The parent's path is rigid: its positions are the file's, untouched.
    let file: Vec<DVec3> = CUBE
        .iter()
        .map(|p| DVec3::from_array(p.map(f64::from)))
        .collect();
    assert_eq!(parent.positions, file);
    assert_eq!(
        parent.color,
        Some(Color([
            linear_to_srgb8(0.5),
            linear_to_srgb8(0.2),
            linear_to_srgb8(0.1)
        ]))
    );
    // The child: translated along the parent's z, no rotation of its own, scale 2.
    assert!(child.pose.approx_eq(
        &Pose::from_translation(DVec3::new(0.0, 0.0, 5.0)),
        1e-9,
        1e-9
    ));
    for (p, q) in child.positions.iter().zip(&file) {
        assert!(p.distance(2.0 * *q) < 1e-12);
    }
    // World positions are the file's meaning: M·v.
    let worlds = world_poses(&scene);
    let m = glam::DAffine3::from_rotation_translation(rotation, DVec3::new(1.0, 2.0, 3.0))
        * glam::DAffine3::from_scale_rotation_translation(
            DVec3::splat(2.0),
            DQuat::IDENTITY,
            DVec3::new(0.0, 0.0, 5.0),
        );
    for (p, q) in child.positions.iter().zip(&file) {
        assert!(
            worlds[1]
                .transform_point(*p)
                .distance(m.transform_point3(*q))
                < 1e-9
        );
    }
    assert!(volume(child) > 0.0);
    assert!((volume(child) - 8.0).abs() < 1e-9);
}

#[test]
fn nodes_without_meshes_fold_into_their_descendants() {
    let doc = cube_doc(
        json!([
            {"name": "group", "translation": [10.0, 0.0, 0.0], "children": [1]},
            {"mesh": 0, "translation": [0.0, 1.0, 0.0]}
        ]),
        json!([0]),
    );
    let scene = read_default(&bytes_of(&doc)).expect("reads");
    assert_eq!(scene.objects.len(), 1);
    let o = &scene.objects[0];
    assert_eq!(
        o.name.as_deref(),
        Some("cube"),
        "the mesh's name, the node having none"
    );
    assert_eq!(o.parent, None);
    assert_eq!(o.pose, Pose::from_translation(DVec3::new(10.0, 1.0, 0.0)));
}

#[test]
fn a_mirrored_node_keeps_its_faces_outward() {
    for node in [
        json!({"mesh": 0, "scale": [-1.0, 1.0, 1.0], "translation": [3.0, 0.0, 0.0]}),
        json!({"mesh": 0, "scale": [1.0, -2.0, 0.5]}),
        json!({"mesh": 0, "matrix": [0.0, 1.0, 0.0, 0.0,  1.0, 0.0, 0.0, 0.0,
                                      0.0, 0.0, 3.0, 0.0,  1.0, 2.0, 3.0, 1.0]}),
    ] {
        let doc = cube_doc(json!([node]), json!([0]));
        let scene = read_default(&bytes_of(&doc)).expect("reads");
        let o = &scene.objects[0];
        assert!(is_rigid(&o.pose));
        assert!(volume(o) > 0.0, "{node}: volume {}", volume(o));
    }
}

#[test]
fn a_matrix_node_splits_into_a_pose_and_a_scale() {
    // T · R · S with R a quarter turn about z and S = diag(2, 3, 4).
    let r = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
    let m = glam::DAffine3::from_scale_rotation_translation(
        DVec3::new(2.0, 3.0, 4.0),
        r,
        DVec3::new(1.0, -1.0, 0.5),
    );
    let cols: Vec<f64> = glam::DMat4::from(m).to_cols_array().to_vec();
    let doc = cube_doc(json!([{"mesh": 0, "matrix": cols}]), json!([0]));
    let scene = read_default(&bytes_of(&doc)).expect("reads");
    let o = &scene.objects[0];
    assert!(o.pose.approx_eq(
        &Pose::new(DVec3::new(1.0, -1.0, 0.5), r).unwrap(),
        1e-6,
        1e-6
    ));
    for (p, q) in o.positions.iter().zip(CUBE) {
        let q = DVec3::from_array(q.map(f64::from));
        assert!(p.distance(q * DVec3::new(2.0, 3.0, 4.0)) < 1e-6);
        assert!(o.pose.transform_point(*p).distance(m.transform_point3(q)) < 1e-6);
    }
}

#[test]
fn a_sheared_path_still_gives_the_files_world_positions() {
    // A non-uniform scale above a rotation: shear, decomposed by the polar decomposition.
    let r = DQuat::from_rotation_z(0.5);
    let doc = cube_doc(
        json!([
            {"scale": [1.0, 3.0, 1.0], "children": [1]},
            {"mesh": 0, "rotation": [r.x, r.y, r.z, r.w]}
        ]),
        json!([0]),
    );
    let scene = read_default(&bytes_of(&doc)).expect("reads");
    let o = &scene.objects[0];
    assert!(is_rigid(&o.pose));
    let m = glam::DAffine3::from_scale(DVec3::new(1.0, 3.0, 1.0)) * glam::DAffine3::from_quat(r);
    for (p, q) in o.positions.iter().zip(CUBE) {
        let q = DVec3::from_array(q.map(f64::from));
        assert!(o.pose.transform_point(*p).distance(m.transform_point3(q)) < 1e-6);
    }
    assert!(volume(o) > 0.0);
}

#[test]
fn strips_and_fans_are_cut_with_their_winding() {
    // A square as a strip (0, 1, 3, 2) and as a fan (0, 1, 2, 3): both counter-clockwise
    // seen from +z, like the triangle list (0, 1, 2), (0, 2, 3).
    let square: [[f32; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    for (mode, order) in [(5, [0u8, 1, 3, 2]), (6, [0u8, 1, 2, 3])] {
        let mut bytes = Vec::new();
        for p in square.iter().flatten() {
            bytes.extend_from_slice(&p.to_le_bytes());
        }
        bytes.extend_from_slice(&order);
        let uri = format!(
            "data:application/gltf-buffer;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bytes)
        );
        let doc = json!({
            "asset": {"version": "2.0"},
            "buffers": [{"byteLength": bytes.len(), "uri": uri}],
            "bufferViews": [
                {"buffer": 0, "byteLength": 48},
                {"buffer": 0, "byteOffset": 48, "byteLength": 4}
            ],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                 "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
                {"bufferView": 1, "componentType": 5121, "count": 4, "type": "SCALAR"}
            ],
            "meshes": [{"primitives": [
                {"attributes": {"POSITION": 0}, "indices": 1, "mode": mode},
                {"attributes": {"POSITION": 0}, "mode": 1}
            ]}],
            "nodes": [{"mesh": 0}]
        });
        let scene = read_default(&bytes_of(&doc)).expect("reads");
        let o = &scene.objects[0];
        assert_eq!(o.faces.len(), 2, "mode {mode}; the lines are skipped");
        for f in o.faces.iter() {
            let p = |k: usize| o.positions[f[k] as usize];
            let n = (p(1) - p(0)).cross(p(2) - p(0));
            assert!(n.z > 0.0, "mode {mode}: face {f:?} turns the wrong way");
        }
    }
}

#[test]
fn primitives_are_concatenated_and_shared_vertices_kept_once() {
    let mut doc = cube_doc(json!([{"mesh": 0}]), json!([0]));
    // The cube's triangles split over two primitives of the same POSITION accessor, and a
    // third, non-indexed one of its own: the first six triangles of the cube, by index.
    doc["accessors"] = json!([
        {"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
         "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]},
        {"bufferView": 1, "componentType": 5125, "count": 18, "type": "SCALAR"},
        {"bufferView": 1, "byteOffset": 72, "componentType": 5125, "count": 18, "type": "SCALAR"},
        {"bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3",
         "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]}
    ]);
    doc["meshes"][0]["primitives"] = json!([
        {"attributes": {"POSITION": 0}, "indices": 1},
        {"attributes": {"POSITION": 0}, "indices": 2, "material": 0},
        {"attributes": {"POSITION": 3}}
    ]);
    let scene = read_default(&bytes_of(&doc)).expect("reads");
    let o = &scene.objects[0];
    assert_eq!(o.faces.len(), 12 + 2);
    assert_eq!(o.positions.len(), 8 + 6);
    assert_eq!(
        o.color,
        Some(Color([
            linear_to_srgb8(0.5),
            linear_to_srgb8(0.2),
            linear_to_srgb8(0.1)
        ]))
    );
    for (f, t) in o.faces.iter().zip(CUBE_TRIANGLES) {
        assert_eq!(f, t);
    }
    assert_eq!(o.faces.face(12), [8, 9, 10]);
    assert_eq!(o.faces.face(13), [11, 12, 13]);
}

#[test]
fn without_a_scene_every_root_node_is_read() {
    let mut doc = cube_doc(
        json!([
            {"mesh": 0, "children": [1]},
            {"mesh": 0},
            {"mesh": 0, "translation": [5.0, 0.0, 0.0]}
        ]),
        json!([0]),
    );
    let map = doc.as_object_mut().unwrap();
    map.remove("scenes");
    map.remove("scene");
    let scene = read_default(&bytes_of(&doc)).expect("reads");
    assert_eq!(scene.objects.len(), 3);
    assert_eq!(scene.objects[1].parent, Some(0));
    assert_eq!(scene.objects[2].parent, None);
}

#[test]
fn a_sparse_accessor_is_applied() {
    let mut doc = cube_doc(json!([{"mesh": 0}]), json!([0]));
    // Vertex 6, (1, 1, 1), replaced by (1, 1, 2): its index (u8, padded to 4 bytes) at
    // byte 240, its value at byte 244.
    let bytes = {
        let mut b = cube_bytes();
        b.extend_from_slice(&[6, 0, 0, 0]);
        for c in [1.0f32, 1.0, 2.0] {
            b.extend_from_slice(&c.to_le_bytes());
        }
        b
    };
    doc["buffers"][0] = json!({
        "byteLength": bytes.len(),
        "uri": format!("data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bytes))
    });
    doc["bufferViews"].as_array_mut().unwrap().extend([
        json!({"buffer": 0, "byteOffset": 240, "byteLength": 4}),
        json!({"buffer": 0, "byteOffset": 244, "byteLength": 12}),
    ]);
    doc["accessors"][0]["sparse"] = json!({
        "count": 1,
        "indices": {"bufferView": 2, "componentType": 5121},
        "values": {"bufferView": 3}
    });
    doc["accessors"][0]["max"] = json!([1.0, 1.0, 2.0]);
    let scene = read_default(&bytes_of(&doc)).expect("reads");
    assert_eq!(scene.objects[0].positions[6], DVec3::new(1.0, 1.0, 2.0));
    assert_eq!(scene.objects[0].positions[5], DVec3::new(1.0, 0.0, 1.0));

    doc["accessors"][0]["sparse"]["count"] = json!(2);
    let e = read_default(&bytes_of(&doc)).expect_err("past the sparse views");
    assert!(parse_detail(&e).contains("sparse"), "{e}");
    doc["accessors"][0]["sparse"]["count"] = json!(1);
    let mut bytes = bytes;
    bytes[240] = 8;
    doc["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bytes)
    ));
    let e = read_default(&bytes_of(&doc)).expect_err("sparse index 8 of 8");
    assert!(parse_detail(&e).contains("sparse index 8"), "{e}");
}

// ------------------------------------------------------------------ refusals

#[test]
fn a_truncated_bin_chunk_is_refused_cleanly() {
    let (w, arm, _, _) = sample_world();
    let glb = write_solid(&solid_of(&w, arm)).expect("writes");
    // Cut short: the header's length is now past the end.
    let cut = &glb[..glb.len() - 20];
    let e = read_default(cut).expect_err("truncated");
    parse_detail(&e);
    // The header's length patched to match: the BIN chunk's own length is past the end.
    let mut patched = cut.to_vec();
    let len = patched.len() as u32;
    patched[8..12].copy_from_slice(&len.to_le_bytes());
    let e = read_default(&patched).expect_err("truncated chunk");
    parse_detail(&e);
    // The chunk's length patched too: the buffer is shorter than its byteLength.
    let json_len = u32::from_le_bytes(patched[12..16].try_into().unwrap()) as usize;
    let bin_at = 20 + json_len;
    let bin_len = (patched.len() - bin_at - 8) as u32;
    patched[bin_at..bin_at + 4].copy_from_slice(&bin_len.to_le_bytes());
    let e = read_default(&patched).expect_err("short buffer");
    assert!(parse_detail(&e).contains("buffer 0"), "{e}");
}

#[test]
fn bad_accessors_are_refused_cleanly() {
    let base = cube_doc(json!([{"mesh": 0}]), json!([0]));
    type Change = Box<dyn Fn(&mut Value)>;
    let cases: Vec<(&str, Change)> = vec![
        (
            "past its view",
            Box::new(|d| d["accessors"][0]["count"] = json!(9)),
        ),
        (
            "offset past its view",
            Box::new(|d| d["accessors"][1]["byteOffset"] = json!(4)),
        ),
        (
            "a huge count",
            Box::new(|d| d["accessors"][0]["count"] = json!(u64::MAX / 2)),
        ),
        (
            "a huge index count",
            Box::new(|d| d["accessors"][1]["count"] = json!(3_000_000_000u64)),
        ),
        (
            "positions of the wrong type",
            Box::new(|d| d["accessors"][0]["componentType"] = json!(5123)),
        ),
        (
            "positions that are VEC2",
            Box::new(|d| d["accessors"][0]["type"] = json!("VEC2")),
        ),
        (
            "float indices",
            Box::new(|d| d["accessors"][1]["componentType"] = json!(5126)),
        ),
        (
            "an index past the vertices",
            Box::new(|d| d["accessors"][0]["count"] = json!(6)),
        ),
        (
            "a view past its buffer",
            Box::new(|d| d["bufferViews"][1]["byteLength"] = json!(400)),
        ),
        (
            "an accessor that does not exist",
            Box::new(|d| d["meshes"][0]["primitives"][0]["indices"] = json!(7)),
        ),
        (
            "a POSITION that does not exist",
            Box::new(|d| d["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(7)),
        ),
        (
            "a stride shorter than the element",
            Box::new(|d| d["bufferViews"][0]["byteStride"] = json!(8)),
        ),
        (
            "an index count not a multiple of 3",
            Box::new(|d| d["accessors"][1]["count"] = json!(35)),
        ),
        (
            "a node that is its own child",
            Box::new(|d| d["nodes"][0]["children"] = json!([0])),
        ),
        (
            "a node under two parents",
            Box::new(|d| {
                d["nodes"] = json!([{"children": [2]}, {"children": [2]}, {"mesh": 0}]);
                d["scenes"][0]["nodes"] = json!([0, 1]);
            }),
        ),
        (
            "a scale of 0",
            Box::new(|d| d["nodes"][0]["scale"] = json!([1.0, 0.0, 1.0])),
        ),
        (
            "an infinite translation",
            Box::new(|d| d["nodes"][0]["translation"] = json!([1e300, 0.0, 0.0])),
        ),
        (
            "a zero quaternion",
            Box::new(|d| d["nodes"][0]["rotation"] = json!([0.0, 0.0, 0.0, 0.0])),
        ),
        (
            "a projective matrix",
            Box::new(|d| {
                d["nodes"][0]["matrix"] = json!([
                    1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0
                ])
            }),
        ),
        (
            "bad base64",
            Box::new(|d| {
                d["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,@@@")
            }),
        ),
        (
            "a buffer without a uri in JSON",
            Box::new(|d| {
                d["buffers"][0].as_object_mut().unwrap().remove("uri");
            }),
        ),
        (
            "an unknown mode",
            Box::new(|d| d["meshes"][0]["primitives"][0]["mode"] = json!(9)),
        ),
        (
            "no buffer view nor sparse",
            Box::new(|d| {
                d["accessors"][0]
                    .as_object_mut()
                    .unwrap()
                    .remove("bufferView");
            }),
        ),
    ];
    // No cap on faces: the accessors' own checks must catch the huge counts.
    let options = ImportOptions {
        max_file_faces: usize::MAX,
        ..ImportOptions::default()
    };
    for (what, change) in cases {
        let mut doc = base.clone();
        change(&mut doc);
        match read(&bytes_of(&doc), &options) {
            Err(ImportError::Parse {
                format: "gltf",
                detail,
            }) => {
                assert!(!detail.is_empty(), "{what}");
            }
            other => panic!("{what}: expected a parse error, got {other:?}"),
        }
    }
}

#[test]
fn an_external_buffer_is_unsupported_and_named() {
    let mut doc = cube_doc(json!([{"mesh": 0}]), json!([0]));
    doc["buffers"][0]["uri"] = json!("cube.bin");
    match read_default(&bytes_of(&doc)) {
        Err(ImportError::Unsupported { detail }) => {
            assert!(detail.contains("cube.bin"), "{detail}")
        }
        other => panic!("expected unsupported, got {other:?}"),
    }
    // A buffer nothing reads is not looked for.
    let mut doc = cube_doc(json!([{"mesh": 0}]), json!([0]));
    doc["buffers"]
        .as_array_mut()
        .unwrap()
        .push(json!({"byteLength": 4, "uri": "other.bin"}));
    read_default(&bytes_of(&doc)).expect("reads");
}

#[test]
fn too_many_faces_are_refused_before_reading() {
    let doc = cube_doc(
        json!([{"mesh": 0, "children": [1]}, {"mesh": 0}]),
        json!([0]),
    );
    let options = ImportOptions {
        max_file_faces: 23,
        ..ImportOptions::default()
    };
    match read(&bytes_of(&doc), &options) {
        Err(ImportError::TooLarge { what, count, limit }) => {
            assert_eq!((what, count, limit), ("faces in the file", 24, 23));
        }
        other => panic!("expected too large, got {other:?}"),
    }
    let options = ImportOptions {
        max_file_faces: 24,
        ..ImportOptions::default()
    };
    read(&bytes_of(&doc), &options).expect("24 is the limit");
}

#[test]
fn garbage_and_damaged_files_never_panic() {
    let (w, _, _, _) = sample_world();
    let glb = write_world(&w).expect("writes");
    let json_doc = bytes_of(&cube_doc(json!([{"mesh": 0}]), json!([0])));
    let mut inputs: Vec<Vec<u8>> = vec![
        Vec::new(),
        b"glTF".to_vec(),
        b"glTF\x02\0\0\0\x04\0\0\0".to_vec(),
        b"glTF\x02\0\0\0\0\0\0\0".to_vec(),
        b"glTF\x02\0\0\0\x14\0\0\0\xff\xff\xff\xffJSON".to_vec(),
        b"glTF\x01\0\0\0\x0c\0\0\0".to_vec(),
        b"{}".to_vec(),
        b"[]".to_vec(),
        b"not a file at all".to_vec(),
    ];
    for n in (0..glb.len()).step_by(7) {
        inputs.push(glb[..n].to_vec());
    }
    for n in (0..json_doc.len()).step_by(5) {
        inputs.push(json_doc[..n].to_vec());
    }
    // Deterministic byte flips of both files.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for _ in 0..400 {
        for file in [&glb, &json_doc] {
            let mut damaged = file.clone();
            for _ in 0..3 {
                let at = (next() % damaged.len() as u64) as usize;
                damaged[at] = next() as u8;
            }
            inputs.push(damaged);
        }
    }
    for input in &inputs {
        // Any answer will do, but no panic.
        let _ = read_default(input);
    }
}

#[test]
fn colours_convert_both_ways() {
    for c in 0..=255u8 {
        assert_eq!(linear_to_srgb8(srgb8_to_linear(c)), c);
    }
    assert_eq!(linear_to_srgb8(0.0), 0);
    assert_eq!(linear_to_srgb8(1.0), 255);
    assert_eq!(linear_to_srgb8(2.0), 255);
    assert_eq!(linear_to_srgb8(-1.0), 0);
    assert_eq!(linear_to_srgb8(f32::NAN), 0);
    assert_eq!(linear_to_srgb8(0.214_041_14), 128);
}

#[test]
fn a_written_world_imports_as_bodies() {
    let (w, _, _, _) = sample_world();
    let glb = write_world(&w).expect("writes");
    let imported = crate::mesh::import(crate::mesh::Format::Glb, &glb, &ImportOptions::default())
        .expect("imports");
    assert_eq!(imported.bodies.len(), 3);
    assert_eq!(imported.bodies[1].parent, Some(0));
}

#[test]
fn meshes_sharing_a_position_accessor_read_it_once() {
    let mut doc = cube_doc(
        json!([{"mesh": 0}, {"mesh": 1}, {"mesh": 2, "translation": [3.0, 0.0, 0.0]}]),
        json!([0, 1, 2]),
    );
    let mesh = doc["meshes"][0].clone();
    doc["meshes"]
        .as_array_mut()
        .unwrap()
        .extend([mesh.clone(), mesh]);
    let scene = read_default(&bytes_of(&doc)).expect("reads");
    assert_eq!(scene.objects.len(), 3);
    for o in &scene.objects {
        assert_eq!((o.positions.len(), o.faces.len()), (8, 12));
    }
}

#[test]
fn many_accessors_over_the_same_bytes_are_refused() {
    // 10,000 vertices (one triangle used) read through 10 accessors of 10 meshes.
    let n = 10_000usize;
    let mut bytes = vec![0u8; 12 * n];
    for (k, c) in [(3, 1.0f32), (7, 1.0f32)] {
        bytes[4 * k..4 * k + 4].copy_from_slice(&c.to_le_bytes());
    }
    for i in [0u32, 1, 2] {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bytes)
    );
    let meshes = 10;
    let mut accessors =
        vec![json!({"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"})];
    let mut mesh_list = Vec::new();
    let mut nodes = Vec::new();
    for k in 0..meshes {
        accessors.push(
            json!({"bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3",
            "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}),
        );
        mesh_list.push(json!({"primitives": [{"attributes": {"POSITION": k + 1}, "indices": 0}]}));
        nodes.push(json!({"mesh": k}));
    }
    let doc = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bytes.len(), "uri": uri}],
        "bufferViews": [
            {"buffer": 0, "byteLength": 12 * n},
            {"buffer": 0, "byteOffset": 12 * n, "byteLength": 12}
        ],
        "accessors": accessors,
        "meshes": mesh_list,
        "nodes": nodes
    });
    let e = read_default(&bytes_of(&doc)).expect_err("past the budget");
    assert!(parse_detail(&e).contains("POSITION accessors"), "{e}");
    // One of them alone is fine.
    let mut one = doc.clone();
    one["nodes"] = json!([{"mesh": 0}]);
    let scene = read_default(&bytes_of(&one)).expect("reads");
    assert_eq!(scene.objects[0].positions.len(), 3);
}
