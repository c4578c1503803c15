//! Reading files into bodies: merging, pieces, and each refusal with its place.

use glam::DVec3;

use super::error::Defect;
use super::*;

/// The 8 corners of a box from `lo` to `hi` and its 6 faces, counter-clockwise seen
/// from outside.
fn box_polygons(lo: DVec3, hi: DVec3) -> (Vec<DVec3>, Vec<[u32; 4]>) {
    let p = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    let faces = vec![
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    (p, faces)
}

/// A binary STL of the triangles.
fn stl(tris: &[[DVec3; 3]]) -> Vec<u8> {
    let mut out = vec![0u8; 80];
    out.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in tris {
        out.extend_from_slice(&[0u8; 12]);
        for v in t {
            for c in v.to_array() {
                out.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    out
}

/// The box's 12 triangles.
fn box_triangles(lo: DVec3, hi: DVec3) -> Vec<[DVec3; 3]> {
    let (p, faces) = box_polygons(lo, hi);
    faces
        .iter()
        .flat_map(|f| {
            let q = f.map(|i| p[i as usize]);
            [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
        })
        .collect()
}

fn off(points: &[DVec3], faces: &[Vec<u32>]) -> Vec<u8> {
    let mut s = format!("OFF\n{} {} 0\n", points.len(), faces.len());
    for p in points {
        s += &format!("{:?} {:?} {:?}\n", p.x, p.y, p.z);
    }
    for f in faces {
        s += &format!("{}", f.len());
        for v in f {
            s += &format!(" {v}");
        }
        s += "\n";
    }
    s.into_bytes()
}

fn defect(r: Result<Imported, ImportError>) -> (Defect, Where) {
    match r {
        Err(ImportError::Invalid { defect, at, .. }) => (defect, *at),
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[test]
fn a_twelve_triangle_box_is_six_faces() {
    let file = stl(&box_triangles(DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0)));
    let got = import(Format::Stl, &file, &ImportOptions::default()).expect("imports");
    assert_eq!(got.bodies.len(), 1);
    let b = &got.bodies[0];
    assert_eq!(b.faces.len(), 6);
    assert!(b.faces.iter().all(|f| f.len() == 4));
    assert_eq!(b.positions.len(), 8);
    assert_eq!(b.faces_read, 12);
    let off_merge = ImportOptions {
        merge_coplanar: false,
        ..ImportOptions::default()
    };
    let got = import(Format::Stl, &file, &off_merge).expect("imports");
    assert_eq!(got.bodies[0].faces.len(), 12);
}

#[test]
fn a_rotated_f32_box_still_merges() {
    let q = glam::DQuat::from_euler(glam::EulerRot::XYZ, 0.3, 0.7, 1.1);
    let tris: Vec<[DVec3; 3]> = box_triangles(DVec3::splat(-0.5), DVec3::splat(0.5))
        .into_iter()
        .map(|t| t.map(|p| q * p + DVec3::new(10.0, 3.0, 1.0)))
        .collect();
    let got = import(Format::Stl, &stl(&tris), &ImportOptions::default()).expect("imports");
    assert_eq!(got.bodies[0].faces.len(), 6);
}

#[test]
fn units_scale_loci_to_meters() {
    let file = stl(&box_triangles(DVec3::ZERO, DVec3::splat(10.0)));
    let mm = ImportOptions {
        unit: Some(Unit::Mm),
        ..ImportOptions::default()
    };
    let got = import(Format::Stl, &file, &mm).expect("imports");
    let max = got.bodies[0]
        .positions
        .iter()
        .fold(DVec3::ZERO, |m, &p| m.max(p));
    assert!(
        (max - DVec3::splat(0.01)).abs().max_element() < 1e-12,
        "{max}"
    );
}

#[test]
fn two_boxes_in_one_file_are_two_bodies() {
    let mut tris = box_triangles(DVec3::ZERO, DVec3::ONE);
    tris.extend(box_triangles(DVec3::splat(2.0), DVec3::splat(3.0)));
    let text = {
        let mut s = String::from("solid pair\n");
        for t in &tris {
            s += "facet normal 0 0 0\nouter loop\n";
            for v in t {
                s += &format!("vertex {} {} {}\n", v.x, v.y, v.z);
            }
            s += "endloop\nendfacet\n";
        }
        s + "endsolid pair\n"
    };
    let got = import(Format::Stl, text.as_bytes(), &ImportOptions::default()).expect("imports");
    assert_eq!(got.bodies.len(), 2);
    assert_eq!(got.bodies[0].name.as_deref(), Some("pair"));
    assert_eq!(got.bodies[1].name.as_deref(), Some("pair.2"));
    assert_eq!(got.bodies[1].parent, Some(0));
}

#[test]
fn an_open_box_names_the_edge_and_face() {
    let (p, faces) = box_polygons(DVec3::ZERO, DVec3::ONE);
    let faces: Vec<Vec<u32>> = faces[..5].iter().map(|f| f.to_vec()).collect();
    let (d, at) = defect(import(
        Format::Off,
        &off(&p, &faces),
        &ImportOptions::default(),
    ));
    assert_eq!(d, Defect::Open);
    assert_eq!(at.vertices.len(), 2);
    assert_eq!(at.faces.len(), 1);
}

#[test]
fn a_flipped_face_is_inconsistent() {
    let (p, faces) = box_polygons(DVec3::ZERO, DVec3::ONE);
    let mut faces: Vec<Vec<u32>> = faces.iter().map(|f| f.to_vec()).collect();
    faces[3].reverse();
    let (d, at) = defect(import(
        Format::Off,
        &off(&p, &faces),
        &ImportOptions::default(),
    ));
    assert_eq!(d, Defect::InconsistentOrientation);
    assert!(at.faces.contains(&3), "{at}");
}

#[test]
fn an_inside_out_box_is_inward() {
    let (p, faces) = box_polygons(DVec3::ZERO, DVec3::ONE);
    let faces: Vec<Vec<u32>> = faces
        .iter()
        .map(|f| f.iter().rev().copied().collect())
        .collect();
    let (d, _) = defect(import(
        Format::Off,
        &off(&p, &faces),
        &ImportOptions::default(),
    ));
    assert_eq!(d, Defect::Inward);
}

#[test]
fn a_third_face_on_an_edge_is_non_manifold() {
    let (mut p, faces) = box_polygons(DVec3::ZERO, DVec3::ONE);
    let mut faces: Vec<Vec<u32>> = faces.iter().map(|f| f.to_vec()).collect();
    p.push(DVec3::new(0.5, -1.0, -1.0));
    faces.push(vec![0, 1, 8]);
    let (d, _) = defect(import(
        Format::Off,
        &off(&p, &faces),
        &ImportOptions::default(),
    ));
    assert_eq!(d, Defect::NonManifoldEdge);
}

#[test]
fn degenerate_faces_and_bad_numbers_are_named() {
    let (mut p, faces) = box_polygons(DVec3::ZERO, DVec3::ONE);
    let mut with_repeat: Vec<Vec<u32>> = faces.iter().map(|f| f.to_vec()).collect();
    with_repeat[2] = vec![0, 1, 1, 5, 4];
    let (d, at) = defect(import(
        Format::Off,
        &off(&p, &with_repeat),
        &ImportOptions::default(),
    ));
    assert_eq!((d, at.faces.clone()), (Defect::Degenerate, vec![2]));
    p[5] = DVec3::new(f64::NAN, 0.0, 0.0);
    let faces: Vec<Vec<u32>> = faces.iter().map(|f| f.to_vec()).collect();
    let text = String::from_utf8(off(&p, &faces)).expect("text");
    let (d, at) = defect(import(
        Format::Off,
        text.as_bytes(),
        &ImportOptions::default(),
    ));
    assert_eq!((d, at.vertices), (Defect::NotFinite, vec![5]));
    let mut bad = faces.clone();
    bad[0][0] = 99;
    let (d, at) = defect(import(
        Format::Off,
        &off(&box_polygons(DVec3::ZERO, DVec3::ONE).0, &bad),
        &ImportOptions::default(),
    ));
    assert_eq!((d, at.faces), (Defect::BadIndex, vec![0]));
}

#[test]
fn two_boxes_through_each_other_in_one_surface_cross() {
    // One surface: two boxes that overlap, joined into one piece by nothing; each is
    // its own piece, and pieces may overlap. But a box with a face pushed through its
    // opposite face crosses itself.
    let (mut p, faces) = box_polygons(DVec3::ZERO, DVec3::ONE);
    for v in [4, 5, 6, 7] {
        p[v].z = -0.5;
    }
    // Top face now below the bottom: the side faces fold through each other.
    let faces: Vec<Vec<u32>> = faces.iter().map(|f| f.to_vec()).collect();
    let r = import(Format::Off, &off(&p, &faces), &ImportOptions::default());
    assert!(r.is_err(), "{r:?}");
}

#[test]
fn a_plate_with_a_hole_keeps_its_holed_faces_triangulated() {
    // A square frame (a plate with a square hole), as quads: its top and bottom are
    // each four coplanar quads around a hole, which no single ring can bound.
    let outer = [[0.0, 0.0], [3.0, 0.0], [3.0, 3.0], [0.0, 3.0]];
    let inner = [[1.0, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0]];
    let mut p = Vec::new();
    for z in [0.0, 1.0] {
        for q in outer.iter().chain(inner.iter()) {
            p.push(DVec3::new(q[0], q[1], z));
        }
    }
    // Indices: bottom outer 0-3, inner 4-7; top outer 8-11, inner 12-15.
    let mut faces: Vec<Vec<u32>> = Vec::new();
    for k in 0..4u32 {
        let (o0, o1, i0, i1) = (k, (k + 1) % 4, 4 + k, 4 + (k + 1) % 4);
        faces.push(vec![8 + o0, 8 + o1, 8 + i1, 8 + i0]); // top, facing +z
        faces.push(vec![o0, i0, i1, o1]); // bottom, facing -z
        faces.push(vec![o0, o1, 8 + o1, 8 + o0]); // outer wall
        faces.push(vec![i0, 8 + i0, 8 + i1, i1]); // inner wall
    }
    let got = import(Format::Off, &off(&p, &faces), &ImportOptions::default()).expect("imports");
    let b = &got.bodies[0];
    assert_eq!(b.unmerged, 2, "top and bottom stay as quads");
    assert_eq!(b.faces.len(), 16);
}

#[test]
fn a_weld_tolerance_closes_near_misses() {
    let mut tris = box_triangles(DVec3::ZERO, DVec3::ONE);
    tris[0][0] += DVec3::splat(1e-5);
    let file = stl(&tris);
    let (d, _) = defect(import(Format::Stl, &file, &ImportOptions::default()));
    assert_eq!(d, Defect::Open);
    let welded = ImportOptions {
        weld: 1e-4,
        ..ImportOptions::default()
    };
    let got = import(Format::Stl, &file, &welded).expect("imports");
    assert_eq!(got.bodies[0].positions.len(), 8);
}

#[test]
fn an_empty_file_is_refused() {
    assert_eq!(
        import(Format::Off, b"OFF\n0 0 0\n", &ImportOptions::default()),
        Err(ImportError::Empty)
    );
}

// Inputs found by coverage-guided fuzzing (fuzz/, `cargo fuzz`), minimised: each must
// give a clean error or a result, never a panic.

/// tobj 4.0.5 multiplied a face's normal or texture-coordinate index unchecked: an
/// index before the start of its list (`1//-4` with fewer than four normals) wrapped to
/// a huge `usize` and `vn * 3 + 2` overflowed. The reader no longer gives tobj the `vt`
/// and `vn` lines.
#[test]
fn fuzz_obj_normal_and_texcoord_indices_out_of_range() {
    for file in [
        &b"f 1//-4 4 0\nv 1 3 4\nvn 0 0 0\n"[..],
        b"vt 0 5\nv 0 5 0\nf 1/-4 4 /\n",
        b"f 2//-6 6 6\nv 1 8 2\nv 1 1 4\nvn 1 0 0\n",
        b"v 5 5 0\nvn 0 1 0\nf  1//-6 4 0\n",
    ] {
        let got = import(Format::Obj, file, &ImportOptions::default());
        assert!(
            matches!(got, Err(ImportError::Parse { .. })),
            "{:?}: {got:?}",
            String::from_utf8_lossy(file)
        );
    }
    // Normals and texture coordinates, in range or not, do not change what is read.
    let tetra = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\r\n  vt 0 0\n\
                 f 1/1/1 3/1/1 2/1/9\nf 1//-7 2//1 4//1\nf 1/-5 4 3\nf 2 3 4\n";
    let got = import(Format::Obj, tetra.as_bytes(), &ImportOptions::default()).expect("imports");
    assert_eq!(got.bodies.len(), 1);
    assert_eq!(got.bodies[0].faces.len(), 4);
}

/// A byte-order mark before a GLB header: the mark was stripped as for JSON after the
/// GLB header's length had been looked for (not found), so the `gltf` crate read the
/// header unchecked and subtracted 12 from a length of 1. The magic is now looked for
/// after the mark.
#[test]
fn fuzz_gltf_byte_order_mark_before_a_glb_header() {
    for format in [Format::Gltf, Format::Glb] {
        let got = import(
            format,
            b"\xEF\xBB\xBFglTF\x02\0\0\0\x01\0\0\0",
            &ImportOptions::default(),
        );
        assert!(matches!(got, Err(ImportError::Parse { .. })), "{got:?}");
    }
}
