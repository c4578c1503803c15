//! The side-by-side scenes, as meshes in the common frame:
//!
//! * `sphere_8k` … `sphere_524k`: A − B, A winged's `sphere(1, n, n + 1)` (2n² triangles
//!   once its quadrilaterals are cut in two: n = 64, 128, 256, 512 give 8,192, 32,768,
//!   131,072 and 524,288), B the same moved by (0.5, 0.5, 0.5), as in manifold's own
//!   sphere benchmark;
//! * `box_box`: A ∩ B of two unit cubes, B turned and moved;
//! * `cones8`: the intersection of 8 cones of 200 planar side faces each (a visual
//!   hull's shape): apexes spread around the origin 4 m out, axes aimed at points near
//!   it, half-angle about 14°, each cone 8 m long.

use glam::{DAffine3, DQuat, DVec3};
use winged::model::boolean::Op;
use winged::model::solids::{SolidError, box_solid, cone, sphere};
use winged::model::{Body, Serials};

#[path = "../../rng.rs"]
mod rng;

use super::off::Mesh;

/// One scene: its inputs (in the common frame) and the operation folded over them.
pub struct Scene {
    /// Its name (file names derive from it).
    pub name: String,
    /// The operation: `inputs[0] op inputs[1] op …`, left to right.
    pub op: Op,
    /// The operands.
    pub inputs: Vec<Mesh>,
}

/// A body's loci (placed) and faces.
pub fn mesh_of(body: &Body, place: DAffine3) -> Mesh {
    let vertices: Vec<_> = body.vertices().collect();
    let mut index = vec![u32::MAX; vertices.iter().map(|v| v.index() + 1).max().unwrap_or(0)];
    for (i, v) in vertices.iter().enumerate() {
        index[v.index()] = i as u32;
    }
    Mesh {
        positions: vertices
            .iter()
            .map(|&v| place.transform_point3(body.position(v)))
            .collect(),
        faces: body
            .faces()
            .map(|f| body.face_vertices(f).map(|v| index[v.index()]).collect())
            .collect(),
    }
}

/// Every scene (the sphere sizes limited to those whose segment count is in `sizes`).
pub fn scenes(sizes: &[usize]) -> Result<Vec<Scene>, SolidError> {
    let mut serials = Serials::new();
    let mut out = Vec::new();
    for &n in sizes {
        let s = sphere(&mut serials, 1.0, n, n + 1)?;
        let label = match n {
            64 => "8k".to_string(),
            128 => "32k".to_string(),
            256 => "131k".to_string(),
            512 => "524k".to_string(),
            _ => format!("{}", 2 * n * n),
        };
        out.push(Scene {
            name: format!("sphere_{label}"),
            op: Op::Difference,
            inputs: vec![
                mesh_of(&s, DAffine3::IDENTITY),
                mesh_of(&s, DAffine3::from_translation(DVec3::splat(0.5))),
            ],
        });
    }
    let cube = box_solid(&mut serials, DVec3::ONE)?;
    let turn = DQuat::from_euler(glam::EulerRot::XYZ, 0.5, 0.7, 0.9);
    out.push(Scene {
        name: "box_box".into(),
        op: Op::Intersection,
        inputs: vec![
            mesh_of(&cube, DAffine3::IDENTITY),
            mesh_of(
                &cube,
                DAffine3::from_rotation_translation(turn, DVec3::new(0.3, 0.2, 0.1)),
            ),
        ],
    });
    out.push(Scene {
        name: "cones8".into(),
        op: Op::Intersection,
        inputs: cones(&mut serials)?,
    });
    Ok(out)
}

/// The eight cones of `cones8`.
fn cones(serials: &mut Serials) -> Result<Vec<Mesh>, SolidError> {
    let (height, radius, distance) = (8.0, 2.0, 4.0);
    let c = cone(serials, radius, height, 200)?;
    let mut rng = rng::Rng(2024);
    let mut out = Vec::new();
    for corner in 0..8 {
        let sign = |bit: usize| if corner & bit == 0 { -1.0 } else { 1.0 };
        let dir = (DVec3::new(sign(1), sign(2), sign(4)) + rng.unit_vector() * 0.3).normalize();
        let apex = dir * distance;
        let target = rng.unit_vector() * 0.1;
        // The cone's apex is at +z·height/2 and it opens toward −z: turn −z onto the
        // apex-to-target direction (with a random turn about it), then move the apex.
        let aim = DQuat::from_rotation_arc(DVec3::NEG_Z, (target - apex).normalize());
        let spin = DQuat::from_rotation_z(rng.range(0.0, std::f64::consts::TAU));
        let rotation = aim * spin;
        let place = DAffine3::from_rotation_translation(
            rotation,
            apex - rotation * DVec3::Z * (height / 2.0),
        );
        out.push(mesh_of(&c, place));
    }
    Ok(out)
}
