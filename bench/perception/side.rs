//! winged's side of the perception side-by-side (see bench/perception/README.md): visual
//! hulls of silhouettes drawn by ray casting, checked against the bodies that cast them
//! and timed; `peers.py` runs manifold3d and Open3D on the same cones and masks.
//!
//! * `write --dir D`: for each scene and view count, the cameras, the masks (PNG), the
//!   silhouette rings winged carves with and the cones built from them (JSON).
//! * `run --dir D --repeat N`: times `visual_hull` and one more view's `carve_by`, and
//!   checks each result: valid pieces, containment of the true body, spill over the
//!   masks; for the ball, the excess volume beside two Monte Carlo estimates.
//! * `trials --n 1000 --seed S`: random boxes and L-prisms seen by 2–16 random cameras;
//!   every hull must be valid and hold its body. Trial `k` uses seed `S + k`.
//! * `robust`: jittered masks and perturbed cameras, 8 and 16 views: the fraction of the
//!   true volume the hull loses.
//!
//! `RUST_LOG=winged::vision::perceive=debug` logs each fall-back to the general boolean.

#[path = "side/files.rs"]
mod files;
#[path = "side/measure.rs"]
mod measure;
#[path = "../rng.rs"]
mod rng;
#[path = "../side_cli.rs"]
mod side_cli;
#[path = "side/solids.rs"]
mod solids;
#[path = "../triangles.rs"]
mod triangles;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::{Parser, Subcommand};
use glam::{DAffine3, DQuat, DVec3};
use serde_json::{Value, json};
use winged::model::boolean::{BooleanError, Op, Operand, boolean};
use winged::model::camera::Camera;
use winged::model::{Serial, Serials};
use winged::vision::image::Mask;
use winged::vision::perceive::bound;
use winged::vision::perceive::cone::cone;
use winged::vision::perceive::silhouette::silhouettes;
use winged::vision::perceive::{Depths, Mesh, Sight, Tally, carve_by, visual_hull};

use rng::Rng;
use solids::{Shape, Solid};

/// The view counts of the side-by-side.
const VIEWS: [usize; 9] = [2, 3, 4, 6, 8, 12, 16, 32, 64];

/// How far masks are widened before tracing, pixels (as the product does by default).
const WIDEN_PX: f64 = 1.0;

#[derive(Parser, Debug)]
struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Writes each scene's cameras, masks, rings and cones under D.
    Write {
        /// The directory to write into.
        #[arg(long)]
        dir: PathBuf,
        /// The view counts.
        #[arg(long, value_delimiter = ',', default_values_t = VIEWS)]
        views: Vec<usize>,
        /// Only the scene of this name.
        #[arg(long)]
        only: Option<String>,
    },
    /// Times and checks winged's visual hulls on what `write` wrote.
    Run {
        /// The directory `write` wrote.
        #[arg(long)]
        dir: PathBuf,
        /// Runs per case (the best is reported).
        #[arg(long, default_value_t = 5)]
        repeat: usize,
        /// Only the scene of this name.
        #[arg(long)]
        only: Option<String>,
        /// Monte Carlo samples for the ball's hulls.
        #[arg(long, default_value_t = 4_000_000)]
        samples: usize,
    },
    /// Random boxes and L-prisms seen by random cameras: every hull valid and holding.
    Trials {
        /// Trials.
        #[arg(long, default_value_t = 1000)]
        n: u64,
        /// Trial k draws from seed + k.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Carves one written case view by view and checks each intermediate piece with
    /// the general boolean's self-intersection test, naming the first crossing faces.
    Diagnose {
        /// The directory `write` wrote.
        #[arg(long)]
        dir: PathBuf,
        /// The scene.
        #[arg(long)]
        scene: String,
        /// The view count.
        #[arg(long)]
        views: usize,
    },
    /// Jittered masks and perturbed cameras: the fraction of the true volume lost.
    Robust {
        /// Draws per scene, view count and perturbation.
        #[arg(long, default_value_t = 3)]
        draws: u64,
        /// The first draw's seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Where to write each refused draw as a case (for `diagnose`).
        #[arg(long)]
        dump: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    side_cli::start();
    let result = match Args::parse().command {
        Command::Write { dir, views, only } => write(&dir, &views, only.as_deref()),
        Command::Run {
            dir,
            repeat,
            only,
            samples,
        } => run(&dir, repeat.max(1), only.as_deref(), samples),
        Command::Trials { n, seed } => trials(n, seed),
        Command::Diagnose { dir, scene, views } => diagnose(&dir, &scene, views),
        Command::Robust { draws, seed, dump } => robust(draws.max(1), seed, dump.as_deref()),
    };
    side_cli::exit(result)
}

/// SplitMix64's finaliser: spreads consecutive seeds over the generator's states.
pub fn spread(seed: u64) -> u64 {
    let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The sights of `masks` seen by `cameras`: each mask must give one silhouette.
fn sights_of(cameras: &[Camera], masks: &[Mask]) -> Result<Vec<Sight>, String> {
    cameras
        .iter()
        .zip(masks)
        .enumerate()
        .map(|(k, (camera, mask))| {
            let mut found = silhouettes(mask, WIDEN_PX, 0.0);
            if found.len() != 1 {
                return Err(format!("view {k}: {} silhouettes, not one", found.len()));
            }
            Ok(Sight {
                camera: *camera,
                outline: found.remove(0).outline,
                view: k as u32,
            })
        })
        .collect()
}

fn write(dir: &Path, views: &[usize], only: Option<&str>) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut index = Vec::new();
    for solid in solids::scenes() {
        if only.is_some_and(|o| o != solid.name) {
            continue;
        }
        for &n in views {
            let cameras = solids::cameras(&solid, n);
            let masks: Vec<Mask> = cameras.iter().map(|c| solids::draw(&solid, c)).collect();
            let sights =
                sights_of(&cameras, &masks).map_err(|e| format!("{} {n}: {e}", solid.name))?;
            let path = files::write_case(
                dir,
                &solid.name,
                solid.volume(),
                solid.radius(),
                &sights,
                &masks,
            )?;
            let points: Vec<usize> = sights
                .iter()
                .map(|s| s.outline.rings.iter().map(Vec::len).sum())
                .collect();
            let holes: usize = sights.iter().map(|s| s.outline.rings.len() - 1).sum();
            println!(
                "{} {n:>2} views: ring points {}..{} per view, {holes} holes in all",
                solid.name,
                points.iter().min().unwrap_or(&0),
                points.iter().max().unwrap_or(&0),
            );
            let relative = path.strip_prefix(dir).unwrap_or(&path);
            index.push(json!({"scene": solid.name, "views": n, "path": relative}));
        }
    }
    files::write_index(dir, &index)
}

/// Runs `f` `repeat` times (stopping at the first failure or panic): the times in
/// seconds and the last outcome.
fn timed<T>(
    repeat: usize,
    mut f: impl FnMut() -> Result<T, String>,
) -> (Vec<f64>, Result<T, String>) {
    let mut runs = Vec::with_capacity(repeat);
    let mut outcome = Err("not run".to_string());
    for _ in 0..repeat {
        let t = Instant::now();
        let result = side_cli::caught(&mut f);
        runs.push(t.elapsed().as_secs_f64());
        let failed = result.is_err();
        outcome = result;
        if failed {
            break;
        }
    }
    (runs, outcome)
}

fn best(runs: &[f64]) -> f64 {
    runs.iter().copied().fold(f64::INFINITY, f64::min)
}

/// The hull of `sights` with its tally, panics caught.
fn hull_of(sights: &[Sight]) -> Result<(Vec<Mesh>, Tally), String> {
    side_cli::caught(|| {
        let mut tally = Tally::default();
        visual_hull(sights, Depths::default(), &mut tally)
            .map(|p| (p, tally))
            .map_err(|e| format!("refused: {e}"))
    })
}

fn volume_of(pieces: &[Mesh]) -> f64 {
    pieces.iter().map(Mesh::volume).sum()
}

fn bounds_of(pieces: &[Mesh]) -> (DVec3, DVec3) {
    pieces.iter().map(Mesh::bounds).fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), (a, b)| (lo.min(a), hi.max(b)),
    )
}

/// One row of the ball's table.
struct BallRow {
    views: usize,
    true_volume: f64,
    winged: Option<f64>,
    hulls: measure::BallHulls,
}

fn run(dir: &Path, repeat: usize, only: Option<&str>, samples: usize) -> Result<(), String> {
    let mut report = serde_json::Map::new();
    let mut ball_rows = Vec::new();
    let mut scene_now = String::new();
    for (scene, views) in files::read_index(dir)? {
        if only.is_some_and(|o| o != scene) {
            continue;
        }
        let solid = solids::scene(&scene).ok_or(format!("no scene named {scene}"))?;
        let case = files::read_case(dir, &scene, views)?;
        if scene != scene_now {
            println!("\n{scene}: true volume {:.6e} m³\n", solid.volume());
            println!(
                "| views | hull ms | +1 view ms | pieces | faces | volume / true | image / boolean / uncarved | valid | self-crossing | contained | spill px (view) |"
            );
            println!("|---:|---:|---:|---:|---:|---:|---|---|---|---|---|");
            scene_now = scene.clone();
        }
        let (entry, ball) = run_case(&solid, &case, repeat, samples);
        if let Some(row) = ball {
            ball_rows.push(row);
        }
        report.insert(format!("{scene}/{views}"), entry);
    }
    if !ball_rows.is_empty() {
        print_ball(&ball_rows);
    }
    let path = dir.join("winged.json");
    let text = serde_json::to_string_pretty(&Value::Object(report)).map_err(|e| e.to_string())?;
    std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Times, checks and prints one case; for the ball, also its Monte Carlo row.
fn run_case(
    solid: &Solid,
    case: &files::Case,
    repeat: usize,
    samples: usize,
) -> (Value, Option<BallRow>) {
    let sights = &case.sights;
    let n = sights.len();
    let true_volume = solid.volume();
    let (runs, outcome) = timed(repeat, || hull_of(sights));
    // One more view on the hull of the others.
    let mut carve = (Vec::new(), Err("no hull of the other views".to_string()));
    if let Ok((prior, _)) = hull_of(&sights[..n - 1]) {
        let mut inputs: Vec<Vec<Mesh>> = (0..repeat).map(|_| prior.clone()).collect();
        carve = timed(repeat, || {
            let mut tally = Tally::default();
            let pieces = inputs.pop().unwrap_or_default();
            carve_by(pieces, &sights[n - 1], Depths::default(), &mut tally)
                .map(|p| (p, tally))
                .map_err(|e| format!("refused: {e}"))
        });
    }
    let ball = match &solid.shape {
        Shape::Ball(r) => Some(ball_row(
            *r,
            case,
            outcome.as_ref().ok().map(|(p, _)| &p[..]),
            samples,
        )),
        _ => None,
    };
    let (pieces, tally) = match outcome {
        Ok(found) => found,
        Err(why) => {
            println!("| {n} | — | — | — | — | — | — | {why} | — | — | — |");
            return (json!({"status": why, "runs_s": runs}), ball);
        }
    };
    let volume = volume_of(&pieces);
    let faces: usize = pieces.iter().map(|p| p.faces.len()).sum();
    let vertices: usize = pieces.iter().map(|p| p.positions.len()).sum();
    let invalid = measure::invalid(&pieces);
    let crossing = pieces.iter().find_map(|p| self_check(p).err());
    let samples_in = solid.surface_samples();
    let (outside, worst) = measure::containment(&pieces, &samples_in);
    let spills: Vec<f64> = sights
        .iter()
        .zip(&case.masks)
        .map(|(s, m)| measure::spill(&pieces, &s.camera, m, 16))
        .collect();
    let (worst_view, spill) = spills
        .iter()
        .copied()
        .enumerate()
        .fold((0, 0.0), |a, (k, s)| if s > a.1 { (k, s) } else { a });
    let (carve_ms, carve_volume) = match &carve.1 {
        Ok((p, t)) => {
            let how = if t.boolean > 0 { " (boolean)" } else { "" };
            (
                format!("{:.2}{how}", best(&carve.0) * 1e3),
                Some(volume_of(p)),
            )
        }
        Err(why) => (why.chars().take(40).collect(), None),
    };
    let carve_agrees = carve_volume.map(|v| (v - volume).abs() / volume);
    println!(
        "| {n} | {:.2} | {carve_ms} | {} | {faces} | {:.4} | {} / {} / {} | {} | {} | {} | {spill:.2} ({worst_view}) |",
        best(&runs) * 1e3,
        pieces.len(),
        volume / true_volume,
        tally.exact_image,
        tally.boolean,
        tally.uncarved,
        invalid.as_deref().unwrap_or("yes"),
        if crossing.is_some() {
            "CROSSING"
        } else {
            "none"
        },
        if outside == 0 {
            format!("{} of {}", samples_in.len(), samples_in.len())
        } else {
            format!(
                "{outside} outside of {} (winding {worst})",
                samples_in.len()
            )
        },
    );
    if outside > 0 {
        println!(
            "  (outside: {})",
            missed_by_masks(&pieces, &samples_in, sights)
        );
    }
    if let Some(why) = &crossing {
        println!("  (self-crossing: {why})");
    }
    if let Some(d) = carve_agrees.filter(|d| *d > 1e-9) {
        println!(
            "  (the hull of {n} views and {} views + 1 differ in volume by {d:.2e})",
            n - 1
        );
    }
    let entry = json!({
        "status": "ok",
        "best_s": best(&runs),
        "runs_s": runs,
        "carve_best_s": carve.1.as_ref().ok().map(|_| best(&carve.0)),
        "carve_runs_s": carve.0,
        "carve_status": carve.1.as_ref().err(),
        "carve_tally": carve.1.as_ref().ok().map(|(_, t)| json!({"exact_image": t.exact_image, "boolean": t.boolean})),
        "carve_relative_volume_difference": carve_agrees,
        "pieces": pieces.len(),
        "piece_volumes": pieces.iter().map(Mesh::volume).collect::<Vec<_>>(),
        "faces": faces,
        "vertices": vertices,
        "volume": volume,
        "true_volume": true_volume,
        "tally": {"exact_image": tally.exact_image, "boolean": tally.boolean, "uncarved": tally.uncarved},
        "invalid": invalid,
        "self_crossing": crossing,
        "containment": {"samples": samples_in.len(), "outside": outside, "worst_winding": worst},
        "spill_px": spills,
        "spill_max_px": spill,
        "ball": ball.as_ref().map(|b| {
            let (t, ts) = b.hulls.volume(b.hulls.in_true);
            let (p, ps) = b.hulls.volume(b.hulls.in_polygons);
            json!({"mc_true_hull": t, "mc_true_se": ts, "mc_polygon_hull": p, "mc_polygon_se": ps,
                   "samples": b.hulls.samples, "beyond_box": b.hulls.beyond_inner})
        }),
    });
    (entry, ball)
}

/// The ball's Monte Carlo hulls for one case, sampled in winged's hull's bounding box
/// (with the ball's) enlarged by 5 % of its size on each side.
fn ball_row(r: f64, case: &files::Case, pieces: Option<&[Mesh]>, samples: usize) -> BallRow {
    let ball = (DVec3::splat(-r), DVec3::splat(r));
    let inner = match pieces {
        Some(p) if !p.is_empty() => {
            let (lo, hi) = bounds_of(p);
            (lo.min(ball.0), hi.max(ball.1))
        }
        _ => (ball.0 * 3.0, ball.1 * 3.0),
    };
    let margin = (inner.1 - inner.0) * 0.05;
    let outer = (inner.0 - margin, inner.1 + margin);
    let cameras: Vec<Camera> = case.sights.iter().map(|s| s.camera).collect();
    let outlines: Vec<_> = case.sights.iter().map(|s| s.outline.clone()).collect();
    let seed = spread(case.sights.len() as u64);
    let hulls = measure::ball_hulls(r, &cameras, &outlines, outer, inner, samples, seed);
    BallRow {
        views: case.sights.len(),
        true_volume: 4.0 / 3.0 * std::f64::consts::PI * r * r * r,
        winged: pieces.map(volume_of),
        hulls,
    }
}

fn print_ball(rows: &[BallRow]) {
    println!("\nball: excess volume over the true ball, % (Monte Carlo ± one standard error)\n");
    println!(
        "| views | winged | MC: true visual hull | MC: hull of the polygons | winged − MC polygons (points) | samples outside winged's box |"
    );
    println!("|---:|---:|---:|---:|---:|---:|");
    for row in rows {
        let (t, ts) = row.hulls.volume(row.hulls.in_true);
        let (p, ps) = row.hulls.volume(row.hulls.in_polygons);
        let v = row.true_volume;
        let pct = |x: f64| (x / v - 1.0) * 100.0;
        let winged = row.winged.map(pct);
        println!(
            "| {} | {} | {:+.2} ± {:.2} | {:+.2} ± {:.2} | {} | {} |",
            row.views,
            winged.map_or("—".into(), |w| format!("{w:+.3}")),
            pct(t),
            ts / v * 100.0,
            pct(p),
            ps / v * 100.0,
            winged.map_or("—".into(), |w| format!("{:+.2}", w - pct(p))),
            row.hulls.beyond_inner,
        );
    }
}

/// A random unit quaternion (uniform over rotations).
fn random_rotation(rng: &mut Rng) -> DQuat {
    DQuat::from_xyzw(rng.normal(), rng.normal(), rng.normal(), rng.normal()).normalize()
}

/// What one trial found: its body, view count, and the hull's tally when it passed.
struct Trial {
    kind: &'static str,
    views: usize,
    outcome: Result<Passed, String>,
}

/// A trial that passed: the hull's tally, pieces, volume over the body's, and whether
/// the general boolean's self-intersection check refuses a piece.
struct Passed {
    tally: Tally,
    pieces: usize,
    ratio: f64,
    crossing: Option<String>,
}

/// One random trial: a box or an L-prism of random size and orientation, seen by 2–16
/// cameras in random directions at 5 radii.
fn trial(seed: u64) -> Trial {
    let mut rng = Rng(spread(seed));
    let (kind, shape) = if rng.next() < 0.5 {
        let half = DVec3::new(
            rng.range(0.02, 0.15),
            rng.range(0.02, 0.15),
            rng.range(0.02, 0.15),
        );
        ("box", Shape::Boxes(vec![(-half, half)]))
    } else {
        let (sx, sy, sz) = (
            rng.range(0.05, 0.2),
            rng.range(0.05, 0.2),
            rng.range(0.02, 0.1),
        );
        let (a, b) = (rng.range(0.3, 0.7), rng.range(0.3, 0.7));
        ("l_prism", solids::l_prism(sx, sy, sz, a, b))
    };
    let solid = Solid::new(kind, shape, random_rotation(&mut rng));
    let views = 2 + (rng.next() * 15.0) as usize;
    let distance = solids::DISTANCE * solid.radius();
    let cameras: Vec<Camera> = (0..views)
        .map(|_| solids::camera_toward(rng.unit_vector(), distance))
        .collect();
    let outcome = (|| {
        let masks: Vec<Mask> = cameras.iter().map(|c| solids::draw(&solid, c)).collect();
        let sights = sights_of(&cameras, &masks)?;
        let (pieces, tally) = hull_of(&sights)?;
        if pieces.is_empty() {
            return Err("empty hull".to_string());
        }
        if let Some(why) = measure::invalid(&pieces) {
            return Err(format!("invalid: {why}"));
        }
        let points = solid.surface_samples();
        let (outside, worst) = measure::containment(&pieces, &points);
        if outside > 0 {
            return Err(format!(
                "{outside} of {} points of the body outside (winding {worst}); {}",
                points.len(),
                missed_by_masks(&pieces, &points, &sights)
            ));
        }
        Ok(Passed {
            tally,
            pieces: pieces.len(),
            ratio: volume_of(&pieces) / solid.volume(),
            crossing: pieces.iter().find_map(|p| self_check(p).err()),
        })
    })();
    Trial {
        kind,
        views,
        outcome,
    }
}

/// Of the body's `points` outside `pieces`, how many project outside some view's
/// silhouette polygon (the mask, drawn by pixel centres, missed a part of the body
/// narrower than a pixel, and widening did not bring it back), naming those views.
fn missed_by_masks(pieces: &[Mesh], points: &[DVec3], sights: &[Sight]) -> String {
    let rows: Vec<measure::Rows> = sights
        .iter()
        .map(|s| measure::Rows::new(&s.outline))
        .collect();
    let outside: Vec<DVec3> = points
        .iter()
        .copied()
        .filter(|&x| (measure::winding(pieces, x) - 1.0).abs() > 1e-6)
        .collect();
    let mut views = std::collections::BTreeSet::new();
    let missed = outside
        .iter()
        .filter(|&&x| {
            let out: Vec<u32> = sights
                .iter()
                .zip(&rows)
                .filter(|(s, r)| s.camera.project(x).is_none_or(|q| !r.inside(q)))
                .map(|(s, _)| s.view)
                .collect();
            views.extend(out.iter().copied());
            !out.is_empty()
        })
        .count();
    format!("{missed} of them outside a silhouette (views {views:?}): the masks missed them")
}

fn trials(n: u64, seed: u64) -> Result<(), String> {
    let start = Instant::now();
    let (mut passed, mut boolean, mut pieces_max, mut failures) = (0, 0, 0, Vec::new());
    let mut uncarved = 0;
    let (mut ratios, mut crossing) = (Vec::new(), Vec::new());
    for s in seed..seed + n {
        let t = trial(s);
        match t.outcome {
            Ok(p) => {
                passed += 1;
                boolean += usize::from(p.tally.boolean > 0);
                uncarved += usize::from(p.tally.uncarved > 0);
                pieces_max = pieces_max.max(p.pieces);
                ratios.push(p.ratio);
                if let Some(why) = p.crossing {
                    println!("self-crossing seed={s} {} {} views: {why}", t.kind, t.views);
                    crossing.push(s);
                }
            }
            Err(why) => {
                println!("FAILED seed={s} {} {} views: {why}", t.kind, t.views);
                failures.push(s);
            }
        }
    }
    ratios.sort_by(f64::total_cmp);
    let median = ratios.get(ratios.len() / 2).copied().unwrap_or(f64::NAN);
    println!(
        "{n} trials (seeds {seed}..{}): {passed} passed, {} failed; {boolean} used the general boolean; {uncarved} left a piece uncarved; \
         {} passed with a piece the boolean's self-intersection check refuses; \
         at most {pieces_max} pieces; hull / body volume median {median:.3}; {:.1} s",
        seed + n,
        failures.len(),
        crossing.len(),
        start.elapsed().as_secs_f64()
    );
    if failures.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "failed seeds: {:?} (rerun one with `trials --n 1 --seed S`)",
            failures
        ))
    }
}

/// `mask` with each boundary pixel (one whose 4-neighbour differs; beyond the image is
/// outside) flipped with probability ½.
fn jittered(mask: &Mask, rng: &mut Rng) -> Mask {
    let (w, h) = (mask.width() as i64, mask.height() as i64);
    let at = |x: i64, y: i64| x >= 0 && y >= 0 && mask.get(x as u32, y as u32);
    let mut out = mask.clone();
    for y in 0..h {
        for x in 0..w {
            let v = at(x, y);
            let boundary = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .any(|&(dx, dy)| at(x + dx, y + dy) != v);
            if boundary && rng.next() < 0.5 {
                out.set(x as u32, y as u32, !v);
            }
        }
    }
    out
}

/// `camera` turned about its centre by the angle that moves the image by `px` pixels,
/// about a random axis across the view direction.
fn miscalibrated(camera: &Camera, px: f64, rng: &mut Rng) -> Camera {
    let k = camera.k();
    let axis = loop {
        let u = rng.unit_vector();
        let across = u - k * u.dot(k);
        if across.length() > 0.1 {
            break across.normalize();
        }
    };
    let mut pose = camera.pose;
    pose.rotation =
        (DQuat::from_axis_angle(axis, px / camera.intrinsics.fx) * pose.rotation).normalize();
    Camera::new(pose, camera.intrinsics).expect("a perturbed camera")
}

/// The mean distance, pixels, by which `points` move between two cameras' images.
fn shift(a: &Camera, b: &Camera, points: &[DVec3]) -> f64 {
    let moved: Vec<f64> = points
        .iter()
        .filter_map(|&p| Some((a.project(p)? - b.project(p)?).length()))
        .collect();
    moved.iter().sum::<f64>() / moved.len().max(1) as f64
}

fn robust(draws: u64, seed: u64, dump: Option<&Path>) -> Result<(), String> {
    println!(
        "| scene | views | perturbation | lost % (mean) | lost % (worst) | volume / true | image shift px | valid | boolean fall-backs (pieces left uncarved) | failures |"
    );
    println!("|---|---:|---|---:|---:|---:|---:|---|---:|---|");
    let mut worst_all: f64 = 0.0;
    for solid in solids::scenes() {
        let inside = solid.interior_samples(100_000, &mut Rng(spread(seed ^ 0x5EED)));
        let surface = solid.surface_samples();
        for n in [8, 16] {
            let cameras = solids::cameras(&solid, n);
            let masks: Vec<Mask> = cameras.iter().map(|c| solids::draw(&solid, c)).collect();
            for kind in ["jitter", "calibration", "both"] {
                let (mut lost, mut ratio, mut shifts) = (Vec::new(), Vec::new(), Vec::new());
                let (mut invalid, mut fallbacks, mut failures) = (0, 0, Vec::new());
                let mut uncarved = 0;
                for d in 0..draws {
                    let mut rng = Rng(spread(seed.wrapping_add(d) ^ spread(n as u64)));
                    let masks: Vec<Mask> = if kind != "calibration" {
                        masks.iter().map(|m| jittered(m, &mut rng)).collect()
                    } else {
                        masks.clone()
                    };
                    let used: Vec<Camera> = if kind != "jitter" {
                        cameras
                            .iter()
                            .map(|c| miscalibrated(c, 0.5, &mut rng))
                            .collect()
                    } else {
                        cameras.clone()
                    };
                    for (a, b) in cameras.iter().zip(&used) {
                        shifts.push(shift(a, b, &surface));
                    }
                    let sights = sights_of(&used, &masks);
                    let outcome = sights
                        .as_ref()
                        .map_err(Clone::clone)
                        .and_then(|s| hull_of(s));
                    if let (Err(_), Ok(sights), Some(dump)) = (&outcome, &sights, dump) {
                        let name = format!("{}.{kind}.{d}", solid.name);
                        files::write_case(
                            dump,
                            &name,
                            solid.volume(),
                            solid.radius(),
                            sights,
                            &masks,
                        )?;
                        println!(
                            "(written: diagnose --dir {} --scene {name} --views {n})",
                            dump.display()
                        );
                    }
                    match outcome {
                        Ok((pieces, tally)) => {
                            let parity = measure::Parity::new(&pieces);
                            let out = inside.iter().filter(|&&p| !parity.inside(p)).count();
                            lost.push(out as f64 / inside.len() as f64 * 100.0);
                            ratio.push(volume_of(&pieces) / solid.volume());
                            invalid += usize::from(measure::invalid(&pieces).is_some());
                            fallbacks += tally.boolean;
                            uncarved += tally.uncarved;
                        }
                        Err(why) => failures.push(format!("draw {d}: {why}")),
                    }
                }
                let mean = |v: &[f64], digits: usize| {
                    if v.is_empty() {
                        "—".to_string()
                    } else {
                        format!("{:.digits$}", v.iter().sum::<f64>() / v.len() as f64)
                    }
                };
                let worst = lost.iter().copied().fold(0.0, f64::max);
                worst_all = worst_all.max(worst);
                println!(
                    "| {} | {n} | {kind} | {} | {} | {} | {} | {} | {fallbacks} ({uncarved}) | {} |",
                    solid.name,
                    mean(&lost, 3),
                    if lost.is_empty() {
                        "—".to_string()
                    } else {
                        format!("{worst:.3}")
                    },
                    mean(&ratio, 4),
                    mean(&shifts, 2),
                    if invalid == 0 {
                        "yes".to_string()
                    } else {
                        format!("{invalid} invalid")
                    },
                    if failures.is_empty() {
                        "—".to_string()
                    } else {
                        failures.join("; ")
                    },
                );
            }
        }
    }
    println!("\nworst fraction of the true volume lost: {worst_all:.3} % (goal ≤ 1 %)");
    Ok(())
}

/// Whether the general boolean takes `piece` as an operand: its union with a copy of
/// itself 1 km away runs the boolean's check that no two faces of an operand cross.
fn self_check(piece: &Mesh) -> Result<(), String> {
    let body = piece
        .to_body(&mut Serials::new())
        .map_err(|e| format!("to_body: {e}"))?;
    let far = DAffine3::from_translation(DVec3::splat(1000.0));
    let operand = |place| Operand { body: &body, place };
    match boolean(operand(DAffine3::IDENTITY), operand(far), Op::Union) {
        Ok(_) => Ok(()),
        Err(e) => {
            let index: Vec<Serial> = body.faces().map(|f| body.face_serial(f)).collect();
            let describe = |serial: Serial| {
                let Some(i) = index.iter().position(|&s| s == serial) else {
                    return format!("{serial:?}");
                };
                let ring = &piece.faces[i];
                let p = |k: usize| piece.positions[ring[k % ring.len()] as usize];
                let normal = (0..ring.len())
                    .map(|k| p(k).cross(p(k + 1)))
                    .sum::<DVec3>()
                    .normalize();
                let off = (0..ring.len())
                    .map(|k| (p(k) - p(0)).dot(normal).abs())
                    .fold(0.0, f64::max);
                format!(
                    "face {i} ({:?}, {} corners, off its plane by {off:.1e} m)",
                    piece.makers[i],
                    ring.len()
                )
            };
            Err(match e {
                BooleanError::SelfIntersecting { faces, .. } => format!(
                    "faces cross: {} and {}",
                    describe(faces[0]),
                    describe(faces[1])
                ),
                BooleanError::BadFace { face, .. } => {
                    format!("not a simple polygon: {}", describe(face))
                }
                e => format!("{e}"),
            })
        }
    }
}

fn diagnose(dir: &Path, scene: &str, views: usize) -> Result<(), String> {
    let case = files::read_case(dir, scene, views)?;
    let sights = &case.sights;
    // As visual_hull starts: the first frustum clipped by the others' near and far ends.
    let depths = Depths::default();
    let frustums: Vec<_> = sights
        .iter()
        .map(|s| {
            bound::frustum(
                &s.camera,
                &s.outline.rings[0],
                depths.near,
                depths.far,
                s.view,
            )
        })
        .collect::<Option<_>>()
        .ok_or("a silhouette without area")?;
    let start = bound::start(&frustums[0], &frustums[1..]).ok_or("the frustums do not meet")?;
    let mut pieces = vec![start];
    let mut tally = Tally::default();
    let mut clean = true;
    for k in 0..=sights.len() {
        for (i, p) in pieces.iter().enumerate() {
            if let Err(why) = self_check(p) {
                let after = if k == 0 {
                    "the start".to_string()
                } else {
                    format!("views 0..={}", k - 1)
                };
                println!("after {after}: piece {i} of {}: {why}", pieces.len());
                clean = false;
            }
        }
        if k == sights.len() {
            break;
        }
        let before = tally;
        pieces = match carve_by(pieces.clone(), &sights[k], Depths::default(), &mut tally) {
            Ok(p) => p,
            Err(e) => {
                println!("view {k}: {e}");
                outer_cone_check(&pieces, &sights[k]);
                return Ok(());
            }
        };
        println!(
            "view {k}: {} pieces, carved by the image method {} times, by the boolean {} times",
            pieces.len(),
            tally.exact_image - before.exact_image,
            tally.boolean - before.boolean
        );
    }
    if clean {
        println!("every intermediate piece passes the boolean's checks of its operands");
    }
    Ok(())
}

/// After a refusal: intersects each piece with the view's outer cone by the general
/// boolean (as `carve_by` does before it subtracts the holes' cones) and self-checks
/// the shells it returns.
fn outer_cone_check(pieces: &[Mesh], sight: &Sight) {
    let depths = Depths::default();
    let ring = &sight.outline.rings[0];
    let tool = cone(&sight.camera, ring, depths.near, depths.far, sight.view, 0);
    let mut serials = Serials::new();
    let Ok(tool) = tool.to_body(&mut serials) else {
        println!("the outer cone does not build");
        return;
    };
    for (i, piece) in pieces.iter().enumerate() {
        let Ok(body) = piece.to_body(&mut serials) else {
            continue;
        };
        let operand = |body| Operand {
            body,
            place: DAffine3::IDENTITY,
        };
        match boolean(operand(&body), operand(&tool), Op::Intersection) {
            Ok(solution) => {
                for (j, shell) in solution.shells.iter().enumerate() {
                    let mesh = Mesh {
                        positions: shell.positions.clone(),
                        faces: shell.faces.clone(),
                        makers: vec![winged::model::Maker::Bound { view: 0 }; shell.faces.len()],
                    };
                    let verdict = self_check(&mesh).err().unwrap_or_else(|| "passes".into());
                    println!("piece {i} ∩ outer cone, shell {j}: {verdict}");
                }
            }
            Err(e) => println!("piece {i} ∩ outer cone: {e}"),
        }
    }
}
