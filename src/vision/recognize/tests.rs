//! Recognition of the demo scene when something the model lacks (a box held up between
//! the camera and the drum) hides part of it: the hidden drum is `occluded`, not
//! `absent`, the rest is seen, and the box is unexplained, from edges alone and from
//! depth. (The HTTP tests recognize pictures drawn by another renderer, with bodies
//! pushed and taken away.)

use glam::DVec3;

use super::*;
use crate::model::solids::box_solid;
use crate::model::{Intrinsics, Pose, World};
use crate::render::raster::depth_image;
use crate::render::{Mode, Options, Picture, SHADED_BACKGROUND, render};
use crate::server::demo::demo_world;
use crate::vision::image::Luma;
use crate::vision::testing::Rng;

/// 640 × 480, f = 600, 2 m from the blocks on the demo table.
fn camera() -> Camera {
    let target = DVec3::new(0.0, 0.0, 0.8);
    let eye = target + DVec3::new(0.55, -0.65, 0.52).normalize() * 2.0;
    let k = Intrinsics::centered(640, 480, 600.0).expect("intrinsics");
    Camera::look_at(eye, target, DVec3::Z, k).expect("a camera")
}

/// The model with a 20 cm box held a third of the way from the drum to the camera.
fn with_screen(model: &World, camera: &Camera) -> (World, World) {
    let drum = model.find_by_name("drum").expect("the drum");
    let at = model.world_pose(drum).expect("a pose").position;
    let centre = at + (camera.position() - at) / 3.0;
    let put = |world: &mut World| {
        let root = world.root();
        world
            .insert_with(Some("screen"), root, Pose::from_translation(centre), |s| {
                box_solid(s, DVec3::splat(0.2))
            })
            .expect("a box");
    };
    let mut truth = model.clone();
    put(&mut truth);
    let mut alone = World::new();
    put(&mut alone);
    (truth, alone)
}

fn report<'a>(found: &'a Recognition, scene: &Scene, name: &str) -> &'a BodyReport {
    found
        .bodies
        .iter()
        .find(|r| scene.bodies[r.body].name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no report of {name}: {found:?}"))
}

#[test]
fn a_block_hidden_by_something_unmodeled_is_occluded_not_absent() {
    let model = demo_world().expect("the demo");
    let scene = Scene::build(&model);
    let camera = camera();
    let (truth, alone) = with_screen(&model, &camera);
    let truth_scene = Scene::build(&truth);
    let options = Options {
        background: SHADED_BACKGROUND,
        ..Options::default()
    };
    let Ok(Picture::Rgb(mut rgb)) = render(&truth_scene, &camera, Mode::Shaded, &options) else {
        panic!("a shaded picture is RGB");
    };
    let mut rng = Rng(5);
    for v in &mut rgb.data {
        *v = (*v as f64 + 6.0 * rng.normal()).round().clamp(0.0, 255.0) as u8;
    }
    let image = Luma::from_samples(rgb.width, rgb.height, 3, &rgb.data).expect("a picture");
    let view = View::new(&camera, DEFAULT_NEAR);
    let depth = depth_image(&rasterize(&truth_scene, &view), 0.001);
    let depth = DepthImage::from_units(depth.width, depth.height, &depth.data, 0.001)
        .expect("a depth picture");
    let screen = projected_areas(&Scene::build(&alone), &view)[0];
    let options = RecognizeOptions::default();
    let pyramid = EdgePyramid::new(&image, &options.align).expect("edges");
    for depth in [None, Some(&depth)] {
        let found =
            recognize(&scene, &camera, &image, &pyramid, depth, &options).expect("recognized");
        let drum = report(&found, &scene, "drum");
        assert_eq!(drum.status, Status::Occluded, "{drum:?}");
        assert!(drum.score > 0.5, "{drum:?}");
        for name in ["table", "cube", "wedge", "pyramid"] {
            let r = report(&found, &scene, name);
            assert_eq!(r.status, Status::Seen, "{name}: {r:?}");
        }
        let region = found.unexplained.first().expect("a region");
        let [u0, v0, u1, v1] = screen.bbox.expect("the screen is in view");
        let overlap = (region.bbox[2].min(u1) - region.bbox[0].max(u0)).max(0.0)
            * (region.bbox[3].min(v1) - region.bbox[1].max(v0)).max(0.0);
        assert!(
            overlap > 0.8 * (u1 - u0) * (v1 - v0) && (region.area / screen.whole - 1.0).abs() < 0.2,
            "region {region:?} for a screen of {} px² in {:?}",
            screen.whole,
            screen.bbox
        );
        for r in &found.bodies {
            assert!((0.0..=1.0).contains(&r.score), "{r:?}");
            assert!((0.0..=1.0).contains(&r.visible_fraction), "{r:?}");
        }
    }
}

#[test]
fn a_picture_of_the_model_as_it_is_shows_every_body_and_nothing_else() {
    let model = demo_world().expect("the demo");
    let scene = Scene::build(&model);
    let camera = camera();
    let options = Options {
        background: SHADED_BACKGROUND,
        ..Options::default()
    };
    let Ok(Picture::Rgb(rgb)) = render(&scene, &camera, Mode::Shaded, &options) else {
        panic!("a shaded picture is RGB");
    };
    let image = Luma::from_samples(rgb.width, rgb.height, 3, &rgb.data).expect("a picture");
    let options = RecognizeOptions::default();
    let pyramid = EdgePyramid::new(&image, &options.align).expect("edges");
    let found = recognize(&scene, &camera, &image, &pyramid, None, &options).expect("recognized");
    assert!(!found.bodies.is_empty());
    for r in &found.bodies {
        assert_eq!(r.status, Status::Seen, "{r:?}");
    }
    assert!(found.unexplained.is_empty(), "{:?}", found.unexplained);
    assert_eq!(found.unexplained_mask.count(), 0);
}
