//! The demo scene of `winged serve --demo`: Baumgart's hand-eye table with a few blocks
//! on it, a camera looking at it and a sun.

use glam::{DQuat, DVec2, DVec3};

use crate::model::solids::{box_solid, cylinder, prism_solid, pyramid_solid};
use crate::model::{Camera, Intrinsics, Light, Pose, World, WorldError};

/// Height of the table top's upper surface above the floor, meters.
pub const TABLE_TOP: f64 = 0.75;

/// Builds the demo world: a table (`table`, with four `leg` parts), blocks on it
/// (`cube`, `wedge`, `pyramid`, `drum`) attached to the table, the camera `eye` and the
/// light `sun`.
pub fn demo_world() -> Result<World, WorldError> {
    let mut w = World::new();
    let root = w.root();
    let top_thickness = 0.05;
    let table = w.insert_with(
        Some("table"),
        root,
        Pose::from_translation(DVec3::new(0.0, 0.0, TABLE_TOP - top_thickness / 2.0)),
        |s| box_solid(s, DVec3::new(1.5, 1.0, top_thickness)),
    )?;
    let leg_h = TABLE_TOP - top_thickness;
    for (i, (x, y)) in [(0.7, 0.45), (-0.7, 0.45), (-0.7, -0.45), (0.7, -0.45)]
        .into_iter()
        .enumerate()
    {
        let z = -(top_thickness / 2.0) - leg_h / 2.0;
        w.insert_with(
            Some(&format!("leg{}", i + 1)),
            table,
            Pose::from_translation(DVec3::new(x, y, z)),
            |s| box_solid(s, DVec3::new(0.05, 0.05, leg_h)),
        )?;
    }
    let on_top = |h: f64| top_thickness / 2.0 + h / 2.0;
    w.insert_with(
        Some("cube"),
        table,
        Pose::new(
            DVec3::new(-0.35, 0.15, on_top(0.1)),
            DQuat::from_rotation_z(0.3),
        )
        .map_err(WorldError::from)?,
        |s| box_solid(s, DVec3::splat(0.1)),
    )?;
    let wedge = [
        DVec2::new(-0.08, -0.05),
        DVec2::new(0.08, -0.05),
        DVec2::new(-0.08, 0.07),
    ];
    w.insert_with(
        Some("wedge"),
        table,
        Pose::new(
            DVec3::new(0.05, -0.2, on_top(0.12)),
            DQuat::from_rotation_z(-0.5),
        )
        .map_err(WorldError::from)?,
        |s| prism_solid(s, &wedge, 0.12),
    )?;
    let square = [
        DVec2::new(-0.06, -0.06),
        DVec2::new(0.06, -0.06),
        DVec2::new(0.06, 0.06),
        DVec2::new(-0.06, 0.06),
    ];
    w.insert_with(
        Some("pyramid"),
        table,
        Pose::from_translation(DVec3::new(0.35, 0.2, on_top(0.15))),
        |s| pyramid_solid(s, &square, 0.15),
    )?;
    w.insert_with(
        Some("drum"),
        table,
        Pose::from_translation(DVec3::new(0.4, -0.25, on_top(0.08))),
        |s| cylinder(s, 0.06, 0.08, 24),
    )?;
    let eye = Camera::look_at(
        DVec3::new(1.6, -1.8, 1.7),
        DVec3::new(0.0, 0.0, TABLE_TOP),
        DVec3::Z,
        Intrinsics::centered(640, 480, 600.0)?,
    )?;
    w.set_camera("eye", eye)?;
    w.set_light("sun", Light::sun(DVec3::new(-0.3, 0.5, -1.0), 1.0)?)?;
    Ok(w)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::check_solid;

    #[test]
    fn the_demo_scene_is_valid_and_the_blocks_sit_on_the_table() {
        let w = demo_world().unwrap();
        let table = w.find_by_name("table").unwrap();
        assert_eq!(w.parts(table).unwrap().len(), 8);
        for (id, node) in w.bodies() {
            if id == w.root() {
                continue;
            }
            assert!(check_solid(&node.body, 1e-9).is_ok(), "{:?}", node.name);
        }
        for name in ["cube", "wedge", "pyramid", "drum"] {
            let b = w.find_by_name(name).unwrap();
            let lowest = w
                .body(b)
                .unwrap()
                .vertices()
                .map(|v| w.world_position(b, v).unwrap().z)
                .fold(f64::INFINITY, f64::min);
            assert!(
                (lowest - TABLE_TOP).abs() < 1e-9,
                "{name} rests on the top: {lowest}"
            );
        }
        let eye = w.camera("eye").unwrap();
        assert!(
            eye.view_direction().z < 0.0,
            "the camera looks down at the table"
        );
    }
}
