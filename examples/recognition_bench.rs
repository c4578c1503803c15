//! The recognition benchmark's scenes and winged's runs on them (see
//! `bench/recognition/README.md` for the whole protocol).
//!
//! ```sh
//! cargo run --release --example recognition_bench -- scenes DIR [--count 300] [--seed 1] [--clutter]
//! cargo run --release --example recognition_bench -- run DIR [--only N]
//! ```
//!
//! `scenes` writes `DIR/scene_NNN.json`: the model world (as the server would hold it),
//! the truth (the model with some bodies pushed by 1–10 cm and turned by 1–10°, some
//! taken away, and distractors the model lacks put on the table), the truth's triangles
//! for another renderer to draw, the exact camera and one off by up to 2° and 5 cm, and
//! every model body's fate. `--clutter` puts the bodies 1 cm apart (not 12) and the
//! camera 10–30° above the table (not 25–60°), so that bodies hide each other.
//! `bench/recognition/render.py` draws the pictures.
//!
//! `run` recognizes every scene's picture with the exact camera (without and with
//! depth) and with the rough camera (`refine_camera`), and writes
//! `DIR/winged_NNN.json`: per run the reports, the unexplained mask's pixels (run-length
//! coded), and the time (decoding the PNGs, finding edges, recognizing). It also writes
//! each body's predicted visible edge points (`DIR/edges_NNN.json`), the templates of the
//! chamfer baseline, and the model as winged draws it with the body covering each pixel
//! (`DIR/model_NNN.png`, `DIR/model_bodies_NNN.png`), the templates of LINE-2D.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::{DQuat, DVec2, DVec3};
use serde_json::{Value, json};
use winged::camera::{DEFAULT_NEAR, View};
use winged::model::solids::{box_solid, cylinder, prism_solid, pyramid_solid};
use winged::model::{Camera, Intrinsics, Pose, World};
use winged::render::hidden::hidden_lines;
use winged::render::{Mode, Options, Picture, SHADED_BACKGROUND, Scene, render};
use winged::vision::image::Luma;
use winged::vision::recognize::{DepthImage, RecognizeOptions, recognize};
use winged::vision::solve::align::{EdgePyramid, align_camera};

/// SplitMix64: the same scenes from the same seed on every machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next() >> 11) as f64 / (1u64 << 53) as f64)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn sign(&mut self) -> f64 {
        if self.next() & 1 == 0 { 1.0 } else { -1.0 }
    }
}

const TABLE_TOP: f64 = 0.75;
const TABLE: DVec2 = DVec2::new(1.2, 0.8);

/// One body to put on the table: its kind and size, and a radius that bounds it in plan.
#[derive(Clone, Copy)]
enum Kind {
    Box(DVec3),
    Prism {
        sides: usize,
        radius: f64,
        height: f64,
    },
    Cylinder {
        radius: f64,
        height: f64,
        sides: usize,
    },
    Pyramid {
        half: f64,
        height: f64,
    },
    Ell {
        size: f64,
        height: f64,
    },
}

impl Kind {
    fn random(rng: &mut Rng) -> Kind {
        match rng.below(5) {
            0 => Kind::Box(DVec3::new(
                rng.range(0.05, 0.15),
                rng.range(0.05, 0.15),
                rng.range(0.05, 0.2),
            )),
            1 => Kind::Prism {
                sides: [3, 5, 6][rng.below(3)],
                radius: rng.range(0.04, 0.08),
                height: rng.range(0.05, 0.15),
            },
            2 => Kind::Cylinder {
                radius: rng.range(0.03, 0.07),
                height: rng.range(0.05, 0.2),
                sides: 24,
            },
            3 => Kind::Pyramid {
                half: rng.range(0.04, 0.07),
                height: rng.range(0.06, 0.15),
            },
            _ => Kind::Ell {
                size: rng.range(0.08, 0.14),
                height: rng.range(0.04, 0.1),
            },
        }
    }

    fn height(&self) -> f64 {
        match *self {
            Kind::Box(s) => s.z,
            Kind::Prism { height, .. }
            | Kind::Cylinder { height, .. }
            | Kind::Pyramid { height, .. }
            | Kind::Ell { height, .. } => height,
        }
    }

    fn radius(&self) -> f64 {
        match *self {
            Kind::Box(s) => 0.5 * s.x.hypot(s.y),
            Kind::Prism { radius, .. } | Kind::Cylinder { radius, .. } => radius,
            Kind::Pyramid { half, .. } => half * std::f64::consts::SQRT_2,
            Kind::Ell { size, .. } => size * 0.71,
        }
    }

    fn name(&self) -> &'static str {
        match self {
            Kind::Box(_) => "box",
            Kind::Prism { .. } => "prism",
            Kind::Cylinder { .. } => "cylinder",
            Kind::Pyramid { .. } => "pyramid",
            Kind::Ell { .. } => "ell",
        }
    }

    /// Inserts the body, its base centred on `at` (on the table top), turned `yaw`.
    fn insert(&self, world: &mut World, name: &str, at: DVec2, yaw: f64) {
        let root = world.root();
        let h = self.height();
        let pose = Pose::new(
            DVec3::new(at.x, at.y, TABLE_TOP + h / 2.0),
            DQuat::from_rotation_z(yaw),
        )
        .expect("a pose");
        let polygon = |n: usize, r: f64| -> Vec<DVec2> {
            (0..n)
                .map(|i| {
                    let a = std::f64::consts::TAU * i as f64 / n as f64;
                    DVec2::new(r * a.cos(), r * a.sin())
                })
                .collect()
        };
        let made = match *self {
            Kind::Box(s) => world.insert_with(Some(name), root, pose, |sr| box_solid(sr, s)),
            Kind::Prism {
                sides,
                radius,
                height,
            } => world.insert_with(Some(name), root, pose, |sr| {
                prism_solid(sr, &polygon(sides, radius), height)
            }),
            Kind::Cylinder {
                radius,
                height,
                sides,
            } => world.insert_with(Some(name), root, pose, |sr| {
                cylinder(sr, radius, height, sides)
            }),
            Kind::Pyramid { half, height } => world.insert_with(Some(name), root, pose, |sr| {
                let square = [
                    DVec2::new(-half, -half),
                    DVec2::new(half, -half),
                    DVec2::new(half, half),
                    DVec2::new(-half, half),
                ];
                pyramid_solid(sr, &square, height)
            }),
            Kind::Ell { size, height } => world.insert_with(Some(name), root, pose, |sr| {
                let (a, b) = (size / 2.0, size / 6.0);
                let ell = [
                    DVec2::new(-a, -a),
                    DVec2::new(a, -a),
                    DVec2::new(a, -a + 2.0 * b),
                    DVec2::new(-a + 2.0 * b, -a + 2.0 * b),
                    DVec2::new(-a + 2.0 * b, a),
                    DVec2::new(-a, a),
                ];
                prism_solid(sr, &ell, height)
            }),
        };
        made.expect("a body");
    }
}

/// What happens to a model body in the truth.
#[derive(Clone, Copy)]
enum Fate {
    Stays,
    Moved { shift: DVec2, turn: f64 },
    Removed,
}

/// A world of the table alone, its top at [`TABLE_TOP`].
fn table() -> World {
    let mut world = World::new();
    let root = world.root();
    world
        .insert_with(
            Some("table"),
            root,
            Pose::from_translation(DVec3::new(0.0, 0.0, TABLE_TOP - 0.025)),
            |s| box_solid(s, DVec3::new(TABLE.x, TABLE.y, 0.05)),
        )
        .expect("the table");
    world
}

/// How crowded a scene is and how low it is seen.
#[derive(Clone, Copy)]
struct Layout {
    /// The least gap between two bodies, meters.
    gap: f64,
    /// The camera's elevation above the table, degrees.
    elevation_deg: (f64, f64),
}

/// Bodies 12 cm apart, seen from 25–60° above the table: little occlusion.
const SPREAD: Layout = Layout {
    gap: 0.12,
    elevation_deg: (25.0, 60.0),
};

/// Bodies 1 cm apart, seen from 10–30° above the table: bodies hide each other.
const CLUTTER: Layout = Layout {
    gap: 0.01,
    elevation_deg: (10.0, 30.0),
};

/// One scene: the model, the truth, the cameras and the fates.
fn scene(rng: &mut Rng, layout: Layout) -> Value {
    let count = 5 + rng.below(11);
    let distractors = rng.below(3);
    let mut placed: Vec<(DVec2, f64)> = Vec::new();
    let mut model = table();
    let mut truth_adds = Vec::new();
    let mut bodies = Vec::new();
    for i in 0..count + distractors {
        let kind = Kind::random(rng);
        let r = kind.radius();
        let spot = (0..200).find_map(|_| {
            let at = DVec2::new(
                rng.range(-TABLE.x / 2.0 + r, TABLE.x / 2.0 - r),
                rng.range(-TABLE.y / 2.0 + r, TABLE.y / 2.0 - r),
            );
            placed
                .iter()
                .all(|&(p, q)| p.distance(at) > r + q + layout.gap)
                .then_some(at)
        });
        let Some(at) = spot else { continue };
        placed.push((at, r));
        let yaw = rng.range(0.0, std::f64::consts::TAU);
        if i < count {
            let name = format!("{}{i}", kind.name());
            kind.insert(&mut model, &name, at, yaw);
            let fate = match rng.below(10) {
                0..=2 => Fate::Moved {
                    shift: DVec2::from_angle(rng.range(0.0, std::f64::consts::TAU))
                        * rng.range(0.01, 0.1),
                    turn: rng.sign() * rng.range(1.0, 10.0).to_radians(),
                },
                3 => Fate::Removed,
                _ => Fate::Stays,
            };
            bodies.push((name, kind, at, yaw, fate));
        } else {
            truth_adds.push((format!("distractor{i}"), kind, at, yaw));
        }
    }
    let mut truth = table();
    let mut fates = vec![json!({"name": "table", "fate": "stays"})];
    for (name, kind, at, yaw, fate) in &bodies {
        match *fate {
            Fate::Stays => {
                kind.insert(&mut truth, name, *at, *yaw);
                fates.push(json!({"name": name, "fate": "stays"}));
            }
            Fate::Removed => fates.push(json!({"name": name, "fate": "removed"})),
            Fate::Moved { shift, turn } => {
                kind.insert(&mut truth, name, *at + shift, *yaw + turn);
                // The motion in the world: about the body's vertical axis through `at`.
                let q = DQuat::from_rotation_z(turn);
                let c = DVec3::new(at.x, at.y, 0.0);
                let motion = Pose {
                    position: DVec3::new(shift.x, shift.y, 0.0) + c - q * c,
                    rotation: q,
                };
                fates.push(json!({"name": name, "fate": "moved",
                    "motion": {"position": motion.position.to_array(), "rotation": motion.rotation.to_array()}}));
            }
        }
    }
    for (name, kind, at, yaw) in &truth_adds {
        kind.insert(&mut truth, name, *at, *yaw);
    }
    // The camera: toward the table's middle, from 1.3–2.2 m, at the layout's elevation.
    let azimuth = rng.range(0.0, std::f64::consts::TAU);
    let elevation = rng
        .range(layout.elevation_deg.0, layout.elevation_deg.1)
        .to_radians();
    let distance = rng.range(1.3, 2.2);
    let target = DVec3::new(rng.range(-0.1, 0.1), rng.range(-0.1, 0.1), TABLE_TOP);
    let eye = target
        + distance
            * DVec3::new(
                elevation.cos() * azimuth.cos(),
                elevation.cos() * azimuth.sin(),
                elevation.sin(),
            );
    let k = Intrinsics::centered(640, 480, 525.0).expect("intrinsics");
    let camera = Camera::look_at(eye, target, DVec3::Z, k).expect("a camera");
    let axis = DVec3::new(
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
    )
    .normalize();
    let mut rough = camera.pose;
    rough.rotation = (DQuat::from_axis_angle(axis, rng.range(0.5, 2.0).to_radians())
        * rough.rotation)
        .normalize();
    let away = DVec3::new(
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
    )
    .normalize();
    rough.position += away * rng.range(0.01, 0.05);
    let rough = Camera::new(rough, k).expect("a camera");
    json!({
        "model": model,
        "truth": truth,
        "triangles": triangles(&truth),
        "camera": camera_json(&camera),
        "rough_camera": camera_json(&rough),
        "fates": fates,
    })
}

fn camera_json(c: &Camera) -> Value {
    let k = c.intrinsics;
    let (r, t) = c.to_opencv();
    json!({
        "pose": {"position": c.pose.position.to_array(), "rotation": c.pose.rotation.to_array()},
        "intrinsics": {"width": k.width, "height": k.height, "fx": k.fx, "fy": k.fy, "cx": k.cx, "cy": k.cy},
        "opencv": {"r": r.transpose().to_cols_array(), "t": t.to_array()},
    })
}

/// The truth's triangles by body name, with colours, for another renderer.
fn triangles(world: &World) -> Value {
    let scene = Scene::build(world);
    let mut by_body: Vec<Vec<[f64; 9]>> = vec![Vec::new(); scene.bodies.len()];
    for (t, &f) in scene.triangles.iter().zip(&scene.triangle_faces) {
        let b = scene.faces[f as usize].body as usize;
        let [a, bb, c] = t.map(|i| scene.points[i as usize]);
        by_body[b].push([a.x, a.y, a.z, bb.x, bb.y, bb.z, c.x, c.y, c.z]);
    }
    Value::Array(
        scene
            .bodies
            .iter()
            .zip(by_body)
            .map(|(b, tris)| json!({"name": b.name, "color": b.color.0, "triangles": tris}))
            .collect(),
    )
}

fn camera_from(v: &Value) -> Camera {
    let num = |x: &Value| x.as_f64().expect("a number");
    let p = &v["pose"];
    let i = &v["intrinsics"];
    let pose = Pose::new(
        DVec3::new(
            num(&p["position"][0]),
            num(&p["position"][1]),
            num(&p["position"][2]),
        ),
        DQuat::from_xyzw(
            num(&p["rotation"][0]),
            num(&p["rotation"][1]),
            num(&p["rotation"][2]),
            num(&p["rotation"][3]),
        ),
    )
    .expect("a pose");
    let k = Intrinsics::new(
        i["width"].as_u64().expect("w") as u32,
        i["height"].as_u64().expect("h") as u32,
        num(&i["fx"]),
        num(&i["fy"]),
        num(&i["cx"]),
        num(&i["cy"]),
    )
    .expect("intrinsics");
    Camera::new(pose, k).expect("a camera")
}

fn read_png(path: &Path) -> (u32, u32, png::ColorType, png::BitDepth, Vec<u8>) {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let decoder = png::Decoder::new(std::io::BufReader::new(file));
    let mut reader = decoder.read_info().expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size().expect("a size")];
    let info = reader.next_frame(&mut buf).expect("a frame");
    buf.truncate(info.buffer_size());
    (
        info.width,
        info.height,
        info.color_type,
        info.bit_depth,
        buf,
    )
}

/// The LINE-2D baseline's templates: the model drawn by winged (shaded, grey) and which
/// body covers each pixel (0 none, `k + 1` the scene's body `k`), as PNGs.
fn write_model_views(dir: &Path, i: usize, drawn: &Scene, camera: &Camera) {
    let options = Options {
        background: SHADED_BACKGROUND,
        ..Options::default()
    };
    let Ok(Picture::Rgb(rgb)) = render(drawn, camera, Mode::Shaded, &options) else {
        panic!("a shaded picture is RGB");
    };
    let Ok(Picture::Ids { image, legend }) = render(drawn, camera, Mode::Ids, &options) else {
        panic!("an ids picture");
    };
    let index: Vec<u8> = image
        .data
        .iter()
        .map(|&v| {
            if v == 0 {
                return 0;
            }
            let id = legend[v as usize - 1];
            let k = drawn
                .bodies
                .binary_search_by_key(&id, |b| b.id)
                .expect("a body of the scene");
            u8::try_from(k + 1).expect("fewer than 255 bodies")
        })
        .collect();
    let write = |name: String, color: png::ColorType, bytes: &[u8]| {
        let file = std::fs::File::create(dir.join(name)).expect("created");
        let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), rgb.width, rgb.height);
        encoder.set_color(color);
        encoder.set_depth(png::BitDepth::Eight);
        encoder
            .write_header()
            .and_then(|mut w| w.write_image_data(bytes))
            .expect("written");
    };
    write(format!("model_{i:03}.png"), png::ColorType::Rgb, &rgb.data);
    write(
        format!("model_bodies_{i:03}.png"),
        png::ColorType::Grayscale,
        &index,
    );
}

/// Run-length code of a mask: alternating lengths of false and true runs.
fn runs(bits: &[bool]) -> Vec<usize> {
    let mut out = Vec::new();
    let mut current = false;
    let mut n = 0;
    for &b in bits {
        if b == current {
            n += 1;
        } else {
            out.push(n);
            current = b;
            n = 1;
        }
    }
    out.push(n);
    out
}

fn run_scene(dir: &Path, i: usize) -> Value {
    let text = std::fs::read_to_string(dir.join(format!("scene_{i:03}.json"))).expect("a scene");
    let scene: Value = serde_json::from_str(&text).expect("JSON");
    let model: World = serde_json::from_value(scene["model"].clone()).expect("a world");
    let drawn = Scene::build(&model);
    let exact = camera_from(&scene["camera"]);
    let rough = camera_from(&scene["rough_camera"]);
    // The chamfer baseline's templates: each body's visible edge points, model pose.
    let view = View::new(&exact, DEFAULT_NEAR);
    let mut templates: Vec<Vec<[f64; 4]>> = vec![Vec::new(); drawn.bodies.len()];
    for s in hidden_lines(&drawn, &view) {
        let Ok(b) = drawn.bodies.binary_search_by_key(&s.body, |b| b.id) else {
            continue;
        };
        let d = s.b - s.a;
        let n = (d.length() / 2.0).ceil().max(1.0) as usize;
        let dir = d.normalize_or_zero();
        for k in 0..n {
            let p = s.a + d * ((k as f64 + 0.5) / n as f64);
            templates[b].push([p.x, p.y, dir.x, dir.y]);
        }
    }
    let names: Vec<Value> = drawn.bodies.iter().map(|b| json!(b.name)).collect();
    write_model_views(dir, i, &drawn, &exact);
    std::fs::write(
        dir.join(format!("edges_{i:03}.json")),
        json!({"names": names, "points": templates}).to_string(),
    )
    .expect("written");

    let mut runs_out = Vec::new();
    for (label, with_depth, refine) in [
        ("image", false, false),
        ("depth", true, false),
        ("refine", false, true),
    ] {
        let started = Instant::now();
        let (w, h, color, _, rgb) = read_png(&dir.join(format!("image_{i:03}.png")));
        let channels = match color {
            png::ColorType::Rgb => 3,
            png::ColorType::Grayscale => 1,
            png::ColorType::Rgba => 4,
            _ => 2,
        };
        let luma = Luma::from_samples(w, h, channels, &rgb).expect("a picture");
        let depth = with_depth.then(|| {
            let (dw, dh, _, _, bytes) = read_png(&dir.join(format!("depth_{i:03}.png")));
            let units: Vec<u16> = bytes
                .chunks_exact(2)
                .map(|b| u16::from_be_bytes([b[0], b[1]]))
                .collect();
            DepthImage::from_units(dw, dh, &units, 0.001).expect("a depth picture")
        });
        let options = RecognizeOptions::default();
        let pyramid = EdgePyramid::of(&luma, &options.refine).expect("edges");
        let camera = if refine {
            match align_camera(&drawn, &rough, &pyramid, &options.refine) {
                Ok(a) => a.camera,
                Err(e) => {
                    runs_out.push(json!({"run": label, "error": e.to_string(),
                        "ms": started.elapsed().as_secs_f64() * 1e3}));
                    continue;
                }
            }
        } else {
            exact
        };
        let found = recognize(&drawn, &camera, &luma, &pyramid, depth.as_ref(), &options)
            .expect("recognized");
        let ms = started.elapsed().as_secs_f64() * 1e3;
        let bodies: Vec<Value> = found
            .bodies
            .iter()
            .map(|r| {
                json!({
                    "name": drawn.bodies[r.body].name,
                    "status": r.status.name(),
                    "score": r.score,
                    "visible_fraction": r.visible_fraction,
                    "edge_support": r.edge_support,
                    "motion": r.motion.map(|m| json!({"position": m.position.to_array(), "rotation": m.rotation.to_array()})),
                })
            })
            .collect();
        runs_out.push(json!({
            "run": label,
            "ms": ms,
            "bodies": bodies,
            "mask_runs": runs(found.unexplained_mask.bits()),
            "camera_error": {
                "degrees": camera.pose.rotation.angle_between(exact.pose.rotation).to_degrees(),
                "meters": camera.pose.position.distance(exact.pose.position),
            },
        }));
    }
    json!({"scene": i, "runs": runs_out})
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: recognition_bench scenes DIR [--count N] [--seed S] [--clutter] | run DIR [--only N]";
    let (Some(command), Some(dir)) = (args.first(), args.get(1)) else {
        eprintln!("{usage}");
        std::process::exit(2);
    };
    let dir = PathBuf::from(dir);
    let flag = |name: &str, default: u64| -> u64 {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .map_or(default, |v| v.parse().expect("a number"))
    };
    match command.as_str() {
        "scenes" => {
            std::fs::create_dir_all(&dir).expect("a directory");
            let count = flag("--count", 300) as usize;
            let mut rng = Rng(flag("--seed", 1));
            let layout = if args.iter().any(|a| a == "--clutter") {
                CLUTTER
            } else {
                SPREAD
            };
            for i in 0..count {
                let s = scene(&mut rng, layout);
                std::fs::write(dir.join(format!("scene_{i:03}.json")), s.to_string())
                    .expect("written");
            }
            eprintln!("{count} scenes in {}", dir.display());
        }
        "run" => {
            tracing_subscriber::fmt()
                .with_env_filter(
                    tracing_subscriber::EnvFilter::try_from_default_env()
                        .unwrap_or_else(|_| "warn".into()),
                )
                .with_writer(std::io::stderr)
                .init();
            // `--only N` recognizes scene N alone (its answer file is rewritten).
            let only = args
                .iter()
                .position(|a| a == "--only")
                .map(|_| flag("--only", 0) as usize);
            let mut i = only.unwrap_or(0);
            while dir.join(format!("image_{i:03}.png")).exists() {
                let out = run_scene(&dir, i);
                std::fs::write(dir.join(format!("winged_{i:03}.json")), out.to_string())
                    .expect("written");
                i += 1;
                if only.is_some() {
                    break;
                }
            }
            eprintln!("scenes up to {i} recognized");
        }
        _ => {
            eprintln!("{usage}");
            std::process::exit(2);
        }
    }
}
