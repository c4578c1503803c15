//! Tests of the pixel renderer against independent, analytic answers.

use glam::{DQuat, DVec2, DVec3, EulerRot};

use super::fill::{self, Band, Sink};
use super::shade::testing;
use super::*;
use crate::camera::DEFAULT_NEAR;
use crate::model::{BodyId, Camera, Color, Intrinsics, Light, Pose, World, solids};
use crate::render::scene::{SceneBody, SceneFace};

/// A world of boxes: (pose, size) each; returns the world and the body ids.
fn boxes(list: &[(Pose, [f64; 3])]) -> (World, Vec<BodyId>) {
    let mut w = World::new();
    let root = w.root();
    let ids = list
        .iter()
        .map(|&(pose, [x, y, z])| {
            w.insert_with(None, root, pose, |s| solids::mkcube(s, x, y, z))
                .unwrap()
        })
        .collect();
    (w, ids)
}

fn view(eye: DVec3, target: DVec3, up: DVec3, k: Intrinsics) -> (Camera, View) {
    let cam = Camera::look_at(eye, target, up, k).unwrap();
    (cam, View::new(&cam, DEFAULT_NEAR))
}

/// Andrew's monotone chain: the convex hull, counter-clockwise in (u, v) as numbers.
fn hull(mut pts: Vec<DVec2>) -> Vec<DVec2> {
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let mut h: Vec<DVec2> = Vec::new();
    for pass in 0..2 {
        let start = h.len();
        let it: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in it {
            while h.len() >= start + 2 {
                let (a, b) = (h[h.len() - 2], h[h.len() - 1]);
                if (b - a).perp_dot(p - a) <= 0.0 {
                    h.pop();
                } else {
                    break;
                }
            }
            h.push(p);
        }
        h.pop();
    }
    h
}

/// Signed distance of `p` to the outline of the polygon `poly` (either orientation,
/// possibly concave): positive inside, negative outside.
fn signed_distance(poly: &[DVec2], p: DVec2) -> f64 {
    let mut inside = false;
    let mut d = f64::INFINITY;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
        let t = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
        d = d.min((a + (b - a) * t - p).length());
    }
    if inside { d } else { -d }
}

/// Checks that exactly the pixels whose centres lie inside `outline` are covered,
/// ignoring centres within 1e-9 pixels of it. Returns the number covered.
fn assert_coverage(frame: &Frame, outline: &[DVec2]) -> usize {
    let mut covered = 0;
    for y in 0..frame.height {
        for x in 0..frame.width {
            let c = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            let d = signed_distance(outline, c);
            let drawn = frame.face_at(x, y).is_some();
            covered += usize::from(drawn);
            if d.abs() < 1e-9 {
                continue;
            }
            assert_eq!(drawn, d > 0.0, "pixel ({x}, {y}) at distance {d:e}");
        }
    }
    covered
}

fn general_cube() -> (World, Pose) {
    let pose = Pose {
        position: DVec3::new(0.05, -0.02, 0.03),
        rotation: DQuat::from_euler(EulerRot::XYZ, 0.3, -0.2, 0.5),
    };
    (boxes(&[(pose, [1.0, 1.0, 1.0])]).0, pose)
}

fn corners(pose: Pose, half: DVec3) -> Vec<DVec3> {
    (0..8)
        .map(|i| {
            let s = DVec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            );
            pose.transform_point(s * half)
        })
        .collect()
}

fn general_cameras() -> Vec<(Camera, View)> {
    let k = Intrinsics::new(161, 123, 151.3, 149.7, 80.37, 61.11).unwrap();
    vec![
        view(
            DVec3::new(2.3, -3.1, 1.7),
            DVec3::new(0.1, 0.05, -0.07),
            DVec3::Z,
            k,
        ),
        view(
            DVec3::new(-1.9, 1.3, -2.2),
            DVec3::new(-0.2, 0.1, 0.15),
            DVec3::new(0.1, 0.2, 1.0),
            k,
        ),
        view(
            DVec3::new(0.4, 0.3, 2.6),
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::X,
            Intrinsics::centered(97, 131, 120.0).unwrap(),
        ),
    ]
}

#[test]
fn a_cube_covers_exactly_the_pixels_whose_centres_are_inside_its_outline() {
    let (world, pose) = general_cube();
    let scene = Scene::build(&world);
    for (cam, view) in general_cameras() {
        let frame = rasterize(&scene, &view);
        let outline = hull(
            corners(pose, DVec3::splat(0.5))
                .iter()
                .map(|&p| cam.project(p).unwrap())
                .collect(),
        );
        let covered = assert_coverage(&frame, &outline);
        assert!(covered > 500, "the cube covers only {covered} pixels");
    }
}

#[test]
fn depth_is_the_distance_along_each_pixel_ray_to_the_cube() {
    let (world, pose) = general_cube();
    let scene = Scene::build(&world);
    // The cube's six planes, outward: n·p ≤ d inside.
    let planes: Vec<(DVec3, f64)> = [DVec3::X, DVec3::Y, DVec3::Z]
        .iter()
        .flat_map(|&a| [a, -a])
        .map(|a| {
            let n = pose.rotation * a;
            (n, n.dot(pose.position) + 0.5)
        })
        .collect();
    for (cam, view) in general_cameras() {
        let frame = rasterize(&scene, &view);
        let (w, h) = (frame.width, frame.height);
        let mut checked = 0;
        for y in 0..h {
            for x in 0..w {
                let Some(_) = frame.face_at(x, y) else {
                    continue;
                };
                let dir = cam.pixel_ray(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
                let eye = cam.position();
                // Entry into the convex cube: the last plane crossed going in.
                let t = planes
                    .iter()
                    .filter(|(n, _)| n.dot(dir) < 0.0)
                    .map(|&(n, d)| (d - n.dot(eye)) / n.dot(dir))
                    .fold(f64::NEG_INFINITY, f64::max);
                let depth = t * dir.dot(-cam.k());
                let got = frame.depth_at(x, y) as f64;
                assert!(
                    ((got - depth) / depth).abs() < 1e-6,
                    "pixel ({x}, {y}): depth {got}, expected {depth}"
                );
                checked += 1;
            }
        }
        assert!(checked > 500);
        // And the centre pixel in particular.
        let (x, y) = (w / 2, h / 2);
        assert!(frame.depth_at(x, y).is_finite(), "centre pixel not covered");
    }
}

/// Pixels whose face belongs to body `id` and has outward normal `normal`.
fn face_pixels(scene: &Scene, frame: &Frame, id: BodyId, normal: DVec3) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for y in 0..frame.height {
        for x in 0..frame.width {
            if let Some(f) = frame.face_at(x, y) {
                let face = &scene.faces[f as usize];
                if scene.bodies[face.body as usize].id == id
                    && (face.normal - normal).length() < 1e-9
                {
                    out.push((x, y));
                }
            }
        }
    }
    out
}

fn mean_brightness(img: &RgbImage, pixels: &[(u32, u32)]) -> f64 {
    let sum: f64 = pixels
        .iter()
        .map(|&(x, y)| img.get(x, y).iter().map(|&c| c as f64).sum::<f64>())
        .sum();
    sum / pixels.len() as f64
}

fn assert_all_near(img: &RgbImage, pixels: &[(u32, u32)], want: [u8; 3]) {
    assert!(!pixels.is_empty());
    for &(x, y) in pixels {
        let got = img.get(x, y);
        for k in 0..3 {
            assert!(
                (got[k] as i32 - want[k] as i32).abs() <= 1,
                "pixel ({x}, {y}) is {got:?}, expected {want:?}"
            );
        }
    }
}

/// A small cube at the origin, optionally under a big slab 3 m up, lit by `light`: the
/// world, its body ids (cube first), and a view of the cube from the side.
fn slab_world(slab: bool, light: Light) -> (World, Vec<BodyId>, View) {
    let mut list = vec![(Pose::IDENTITY, [1.0, 1.0, 1.0])];
    if slab {
        list.push((
            Pose::from_translation(DVec3::new(0.0, 0.0, 3.0)),
            [6.0, 6.0, 0.2],
        ));
    }
    let (mut world, ids) = boxes(&list);
    world.set_light("light", light).unwrap();
    let k = Intrinsics::centered(160, 120, 150.0).unwrap();
    let (_, view) = view(DVec3::new(4.0, -3.5, 1.2), DVec3::ZERO, DVec3::Z, k);
    (world, ids, view)
}

/// [`slab_world`]'s cube in a colour: the shaded image from the side and the top face's
/// pixels.
fn under_slab(slab: bool, light: Light) -> (RgbImage, Vec<(u32, u32)>, [u8; 3]) {
    let (mut world, ids, view) = slab_world(slab, light);
    world
        .set_color(ids[0], Some(Color([180, 120, 60])))
        .unwrap();
    let scene = Scene::build(&world);
    let frame = rasterize(&scene, &view);
    let top = face_pixels(&scene, &frame, ids[0], DVec3::Z);
    assert!(top.len() > 100, "top face barely visible: {}", top.len());
    let img = shaded(&scene, &view, &Shading::default());
    (img, top, [180, 120, 60])
}

#[test]
fn a_cube_in_the_shadow_of_a_slab_is_darker_than_in_the_open() {
    let sun = Light::sun(DVec3::new(0.1, 0.05, -1.0), 0.9).unwrap();
    let toward = -DVec3::new(0.1, 0.05, -1.0).normalize();
    let (open, top, color) = under_slab(false, sun);
    let (shade, top2, _) = under_slab(true, sun);
    assert_eq!(top, top2);
    assert!(mean_brightness(&shade, &top) < mean_brightness(&open, &top) - 30.0);
    // In the open every pixel of the top face is fully lit (no shadow acne); under the
    // slab every one is in shadow, ambient only.
    assert_all_near(&open, &top, testing::lit(color, 0.25 + 0.9 * toward.z));
    assert_all_near(&shade, &top, testing::lit(color, 0.25));
}

#[test]
fn a_kept_sun_map_settles_whole_faces_as_the_pixels_would() {
    // The cube under the slab: the sun sees none of the cube's top and all of the slab's.
    let sun = Light::sun(DVec3::new(0.1, 0.05, -1.0), 0.9).unwrap();
    let (world, ids, view) = slab_world(true, sun);
    let scene = Scene::build(&world);
    assert_eq!(
        testing::face_classes(&scene, 0),
        None,
        "made before any picture"
    );
    let whole = shaded(&scene, &view, &Shading::default());
    let classes = testing::face_classes(&scene, 0).expect("the kept map");
    assert_eq!(classes.len(), scene.faces.len());
    let top = |id: BodyId| {
        let f = scene
            .faces
            .iter()
            .position(|f| {
                scene.bodies[f.body as usize].id == id && (f.normal - DVec3::Z).length() < 1e-9
            })
            .unwrap();
        classes[f]
    };
    assert_eq!(top(ids[0]), testing::FACE_DARK);
    assert_eq!(top(ids[1]), testing::FACE_LIT);
    // Faces turned away from the sun are left to the pixels (which give them nothing).
    for (f, face) in scene.faces.iter().enumerate() {
        if face.normal.z < -0.5 {
            assert_eq!(classes[f], 0, "face {f} turned away");
        }
    }
    // And the picture is the one testing every pixel on its own.
    let each = shade::shaded_with(&scene, &view, &Shading::default(), usize::MAX);
    assert_eq!(whole, each);
}

#[test]
fn whole_face_classes_leave_a_block_world_unchanged() {
    // No floor: bodies shadow one another's sides, partly or wholly.
    let world = crate::render::sample::blocks(300, 7).unwrap();
    let scene = Scene::build(&world);
    let views: Vec<View> = crate::render::sample::ring_cameras(300, 4, 320, 240)
        .iter()
        .map(|c| View::new(c, DEFAULT_NEAR))
        .collect();
    let mut settled = 0;
    for view in &views {
        let whole = shaded(&scene, view, &Shading::default());
        let each = shade::shaded_with(&scene, view, &Shading::default(), usize::MAX);
        assert_eq!(whole, each);
    }
    for (light, (_, sun)) in scene.lights.iter().enumerate() {
        let Light::Sun { direction, .. } = *sun else {
            panic!("blocks are lit by suns");
        };
        let classes = testing::face_classes(&scene, light).expect("a kept map");
        let lit = classes.iter().filter(|&&c| c == testing::FACE_LIT).count();
        let toward_sun = scene
            .faces
            .iter()
            .filter(|f| f.normal.dot(-direction.normalize()) > 1e-6)
            .count();
        settled += lit;
        // Not every face turned toward the sun: some are partly in another body's shadow.
        assert!(lit < toward_sun, "{lit} of {toward_sun} faces");
    }
    assert!(
        settled > scene.faces.len() / 4,
        "only {settled} faces settled"
    );
}

#[test]
fn runs_of_faces_end_where_the_value_changes() {
    let mut rng = crate::render::sample::SplitMix64::new(3);
    for len in 1..70 {
        let faces: Vec<u32> = (0..len).map(|_| (rng.next_u64() % 3) as u32).collect();
        let long: Vec<u32> = (0..len).map(|i| (i / 13) as u32).collect();
        for f in [&faces, &long] {
            for x in 0..len {
                let naive = (x + 1..len).find(|&i| f[i] != f[x]).unwrap_or(len);
                assert_eq!(testing::run_end(f, x), naive, "{f:?} from {x}");
            }
        }
    }
}

#[test]
fn filling_a_run_writes_the_colour_into_every_pixel() {
    for n in 0..50 {
        let mut run = vec![7u8; 3 * n + 3];
        testing::fill_rgb(&mut run[..3 * n], [1, 2, 3]);
        for (i, px) in run.chunks(3).enumerate() {
            let want = if i < n { [1, 2, 3] } else { [7, 7, 7] };
            assert_eq!(px, want, "pixel {i} of {n}");
        }
    }
}

#[test]
fn a_polygons_extent_over_a_slab_comes_from_its_clipped_edges() {
    // A diamond with corners (0, 2), (2, 0), (4, 2), (2, 4).
    let diamond = [[0.0, 2.0], [2.0, 0.0], [4.0, 2.0], [2.0, 4.0]];
    assert_eq!(testing::slab_extent(&diamond, 1.0, 1.5), Some((0.5, 3.5)));
    assert_eq!(testing::slab_extent(&diamond, 1.5, 2.5), Some((0.0, 4.0)));
    assert_eq!(testing::slab_extent(&diamond, -1.0, 0.5), Some((1.5, 2.5)));
    assert_eq!(testing::slab_extent(&diamond, 4.5, 5.0), None);
    // A slab inside a tall rectangle, which no corner reaches.
    let tall = [[1.0, 0.0], [3.0, 0.0], [3.0, 10.0], [1.0, 10.0]];
    assert_eq!(testing::slab_extent(&tall, 4.0, 5.0), Some((1.0, 3.0)));
}

/// How many pixels of `a` and `b` differ by more than 2 in some channel.
fn differing(a: &RgbImage, b: &RgbImage) -> usize {
    assert_eq!((a.width, a.height), (b.width, b.height));
    a.data
        .chunks(3)
        .zip(b.data.chunks(3))
        .filter(|(p, q)| p.iter().zip(*q).any(|(x, y)| x.abs_diff(*y) > 2))
        .count()
}

#[test]
fn testing_runs_of_pixels_as_a_whole_gives_the_pixel_by_pixel_picture() {
    // Blocks standing on a floor, which takes most of their shadows.
    let mut world = crate::render::sample::blocks(400, 3).unwrap();
    let side = crate::render::sample::blocks_extent(400) + 10.0;
    let root = world.root();
    world
        .insert_with(
            None,
            root,
            Pose::from_translation(DVec3::new(0.0, 0.0, -0.1)),
            |s| solids::mkcube(s, side, side, 0.2),
        )
        .unwrap();
    let scene = Scene::build(&world);
    for cam in crate::render::sample::ring_cameras(400, 4, 320, 240) {
        let view = View::new(&cam, DEFAULT_NEAR);
        let whole = shade::shaded_with(&scene, &view, &Shading::default(), 2);
        let each = shade::shaded_with(&scene, &view, &Shading::default(), usize::MAX);
        // Shadows are there to be tested.
        let open = Shading {
            shadows: false,
            ..Shading::default()
        };
        let shadowed = differing(&each, &shaded(&scene, &view, &open));
        assert!(shadowed > 1000, "only {shadowed} pixels in shadow");
        assert_eq!(differing(&whole, &each), 0);
    }
}

#[test]
fn kept_shadow_maps_are_made_once_and_agree_with_fresh_ones() {
    let world = crate::render::sample::blocks(200, 5).unwrap();
    let scene = Scene::build(&world);
    let suns = scene.lights.len();
    assert!(suns >= 1);
    assert!(scene.shadows.is_empty());
    let cams = crate::render::sample::ring_cameras(200, 3, 320, 240);
    let views: Vec<View> = cams.iter().map(|c| View::new(c, DEFAULT_NEAR)).collect();
    let first: Vec<RgbImage> = views
        .iter()
        .map(|v| shaded(&scene, v, &Shading::default()))
        .collect();
    assert_eq!(scene.shadows.len(), suns);
    for (v, img) in views.iter().zip(&first) {
        assert_eq!(&shaded(&scene, v, &Shading::default()), img);
        // Maps fitted to the picture, made fresh: the same shadows up to the texels.
        let fresh = Shading {
            shadow_map_size: 1024,
            ..Shading::default()
        };
        let differ = differing(&shaded(&scene, v, &fresh), img);
        assert!(
            differ * 100 < img.data.len() / 3,
            "{differ} pixels differ with fresh maps"
        );
    }
    assert_eq!(scene.shadows.len(), suns);
    let mut copy = scene.clone();
    assert!(copy.shadows.is_empty());
    shaded(&copy, &views[0], &Shading::default());
    assert_eq!(copy.shadows.len(), suns);
    copy.shadows.clear();
    assert!(copy.shadows.is_empty());
}

#[test]
fn a_close_up_of_a_large_world_gets_a_sun_map_fitted_to_it() {
    // The cube under the slab of `under_slab`, with a block 2 km away behind the camera:
    // the map kept for the whole world has texels of a metre, too coarse for the picture.
    let sun = Light::sun(DVec3::new(0.1, 0.05, -1.0), 0.9).unwrap();
    let (mut world, ids) = boxes(&[
        (Pose::IDENTITY, [1.0, 1.0, 1.0]),
        (
            Pose::from_translation(DVec3::new(0.0, 0.0, 3.0)),
            [6.0, 6.0, 0.2],
        ),
        (
            Pose::from_translation(DVec3::new(1500.0, -1500.0, 0.0)),
            [10.0, 10.0, 1.0],
        ),
    ]);
    world.set_light("light", sun).unwrap();
    let scene = Scene::build(&world);
    let k = Intrinsics::centered(160, 120, 150.0).unwrap();
    let (_, view) = view(DVec3::new(4.0, -3.5, 1.2), DVec3::ZERO, DVec3::Z, k);
    let img = shaded(&scene, &view, &Shading::default());
    // Exactly the picture made with a fresh map fitted to it (¾ of 160, at least 256).
    let fitted = Shading {
        shadow_map_size: 256,
        ..Shading::default()
    };
    assert_eq!(differing(&img, &shaded(&scene, &view, &fitted)), 0);
    let frame = rasterize(&scene, &view);
    let top = face_pixels(&scene, &frame, ids[0], DVec3::Z);
    assert_all_near(&img, &top, testing::lit(scene.bodies[0].color.0, 0.25));
}

#[test]
fn a_point_light_above_a_slab_leaves_the_cube_in_shadow() {
    let lamp = Light::point(DVec3::new(0.2, 0.1, 6.0), 30.0).unwrap();
    let (open, top, _) = under_slab(false, lamp);
    let (shade, _, color) = under_slab(true, lamp);
    assert!(mean_brightness(&shade, &top) < mean_brightness(&open, &top) - 30.0);
    assert_all_near(&shade, &top, testing::lit(color, 0.25));
}

#[test]
fn a_face_turned_away_from_every_light_shows_ambient_only() {
    let (mut world, ids) = boxes(&[(Pose::IDENTITY, [1.0, 1.0, 1.0])]);
    world
        .set_color(ids[0], Some(Color([90, 160, 220])))
        .unwrap();
    let dir = DVec3::new(1.0, 0.5, -1.0);
    world
        .set_light("sun", Light::sun(dir, 0.7).unwrap())
        .unwrap();
    // A lamp low on the −x, −y side: it too sees neither +x nor +y.
    let lamp = Light::point(DVec3::new(-3.0, -2.0, 0.2), 4.0).unwrap();
    world.set_light("lamp", lamp).unwrap();
    let scene = Scene::build(&world);
    let k = Intrinsics::centered(160, 120, 150.0).unwrap();
    let (_, view) = view(DVec3::new(3.0, 2.5, 2.0), DVec3::ZERO, DVec3::Z, k);
    let frame = rasterize(&scene, &view);
    let img = shaded(&scene, &view, &Shading::default());
    let ambient = testing::lit([90, 160, 220], 0.25);
    for n in [DVec3::X, DVec3::Y] {
        assert_all_near(&img, &face_pixels(&scene, &frame, ids[0], n), ambient);
    }
    // The top is lit by the sun (the lamp is below its plane's reach: z 0.2 < 0.5).
    let toward = -dir.normalize();
    let top = face_pixels(&scene, &frame, ids[0], DVec3::Z);
    assert_all_near(
        &img,
        &top,
        testing::lit([90, 160, 220], 0.25 + 0.7 * toward.z),
    );
}

#[test]
fn a_world_without_lights_gets_a_default_sun() {
    let (world, _) = boxes(&[(Pose::IDENTITY, [1.0, 1.0, 1.0])]);
    let scene = Scene::build(&world);
    let k = Intrinsics::centered(64, 48, 60.0).unwrap();
    let (_, view) = view(DVec3::new(3.0, -2.0, 2.0), DVec3::ZERO, DVec3::Z, k);
    let frame = rasterize(&scene, &view);
    let img = shaded(&scene, &view, &Shading::default());
    let color = scene.bodies[0].color.0;
    let ambient = testing::lit(color, 0.25);
    let brighter = (0..img.height)
        .flat_map(|y| (0..img.width).map(move |x| (x, y)))
        .filter(|&(x, y)| frame.face_at(x, y).is_some())
        .filter(|&(x, y)| {
            let sum = |c: [u8; 3]| c.iter().map(|&v| v as u32).sum::<u32>();
            sum(img.get(x, y)) > sum(ambient)
        })
        .count();
    assert!(brighter > 100, "only {brighter} pixels are lit");
}

#[test]
fn a_camera_inside_a_cube_sees_nothing_and_does_not_panic() {
    let (world, _) = boxes(&[(Pose::IDENTITY, [2.0, 2.0, 2.0])]);
    let scene = Scene::build(&world);
    let k = Intrinsics::centered(64, 48, 40.0).unwrap();
    let (_, view) = view(
        DVec3::new(0.1, 0.05, 0.0),
        DVec3::new(1.0, 0.3, 0.2),
        DVec3::Z,
        k,
    );
    let frame = rasterize(&scene, &view);
    assert!(frame.face.iter().all(|&f| f == NO_FACE));
    assert!(frame.depth.iter().all(|d| *d == f32::INFINITY));
    let shading = Shading::default();
    let img = shaded(&scene, &view, &shading);
    assert_eq!(img, RgbImage::filled(64, 48, shading.background));
    assert!(depth_image(&frame, 0.001).data.iter().all(|&v| v == 0));
    let (ids, legend) = ids_image(&scene, &frame).unwrap();
    assert!(legend.is_empty() && ids.data.iter().all(|&v| v == 0));
    // The edges around the camera are in front of it: the wireframe shows them.
    let lines = wire(&scene, &view, [0; 3], [255; 3]);
    assert!(lines.data.iter().any(|&c| c > 0));
}

#[test]
fn a_camera_looking_away_from_everything_sees_nothing() {
    let (world, _) = boxes(&[(Pose::IDENTITY, [1.0, 1.0, 1.0])]);
    let scene = Scene::build(&world);
    let k = Intrinsics::centered(64, 48, 40.0).unwrap();
    let (_, view) = view(
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::new(0.0, 0.0, 10.0),
        DVec3::Y,
        k,
    );
    let frame = rasterize(&scene, &view);
    assert!(frame.face.iter().all(|&f| f == NO_FACE));
    assert_eq!(
        shaded(&scene, &view, &Shading::default()),
        RgbImage::filled(64, 48, Shading::default().background)
    );
    assert_eq!(
        wire(&scene, &view, [1, 2, 3], [255; 3]),
        RgbImage::filled(64, 48, [1, 2, 3])
    );
}

#[test]
fn a_one_pixel_image_shows_the_cube_in_front() {
    let (world, _) = boxes(&[(Pose::IDENTITY, [1.0, 1.0, 1.0])]);
    let scene = Scene::build(&world);
    let k = Intrinsics::centered(1, 1, 2.0).unwrap();
    let (_, view) = view(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y, k);
    let frame = rasterize(&scene, &view);
    assert!(frame.face_at(0, 0).is_some());
    assert!((frame.depth_at(0, 0) - 4.5).abs() < 1e-6);
    let img = shaded(&scene, &view, &Shading::default());
    assert_ne!(img.get(0, 0), Shading::default().background);
    assert_eq!(depth_image(&frame, 0.01).data, vec![450]);
    let (ids, legend) = ids_image(&scene, &frame).unwrap();
    assert_eq!((ids.data, legend), (vec![1], vec![scene.bodies[0].id]));
    let _ = wire(&scene, &view, [0; 3], [255; 3]);
}

#[test]
fn a_zero_sized_view_gives_empty_images() {
    let (world, _) = boxes(&[(Pose::IDENTITY, [1.0, 1.0, 1.0])]);
    let scene = Scene::build(&world);
    let k = Intrinsics::centered(4, 4, 2.0).unwrap();
    let (_, mut view) = view(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y, k);
    view.intrinsics.width = 0;
    let frame = rasterize(&scene, &view);
    assert!(frame.face.is_empty() && frame.depth.is_empty());
    assert!(shaded(&scene, &view, &Shading::default()).data.is_empty());
    assert!(wire(&scene, &view, [0; 3], [255; 3]).data.is_empty());
    assert!(depth_image(&frame, 1.0).data.is_empty());
    assert!(ids_image(&scene, &frame).unwrap().1.is_empty());
}

#[test]
fn a_floor_crossing_the_near_plane_is_clipped_not_dropped() {
    // A 200 m floor whose top (z = 0.5) is two triangles reaching far behind the camera.
    let (world, ids) = boxes(&[(Pose::IDENTITY, [200.0, 200.0, 1.0])]);
    let scene = Scene::build(&world);
    let k = Intrinsics::centered(64, 48, 40.0).unwrap();
    let (cam, view) = view(
        DVec3::new(0.0, 0.0, 1.5),
        DVec3::new(10.0, 1.0, 0.5),
        DVec3::Z,
        k,
    );
    let frame = rasterize(&scene, &view);
    let mut floor = 0;
    for y in 0..48 {
        for x in 0..64 {
            let dir = cam.pixel_ray(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
            let got = frame.face_at(x, y);
            if dir.z >= -1e-6 {
                assert_eq!(got, None, "pixel ({x}, {y}) above the horizon");
                continue;
            }
            let t = -1.0 / dir.z;
            let hit = cam.position() + dir * t;
            if hit.x.abs() > 99.999 || hit.y.abs() > 99.999 {
                continue;
            }
            let f = got.expect("the floor");
            assert_eq!(
                scene.bodies[scene.faces[f as usize].body as usize].id,
                ids[0]
            );
            let depth = t * dir.dot(-cam.k());
            let rel = (frame.depth_at(x, y) as f64 - depth).abs() / depth;
            assert!(rel < 1e-6, "pixel ({x}, {y}): {rel:e}");
            floor += 1;
        }
    }
    assert!(floor > 500);
}

#[test]
fn the_ids_image_shows_the_front_cube_where_two_overlap() {
    let front = (Pose::IDENTITY, [1.0, 1.0, 1.0]);
    let back = (
        Pose::from_translation(DVec3::new(-3.0, 0.8, 0.1)),
        [1.5, 1.5, 1.5],
    );
    let k = Intrinsics::centered(120, 90, 100.0).unwrap();
    let (_, view) = view(
        DVec3::new(5.0, 0.3, 0.2),
        DVec3::new(-3.0, 0.0, 0.0),
        DVec3::Z,
        k,
    );
    let mask = |list: &[(Pose, [f64; 3])]| {
        let scene = Scene::build(&boxes(list).0);
        rasterize(&scene, &view)
            .face
            .iter()
            .map(|&f| f != NO_FACE)
            .collect::<Vec<_>>()
    };
    let (only_front, only_back) = (mask(&[front]), mask(&[back]));
    let (world, ids) = boxes(&[front, back]);
    let scene = Scene::build(&world);
    let frame = rasterize(&scene, &view);
    let (img, legend) = ids_image(&scene, &frame).unwrap();
    assert_eq!(legend, ids, "both bodies appear, in id order");
    let (mut overlap, mut behind) = (0, 0);
    for i in 0..img.data.len() {
        let want = match (only_front[i], only_back[i]) {
            (true, _) => 1,
            (false, true) => 2,
            (false, false) => 0,
        };
        assert_eq!(img.data[i], want, "pixel {i}");
        overlap += usize::from(only_front[i] && only_back[i]);
        behind += usize::from(!only_front[i] && only_back[i]);
    }
    assert!(
        overlap > 50 && behind > 50,
        "overlap {overlap}, back alone {behind}"
    );
}

#[test]
fn a_concave_prism_shows_its_notch_as_background() {
    let l = crate::render::sample::L_SHAPE;
    let mut world = World::new();
    let root = world.root();
    world
        .insert_with(None, root, Pose::IDENTITY, |s| {
            solids::prism_solid(s, &l, 1.0)
        })
        .unwrap();
    let scene = Scene::build(&world);
    let k = Intrinsics::new(120, 120, 400.0, 400.0, 60.3, 59.8).unwrap();
    let (cam, view) = view(
        DVec3::new(0.8, 0.7, 10.0),
        DVec3::new(0.8, 0.7, 0.0),
        DVec3::Y,
        k,
    );
    let frame = rasterize(&scene, &view);
    // Only the top (z = 0.5) faces the camera; its outline is the projected L.
    let outline: Vec<DVec2> = l
        .iter()
        .map(|p| cam.project(DVec3::new(p.x, p.y, 0.5)).unwrap())
        .collect();
    assert!(assert_coverage(&frame, &outline) > 1000);
    let notch = cam.project(DVec3::new(1.5, 1.5, 0.5)).unwrap();
    assert_eq!(frame.face_at(notch.x as u32, notch.y as u32), None);
}

#[test]
fn wire_draws_every_edge_front_and_back() {
    let (world, _) = boxes(&[(Pose::IDENTITY, [1.0, 1.0, 1.0])]);
    let scene = Scene::build(&world);
    let k = Intrinsics::centered(120, 90, 100.0).unwrap();
    let (cam, view) = view(DVec3::new(3.0, -2.0, 1.5), DVec3::ZERO, DVec3::Z, k);
    let img = wire(&scene, &view, [0; 3], [255; 3]);
    // Ink at the middle of every edge, the hidden ones included.
    for e in &scene.edges {
        let [a, b] = e.ends.map(|i| scene.points[i as usize]);
        let m = cam.project((a + b) / 2.0).unwrap();
        let (x, y) = (m.x as u32, m.y as u32);
        let ink: u32 = (y - 1..=y + 1)
            .flat_map(|yy| (x - 1..=x + 1).map(move |xx| (xx, yy)))
            .map(|(xx, yy)| img.get(xx, yy)[0] as u32)
            .sum();
        assert!(ink > 200, "no ink at the middle of an edge ({x}, {y})");
    }
    // Nothing far from the cube.
    assert_eq!(img.get(2, 2), [0; 3]);
    // The same picture as one sequential pass.
    let mut one = RgbImage::filled(120, 90, [0; 3]);
    for e in &scene.edges {
        let [a, b] = e.ends.map(|i| view.to_camera(scene.points[i as usize]));
        if let Some((t0, t1)) = view.clip_segment(a, b) {
            crate::render::lines::draw_line(
                &mut one,
                view.project(a.lerp(b, t0)),
                view.project(a.lerp(b, t1)),
                [255; 3],
            );
        }
    }
    let differ = one
        .data
        .iter()
        .zip(&img.data)
        .filter(|(a, b)| a.abs_diff(**b) > 1)
        .count();
    assert_eq!(differ, 0);
}

#[test]
fn depth_images_scale_round_and_clamp() {
    let frame = Frame {
        width: 5,
        height: 1,
        depth: vec![f32::INFINITY, 0.0004, 1.0, 1e9, 2.5004],
        face: vec![NO_FACE, 0, 0, 0, 0],
    };
    assert_eq!(
        depth_image(&frame, 0.001).data,
        vec![0, 1, 1000, 65535, 2500]
    );
}

#[test]
fn ids_refuses_more_than_65535_bodies() {
    let n = 65536;
    let mut scene = Scene::default();
    for i in 0..n {
        scene.bodies.push(SceneBody {
            id: BodyId(crate::model::Serial(i as u64 + 1)),
            name: None,
            color: Color([0; 3]),
            provisional: false,
            outline_px: 0.0,
        });
        scene.faces.push(SceneFace {
            body: i as u32,
            serial: 0,
            normal: DVec3::Z,
            offset: 0.0,
            ring: 0..0,
        });
    }
    let mut frame = Frame {
        width: n as u32,
        height: 1,
        depth: vec![1.0; n],
        face: (0..n as u32).collect(),
    };
    assert_eq!(
        ids_image(&scene, &frame),
        Err(IdsError::TooManyBodies { count: n })
    );
    frame.face[0] = NO_FACE;
    let (img, legend) = ids_image(&scene, &frame).unwrap();
    assert_eq!(legend.len(), 65535);
    assert_eq!((img.data[0], img.data[1], img.data[n - 1]), (0, 1, 65535));
}

/// Counts how often each pixel is filled.
struct Count<'a>(&'a mut [u32]);

impl Sink for Count<'_> {
    fn clear(&mut self) {
        self.0.fill(0);
    }

    fn plot(&mut self, i: usize, key: f32, _face: u32) {
        self.0[i] += u32::from(key > 0.0);
    }
}

/// Fills `tris` into a `w × h` counter.
fn counts(w: usize, h: usize, tris: &[[DVec2; 3]]) -> Vec<u32> {
    let mut n = vec![0; w * h];
    let mut band = Band {
        y0: 0,
        rows: h,
        width: w,
        sink: Count(&mut n),
    };
    for t in tris {
        fill::fill(&mut band, t.map(|p| [p.x, p.y]), [0.0, 0.0, 1.0], 0);
    }
    n
}

#[test]
fn shared_edges_are_filled_exactly_once() {
    // A rectangle [x0, x1) × [y0, y1) cut into triangles in several ways, with many pixel
    // centres exactly on shared edges and corners: every centre inside (top and left
    // borders included, bottom and right excluded) is filled exactly once.
    let (w, h) = (48usize, 40usize);
    let mut rng = crate::render::sample::SplitMix64::new(3);
    for case in 0..4 {
        let (nx, ny) = (8usize, 6usize);
        let (x0, y0, sx, sy) = match case {
            0 => (4.5, 3.5, 4.0, 5.0),
            1 => (2.0, 1.0, 5.0, 6.0),
            _ => (3.25, 2.75, 4.75, 5.5),
        };
        let grid = |i: usize, j: usize, rng: &mut crate::render::sample::SplitMix64| {
            let mut p = DVec2::new(x0 + sx * i as f64, y0 + sy * j as f64);
            if case == 3 && i > 0 && j > 0 && i < nx && j < ny {
                p += DVec2::new(rng.range(-1.5, 1.5), rng.range(-1.5, 1.5));
            }
            p
        };
        let pts: Vec<Vec<DVec2>> = (0..=nx)
            .map(|i| (0..=ny).map(|j| grid(i, j, &mut rng)).collect())
            .collect();
        let mut tris = Vec::new();
        for i in 0..nx {
            for j in 0..ny {
                let (a, b, c, d) = (pts[i][j], pts[i + 1][j], pts[i + 1][j + 1], pts[i][j + 1]);
                // Alternate diagonals and windings.
                let pair = if (i + j) % 2 == 0 {
                    [[a, b, c], [a, d, c]]
                } else {
                    [[a, b, d], [c, d, b]]
                };
                tris.extend(pair);
            }
        }
        let n = counts(w, h, &tris);
        let (x1, y1) = (x0 + sx * nx as f64, y0 + sy * ny as f64);
        for y in 0..h {
            for x in 0..w {
                let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                let want = u32::from(px >= x0 && px < x1 && py >= y0 && py < y1);
                assert_eq!(n[y * w + x], want, "case {case}, pixel ({x}, {y})");
            }
        }
    }
}

#[test]
fn a_fan_around_a_pixel_centre_fills_it_once() {
    // Eight triangles meeting at the centre of pixel (10, 10), spokes through centres.
    let c = DVec2::new(10.5, 10.5);
    let ring: Vec<DVec2> = (0..8)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 8.0;
            c + DVec2::new(a.cos(), a.sin()) * 6.0
        })
        .map(|p| DVec2::new(p.x.round() + 0.5, p.y.round() + 0.5))
        .collect();
    let tris: Vec<[DVec2; 3]> = (0..8).map(|k| [c, ring[k], ring[(k + 1) % 8]]).collect();
    let n = counts(24, 24, &tris);
    assert_eq!(n[10 * 24 + 10], 1);
    assert!(n.iter().all(|&k| k <= 1));
}
