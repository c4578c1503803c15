//! 3MF round trips, transforms, components, units and refusals.

use std::io::{Cursor, Read, Write};
use std::time::{Duration, Instant};

use glam::{DAffine3, DMat3, DQuat, DVec3};
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, ZipArchive, ZipWriter};

use super::*;
use crate::mesh::write::{ExportError, Solid};

const CORE: &str = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02";

/// A box from `lo` to `hi`: corners 0–3 counter-clockwise (seen from +z) at `lo.z`,
/// 4–7 above them, and six quads counter-clockwise seen from outside.
fn cube(lo: DVec3, hi: DVec3, name: Option<&str>, color: Color) -> Solid {
    let positions = vec![
        DVec3::new(lo.x, lo.y, lo.z),
        DVec3::new(hi.x, lo.y, lo.z),
        DVec3::new(hi.x, hi.y, lo.z),
        DVec3::new(lo.x, hi.y, lo.z),
        DVec3::new(lo.x, lo.y, hi.z),
        DVec3::new(hi.x, lo.y, hi.z),
        DVec3::new(hi.x, hi.y, hi.z),
        DVec3::new(lo.x, hi.y, hi.z),
    ];
    let mut faces = Polygons::default();
    for f in [
        [0, 3, 2, 1],
        [4, 5, 6, 7],
        [0, 1, 5, 4],
        [1, 2, 6, 5],
        [2, 3, 7, 6],
        [3, 0, 4, 7],
    ] {
        faces.push(&f);
    }
    let volume = (hi - lo).element_product();
    Solid {
        id: 7,
        name: name.map(str::to_owned),
        color,
        positions,
        faces,
        volume,
    }
}

/// The signed volume a closed surface encloses (positive when it faces outward).
fn signed_volume(positions: &[DVec3], faces: &Polygons) -> f64 {
    let mut v = 0.0;
    for f in faces.iter() {
        let a = positions[f[0] as usize];
        for k in 1..f.len() - 1 {
            let b = positions[f[k] as usize];
            let c = positions[f[k + 1] as usize];
            v += a.dot(b.cross(c)) / 6.0;
        }
    }
    v
}

/// A package of `parts` (name, XML), the first being the root model.
fn package(parts: &[(&str, &str)]) -> Vec<u8> {
    let mut zip = ZipWriter::new(Cursor::new(Vec::new()));
    let options = SimpleFileOptions::default().compression_method(CompressionMethod::Deflated);
    zip.start_file("[Content_Types].xml", options).unwrap();
    zip.write_all(b"<?xml version=\"1.0\"?><Types xmlns=\"http://schemas.openxmlformats.org/package/2006/content-types\"><Default Extension=\"model\" ContentType=\"application/vnd.ms-package.3dmanufacturing-3dmodel+xml\"/></Types>").unwrap();
    zip.start_file("_rels/.rels", options).unwrap();
    let rels = format!(
        "<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\"><Relationship Target=\"/{}\" Id=\"r0\" Type=\"{MODEL_RELATIONSHIP}\"/></Relationships>",
        parts[0].0
    );
    zip.write_all(rels.as_bytes()).unwrap();
    for (name, xml) in parts {
        zip.start_file(*name, options).unwrap();
        zip.write_all(xml.as_bytes()).unwrap();
    }
    zip.finish().unwrap().into_inner()
}

/// A model part: `unit`, `resources` and `build` inner XML.
fn model(unit: &str, resources: &str, build: &str) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<model unit="{unit}" xmlns="{CORE}"><resources>{resources}</resources><build>{build}</build></model>"#
    )
}

/// A tetrahedron mesh object (counter-clockwise from outside).
fn tetra(id: u32, extra: &str) -> String {
    format!(
        r#"<object id="{id}"{extra}><mesh><vertices>
<vertex x="0" y="0" z="0"/><vertex x="1" y="0" z="0"/><vertex x="0" y="1" z="0"/><vertex x="0" y="0" z="1"/>
</vertices><triangles>
<triangle v1="0" v2="2" v3="1"/><triangle v1="0" v2="1" v3="3"/><triangle v1="0" v2="3" v3="2"/><triangle v1="1" v2="2" v3="3"/>
</triangles></mesh></object>"#
    )
}

fn tetra_positions() -> Vec<DVec3> {
    vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z]
}

fn read_default(bytes: &[u8]) -> Result<RawScene, ImportError> {
    read(bytes, &ImportOptions::default())
}

/// Sets the declared (inflated) size of entry `name` in both the local header and the
/// central directory. Precondition: the package was written without zip64 fields.
fn set_declared_size(bytes: &mut [u8], name: &str, size: u32) {
    let (local, central) = {
        let mut zip = ZipArchive::new(Cursor::new(&*bytes)).unwrap();
        let f = zip.by_name(name).unwrap();
        (f.header_start() as usize, f.central_header_start() as usize)
    };
    assert_eq!(bytes[local..local + 4], [0x50, 0x4b, 0x03, 0x04]);
    assert_eq!(bytes[central..central + 4], [0x50, 0x4b, 0x01, 0x02]);
    bytes[local + 22..local + 26].copy_from_slice(&size.to_le_bytes());
    bytes[central + 24..central + 28].copy_from_slice(&size.to_le_bytes());
}

/// A root model part holding `n` spaces in a comment (valid XML, nothing in it).
fn spaces_package(n: usize) -> Vec<u8> {
    let mut xml = String::with_capacity(n + 200);
    xml.push_str(&format!(
        r#"<?xml version="1.0"?><model unit="meter" xmlns="{CORE}"><!--"#
    ));
    xml.extend(std::iter::repeat_n(' ', n));
    xml.push_str("--><resources/><build/></model>");
    package(&[("3D/3dmodel.model", &xml)])
}

#[test]
fn cube_round_trips_bit_exact() {
    let lo = DVec3::new(0.1, -1.0 / 3.0, 1e-7);
    let hi = DVec3::new(0.1 + 0.2, 2.0 / 3.0, 12_345.678_901_234_5);
    let color = Color([0x12, 0xab, 0xff]);
    let solid = cube(lo, hi, Some("Würfel <1> & \"two\""), color);
    assert!(
        signed_volume(&solid.positions, &solid.faces) > 0.0,
        "the test cube faces out"
    );
    let bytes = write(std::slice::from_ref(&solid)).unwrap();

    // The package's parts are where readers look for them.
    let mut zip = ZipArchive::new(Cursor::new(&bytes[..])).unwrap();
    for name in ["[Content_Types].xml", "_rels/.rels", "3D/3dmodel.model"] {
        assert!(zip.by_name(name).is_ok(), "{name} is missing");
    }
    let mut xml = String::new();
    zip.by_name("3D/3dmodel.model")
        .unwrap()
        .read_to_string(&mut xml)
        .unwrap();
    assert!(xml.contains(r#"unit="meter""#), "{xml}");
    assert!(xml.contains(r##"displaycolor="#12ABFF""##), "{xml}");

    let scene = read_default(&bytes).unwrap();
    assert_eq!(scene.unit, Some(Unit::M));
    assert_eq!(scene.objects.len(), 1);
    let o = &scene.objects[0];
    assert_eq!(o.name.as_deref(), Some("Würfel <1> & \"two\""));
    assert_eq!(o.color, Some(color));
    assert_eq!(o.pose, Pose::IDENTITY);
    assert_eq!(o.parent, None);
    assert_eq!((o.first_vertex, o.first_face), (Some(0), 0));
    assert_eq!(o.positions.len(), 8);
    for (a, b) in o.positions.iter().zip(&solid.positions) {
        assert_eq!(
            a.to_array().map(f64::to_bits),
            b.to_array().map(f64::to_bits)
        );
    }
    assert_eq!(o.faces.len(), 12);
    assert!(o.faces.iter().all(|f| f.len() == 3));
    let v = signed_volume(&o.positions, &o.faces);
    assert!(
        (v - solid.volume).abs() <= 1e-9 * solid.volume,
        "{v} vs {}",
        solid.volume
    );
}

#[test]
fn awkward_numbers_round_trip_bit_exact() {
    let values = [
        5e-324,
        -0.0,
        f64::MAX,
        f64::MIN_POSITIVE,
        1.0 / 3.0,
        -123_456_789.123_456_79,
        1e300,
        2.5e-300,
        0.1 + 0.2,
    ];
    let positions: Vec<DVec3> = values
        .chunks(3)
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .collect();
    let mut faces = Polygons::default();
    faces.push(&[0, 1, 2]);
    let solid = Solid {
        id: 1,
        name: None,
        color: Color([0, 0, 0]),
        positions: positions.clone(),
        faces,
        volume: 0.0,
    };
    let scene = read_default(&write(&[solid]).unwrap()).unwrap();
    let o = &scene.objects[0];
    assert_eq!(o.name, None);
    for (a, b) in o.positions.iter().zip(&positions) {
        assert_eq!(
            a.to_array().map(f64::to_bits),
            b.to_array().map(f64::to_bits)
        );
    }
}

#[test]
fn several_solids_are_several_objects() {
    let a = cube(DVec3::ZERO, DVec3::ONE, Some("a"), Color([1, 2, 3]));
    let mut b = cube(DVec3::splat(2.0), DVec3::splat(3.0), None, Color([4, 5, 6]));
    b.id = 9;
    let scene = read_default(&write(&[a, b]).unwrap()).unwrap();
    assert_eq!(scene.objects.len(), 2);
    assert_eq!(scene.objects[0].name.as_deref(), Some("a"));
    assert_eq!(scene.objects[1].name, None);
    assert_eq!(scene.objects[0].color, Some(Color([1, 2, 3])));
    assert_eq!(scene.objects[1].color, Some(Color([4, 5, 6])));
}

#[test]
fn non_finite_coordinates_are_not_written() {
    let mut s = cube(DVec3::ZERO, DVec3::ONE, None, Color([0, 0, 0]));
    s.positions[3].y = f64::NAN;
    assert!(matches!(write(&[s]), Err(ExportError::Encode { .. })));
}

/// How long inflating the model part of `bytes` in full takes (the yardstick for "it was
/// not inflated").
fn time_to_inflate(bytes: &[u8]) -> Duration {
    let start = Instant::now();
    let mut zip = ZipArchive::new(Cursor::new(bytes)).unwrap();
    let mut part = zip.by_name("3D/3dmodel.model").unwrap();
    let n = std::io::copy(&mut part, &mut std::io::sink()).unwrap();
    assert!(n >= 50_000_000);
    start.elapsed()
}

#[test]
fn lying_declared_size_is_refused_quickly() {
    let honest = spaces_package(50_000_000);
    let full = time_to_inflate(&honest);
    let mut bytes = honest;
    set_declared_size(&mut bytes, "3D/3dmodel.model", 1000);
    let start = Instant::now();
    let err = read_default(&bytes).unwrap_err();
    let elapsed = start.elapsed();
    assert!(
        matches!(
            err,
            ImportError::TooLarge {
                count: 1001,
                limit: 1000,
                ..
            }
        ),
        "{err:?}"
    );
    // Inflating 50 MB takes far longer than inflating one kilobyte.
    assert!(
        elapsed * 5 < full,
        "{elapsed:?} against {full:?} for all of it"
    );
}

#[test]
fn highly_compressed_part_is_refused_before_inflating() {
    let bytes = spaces_package(50_000_000);
    {
        let zip = ZipArchive::new(Cursor::new(&bytes[..])).unwrap();
        let e = zip
            .by_index_data(zip.index_for_name("3D/3dmodel.model").unwrap())
            .unwrap();
        assert!(
            e.size() > MAX_RATIO * e.compressed_size(),
            "the premise: deflate beats 1000:1 on spaces ({} from {})",
            e.size(),
            e.compressed_size()
        );
    }
    let full = time_to_inflate(&bytes);
    let start = Instant::now();
    let err = read_default(&bytes).unwrap_err();
    let elapsed = start.elapsed();
    assert!(
        matches!(
            err,
            ImportError::TooLarge {
                limit: MAX_RATIO,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(
        elapsed * 5 < full,
        "{elapsed:?} against {full:?} for all of it"
    );
}

#[test]
fn declared_sizes_past_the_limit_are_refused() {
    let xml = model("millimeter", &tetra(1, ""), r#"<item objectid="1"/>"#);
    let mut bytes = package(&[("3D/3dmodel.model", &xml)]);
    set_declared_size(&mut bytes, "3D/3dmodel.model", 300 << 20);
    let err = read_default(&bytes).unwrap_err();
    assert!(
        matches!(
            err,
            ImportError::TooLarge {
                what: "bytes inflated from the 3MF package",
                limit: MAX_INFLATED,
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn not_a_zip_is_a_parse_error() {
    for bytes in [&b""[..], b"solid cube\nendsolid\n", b"PK\x03\x04 truncated"] {
        let err = read_default(bytes).unwrap_err();
        assert!(
            matches!(err, ImportError::Parse { format: "3mf", .. }),
            "{err:?}"
        );
    }
}

#[test]
fn a_zip_without_a_model_is_a_parse_error() {
    let mut zip = ZipWriter::new(Cursor::new(Vec::new()));
    zip.start_file("readme.txt", SimpleFileOptions::default())
        .unwrap();
    zip.write_all(b"not a model").unwrap();
    let bytes = zip.finish().unwrap().into_inner();
    let err = read_default(&bytes).unwrap_err();
    assert!(
        matches!(err, ImportError::Parse { format: "3mf", .. }),
        "{err:?}"
    );
}

#[test]
fn an_empty_build_is_an_empty_scene() {
    let xml = model("millimeter", &tetra(1, ""), "");
    let scene = read_default(&package(&[("3D/3dmodel.model", &xml)])).unwrap();
    assert!(scene.objects.is_empty());
    assert_eq!(scene.unit, Some(Unit::Mm));
}

#[test]
fn broken_xml_is_a_parse_error() {
    for xml in [
        "<model><resources>".to_owned(),
        "<notamodel/>".to_owned(),
        model("parsec", "", ""),
        model(
            "meter",
            r#"<object id="1"><mesh><vertices><vertex x="a" y="0" z="0"/></vertices></mesh></object>"#,
            "",
        ),
        model("meter", &tetra(1, ""), r#"<item objectid="2"/>"#),
        model(
            "meter",
            &tetra(1, ""),
            r#"<item objectid="1" transform="1 0 0"/>"#,
        ),
        model("meter", &format!("{}{}", tetra(1, ""), tetra(1, "")), ""),
    ] {
        let err = read_default(&package(&[("3D/3dmodel.model", &xml)])).unwrap_err();
        assert!(
            matches!(err, ImportError::Parse { format: "3mf", .. }),
            "{xml}: {err:?}"
        );
    }
}

#[test]
fn scale_and_translation_split_into_pose_and_positions() {
    let xml = model(
        "millimeter",
        &tetra(1, ""),
        r#"<item objectid="1" transform="2 0 0 0 2 0 0 0 2 10 20 30"/>"#,
    );
    let scene = read_default(&package(&[("3D/3dmodel.model", &xml)])).unwrap();
    let o = &scene.objects[0];
    assert_eq!(o.pose.position, DVec3::new(10.0, 20.0, 30.0));
    assert_eq!(o.pose.rotation, DQuat::IDENTITY);
    let expected: Vec<DVec3> = tetra_positions().iter().map(|&p| 2.0 * p).collect();
    assert_eq!(o.positions, expected);
    assert_eq!(o.faces.face(0), &[0, 2, 1]);
    assert!(signed_volume(&o.positions, &o.faces) > 0.0);
}

#[test]
fn rotation_alone_is_the_pose() {
    // 90° about z: x ↦ y, y ↦ −x (rows are the axes' images).
    let xml = model(
        "millimeter",
        &tetra(1, ""),
        r#"<item objectid="1" transform="0 1 0 -1 0 0 0 0 1 5 0 0"/>"#,
    );
    let scene = read_default(&package(&[("3D/3dmodel.model", &xml)])).unwrap();
    let o = &scene.objects[0];
    assert_eq!(
        o.positions,
        tetra_positions(),
        "a rotation leaves positions alone"
    );
    let want = Pose::new(
        DVec3::new(5.0, 0.0, 0.0),
        DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2),
    )
    .unwrap();
    assert!(o.pose.approx_eq(&want, 1e-12, 1e-12), "{:?}", o.pose);
}

#[test]
fn rotation_with_scale_and_shear_composes_back() {
    let rotation = DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0);
    let stretch = DMat3::from_cols(
        DVec3::new(3.0, 0.5, 0.0),
        DVec3::new(0.5, 2.0, 0.1),
        DVec3::new(0.0, 0.1, 0.5),
    );
    let l = DMat3::from_quat(rotation) * stretch;
    let t = DVec3::new(-4.0, 0.25, 9.0);
    let [c0, c1, c2] = [l.x_axis, l.y_axis, l.z_axis];
    let transform = format!(
        "{} {} {} {} {} {} {} {} {} {} {} {}",
        c0.x, c0.y, c0.z, c1.x, c1.y, c1.z, c2.x, c2.y, c2.z, t.x, t.y, t.z
    );
    let xml = model(
        "millimeter",
        &tetra(1, ""),
        &format!(r#"<item objectid="1" transform="{transform}"/>"#),
    );
    let scene = read_default(&package(&[("3D/3dmodel.model", &xml)])).unwrap();
    let o = &scene.objects[0];
    assert!(
        o.pose
            .approx_eq(&Pose::new(t, rotation).unwrap(), 1e-12, 1e-9),
        "{:?}",
        o.pose
    );
    for (p, q) in tetra_positions().iter().zip(&o.positions) {
        let placed = o.pose.transform_point(*q);
        assert!(
            placed.distance(l * *p + t) < 1e-12,
            "{placed} vs {}",
            l * *p + t
        );
    }
    assert_eq!(o.faces.face(0), &[0, 2, 1], "no mirror, no reversal");
}

#[test]
fn a_mirror_reverses_the_winding() {
    let xml = model(
        "millimeter",
        &tetra(1, ""),
        r#"<item objectid="1" transform="-1 0 0 0 1 0 0 0 1 0 0 0"/>"#,
    );
    let scene = read_default(&package(&[("3D/3dmodel.model", &xml)])).unwrap();
    let o = &scene.objects[0];
    let want = [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
    for (k, w) in want.iter().enumerate() {
        assert_eq!(o.faces.face(k), w);
    }
    // The pose is rigid, the placed points are the mirrored ones, and the placed
    // surface still faces out.
    assert!((o.pose.rotation.length() - 1.0).abs() < 1e-15);
    let placed: Vec<DVec3> = o
        .positions
        .iter()
        .map(|&q| o.pose.transform_point(q))
        .collect();
    for (p, q) in tetra_positions().iter().zip(&placed) {
        assert!(q.distance(DVec3::new(-p.x, p.y, p.z)) < 1e-15, "{q}");
    }
    assert!(signed_volume(&placed, &o.faces) > 0.0);
}

#[test]
fn singular_transforms_are_refused() {
    let xml = model(
        "millimeter",
        &tetra(1, ""),
        r#"<item objectid="1" transform="1 0 0 0 1 0 0 0 0 0 0 0"/>"#,
    );
    let err = read_default(&package(&[("3D/3dmodel.model", &xml)])).unwrap_err();
    assert!(matches!(err, ImportError::Parse { .. }), "{err:?}");
}

#[test]
fn components_are_flattened_with_composed_transforms() {
    let resources = format!(
        r#"{}<object id="5" name="pair"><components>
<component objectid="1" transform="1 0 0 0 1 0 0 0 1 1 0 0"/>
<component objectid="1" transform="1 0 0 0 1 0 0 0 1 0 3 0"/>
</components></object>{}"#,
        tetra(1, ""),
        tetra(9, r#" name="unused""#),
    );
    let xml = model(
        "millimeter",
        &resources,
        r#"<item objectid="5" transform="1 0 0 0 1 0 0 0 1 0 0 10"/>"#,
    );
    let scene = read_default(&package(&[("3D/3dmodel.model", &xml)])).unwrap();
    assert_eq!(scene.objects.len(), 2, "the unreferenced object is skipped");
    for (o, at) in scene
        .objects
        .iter()
        .zip([DVec3::new(1.0, 0.0, 10.0), DVec3::new(0.0, 3.0, 10.0)])
    {
        assert_eq!(o.parent, None);
        assert_eq!(
            o.name.as_deref(),
            Some("pair"),
            "inherited from the components object"
        );
        assert_eq!(o.pose.position, at);
        assert_eq!(o.positions, tetra_positions());
        assert_eq!(o.faces.len(), 4);
    }
}

#[test]
fn component_cycles_and_depth_are_refused() {
    let resources = r#"<object id="1"><components><component objectid="2"/></components></object>
<object id="2"><components><component objectid="1"/></components></object>"#;
    let xml = model("millimeter", resources, r#"<item objectid="1"/>"#);
    let err = read_default(&package(&[("3D/3dmodel.model", &xml)])).unwrap_err();
    assert!(matches!(err, ImportError::Parse { .. }), "{err:?}");
}

#[test]
fn instance_explosion_is_refused_before_building() {
    // Each level refers to the one below twice: 2^30 instances of the tetrahedron.
    let mut resources = tetra(1, "");
    for id in 2..=31 {
        resources.push_str(&format!(
            r#"<object id="{id}"><components><component objectid="{0}"/><component objectid="{0}"/></components></object>"#,
            id - 1
        ));
    }
    let xml = model("millimeter", &resources, r#"<item objectid="31"/>"#);
    let start = Instant::now();
    let err = read_default(&package(&[("3D/3dmodel.model", &xml)])).unwrap_err();
    assert!(matches!(err, ImportError::TooLarge { .. }), "{err:?}");
    assert!(start.elapsed() < Duration::from_secs(1));
}

#[test]
fn too_many_faces_are_refused() {
    let bytes = write(&[cube(DVec3::ZERO, DVec3::ONE, None, Color([0, 0, 0]))]).unwrap();
    let options = ImportOptions {
        max_file_faces: 11,
        ..ImportOptions::default()
    };
    let err = read(&bytes, &options).unwrap_err();
    assert!(
        matches!(
            err,
            ImportError::TooLarge {
                what: "faces in the file",
                limit: 11,
                ..
            }
        ),
        "{err:?}"
    );
    let options = ImportOptions {
        max_file_faces: 12,
        ..ImportOptions::default()
    };
    assert_eq!(read(&bytes, &options).unwrap().face_count(), 12);
}

#[test]
fn units_are_read_and_micron_and_foot_converted() {
    for (unit, want, scale) in [
        ("meter", Unit::M, 1.0),
        ("millimeter", Unit::Mm, 1.0),
        ("centimeter", Unit::Cm, 1.0),
        ("inch", Unit::In, 1.0),
        ("micron", Unit::Mm, 1e-3),
        ("foot", Unit::In, 12.0),
    ] {
        let xml = model(
            unit,
            &tetra(1, ""),
            r#"<item objectid="1" transform="1 0 0 0 1 0 0 0 1 0 0 1"/>"#,
        );
        let scene = read_default(&package(&[("3D/3dmodel.model", &xml)])).unwrap();
        assert_eq!(scene.unit, Some(want), "{unit}");
        let o = &scene.objects[0];
        assert_eq!(o.positions[1], DVec3::new(scale, 0.0, 0.0), "{unit}");
        assert_eq!(o.pose.position, DVec3::new(0.0, 0.0, scale), "{unit}");
    }
    // No unit: millimetres, as the specification says.
    let xml = format!(
        r#"<model xmlns="{CORE}"><resources>{}</resources><build><item objectid="1"/></build></model>"#,
        tetra(1, "")
    );
    let bytes = package(&[("3D/3dmodel.model", &xml)]);
    assert_eq!(read_default(&bytes).unwrap().unit, Some(Unit::Mm));
    // A unit the caller names overrides, and nothing is scaled.
    let xml = model("micron", &tetra(1, ""), r#"<item objectid="1"/>"#);
    let options = ImportOptions {
        unit: Some(Unit::Cm),
        ..ImportOptions::default()
    };
    let scene = read(&package(&[("3D/3dmodel.model", &xml)]), &options).unwrap();
    assert_eq!(scene.unit, Some(Unit::Cm));
    assert_eq!(scene.objects[0].positions, tetra_positions());
}

#[test]
fn parts_referred_to_by_path_are_read_in_the_root_unit() {
    // The root (centimetres) refers to an object of another part (millimetres), as
    // slicers with the production extension write.
    let root = format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<model unit="centimeter" xmlns="{CORE}" xmlns:p="http://schemas.microsoft.com/3dmanufacturing/production/2015/06">
<resources><object id="2" name="outer" p:UUID="x"><components>
<component p:path="/3D/Objects/object_1.model" objectid="1" transform="1 0 0 0 1 0 0 0 1 10 0 0"/>
</components></object></resources>
<build><item objectid="2" p:UUID="y"/></build></model>"#
    );
    let sub = model("millimeter", &tetra(1, r#" partnumber="tip""#), "");
    let bytes = package(&[
        ("3D/3dmodel.model", &root),
        ("3D/Objects/object_1.model", &sub),
    ]);
    let scene = read_default(&bytes).unwrap();
    assert_eq!(scene.unit, Some(Unit::Cm));
    assert_eq!(scene.objects.len(), 1);
    let o = &scene.objects[0];
    assert_eq!(o.name.as_deref(), Some("tip"));
    assert_eq!(o.pose.position, DVec3::new(10.0, 0.0, 0.0));
    let want: Vec<DVec3> = tetra_positions().iter().map(|&p| p * 0.1).collect();
    assert_eq!(o.positions, want);
}

#[test]
fn colours_come_from_base_materials_with_or_without_alpha_and_prefix() {
    let resources = format!(
        r##"<basematerials id="3"><base name="a" displaycolor="#FF000080"/><base name="b" displaycolor="#00ff00"/></basematerials>
<m:basematerials xmlns:m="http://schemas.microsoft.com/3dmanufacturing/material/2015/02" id="4"><m:base name="c" displaycolor="#0000FF"/></m:basematerials>
{}{}{}{}"##,
        tetra(1, r#" pid="3" pindex="0""#),
        tetra(2, r#" pid="3" pindex="1""#),
        tetra(5, r#" pid="4""#),
        tetra(6, r#" pid="3" pindex="9""#),
    );
    let build =
        r#"<item objectid="1"/><item objectid="2"/><item objectid="5"/><item objectid="6"/>"#;
    let xml = model("millimeter", &resources, build);
    let scene = read_default(&package(&[("3D/3dmodel.model", &xml)])).unwrap();
    let colors: Vec<_> = scene.objects.iter().map(|o| o.color).collect();
    assert_eq!(
        colors,
        [
            Some(Color([255, 0, 0])),
            Some(Color([0, 255, 0])),
            Some(Color([0, 0, 255])),
            None
        ]
    );
    assert_eq!(model::display_color("#12345"), None);
    assert_eq!(model::display_color("#GG0000"), None);
    assert_eq!(model::display_color("#ÿÿÿÿÿÿ"), None);
}

#[test]
fn supports_and_empty_meshes_are_skipped_and_indices_pass_through() {
    let resources = format!(
        r#"{}<object id="2" type="model"><mesh><vertices><vertex x="0" y="0" z="0"/></vertices><triangles/></mesh></object>
<object id="3"><mesh><vertices><vertex x="0" y="0" z="0"/></vertices><triangles><triangle v1="0" v2="7" v3="99999999999"/></triangles></mesh></object>"#,
        tetra(1, r#" type="support""#)
    );
    let build = r#"<item objectid="1"/><item objectid="2"/><item objectid="3"/>"#;
    let xml = model("millimeter", &resources, build);
    let scene = read_default(&package(&[("3D/3dmodel.model", &xml)])).unwrap();
    assert_eq!(scene.objects.len(), 1);
    assert_eq!(scene.objects[0].faces.face(0), &[0, 7, u32::MAX]);
}

#[test]
fn the_root_is_found_by_relationship_or_by_name() {
    let xml = model("meter", &tetra(1, ""), r#"<item objectid="1"/>"#);
    // Named by the relationship, not by convention.
    let bytes = package(&[("3D/other.model", &xml)]);
    assert_eq!(read_default(&bytes).unwrap().objects.len(), 1);
    // No relationships: the conventional name.
    let mut zip = ZipWriter::new(Cursor::new(Vec::new()));
    zip.start_file("3D/3dmodel.model", SimpleFileOptions::default())
        .unwrap();
    zip.write_all(xml.as_bytes()).unwrap();
    let bytes = zip.finish().unwrap().into_inner();
    assert_eq!(read_default(&bytes).unwrap().objects.len(), 1);
}

#[test]
fn damaged_packages_never_panic() {
    let mut a = cube(DVec3::ZERO, DVec3::ONE, Some("a"), Color([9, 9, 9]));
    a.id = 1;
    let bytes = write(&[a]).unwrap();
    for cut in (0..bytes.len()).step_by(7) {
        let _ = read_default(&bytes[..cut]);
    }
    // Flip bytes one at a time, a deterministic sweep over the whole package.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for _ in 0..2000 {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let mut damaged = bytes.clone();
        let at = (state % bytes.len() as u64) as usize;
        damaged[at] ^= (state >> 32) as u8 | 1;
        let _ = read_default(&damaged);
    }
}

#[test]
fn decompose_keeps_exact_rotations_and_refuses_nonsense() {
    let exact = DAffine3::from_rotation_translation(DQuat::from_rotation_y(0.7), DVec3::ONE);
    let (pose, residual) = decompose(&exact).unwrap();
    assert!(residual.is_none());
    assert!(pose.approx_eq(
        &Pose::new(DVec3::ONE, DQuat::from_rotation_y(0.7)).unwrap(),
        0.0,
        1e-15
    ));
    let zero = DAffine3 {
        matrix3: DMat3::ZERO,
        translation: DVec3::ZERO,
    };
    assert!(decompose(&zero).is_err());
    let inf = DAffine3 {
        matrix3: DMat3::IDENTITY * f64::MAX,
        translation: DVec3::ZERO,
    };
    assert!(decompose(&inf).is_err());
}
