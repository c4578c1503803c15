//! winged's side of the side-by-side with manifold3d (see bench/boolean/README.md).
//!
//! * `write --dir D`: writes each scene's inputs as polygon OFF files (`D/inputs/`,
//!   winged's faces) and as triangle OFF files (the same faces cut into triangles, for
//!   manifold3d), and the list of scenes `D/scenes.json`.
//! * `run --dir D`: reads the polygon inputs back, builds them with
//!   `Body::from_polygons` (not timed) and times the scene's booleans (best of
//!   `--repeat`), writing the result to `D/winged/NAME.off` (polygons) and
//!   `NAME.tri.off` (triangles), and the times to `D/winged.json`.
//!
//! `cargo run --release --example boolean_side -- write --dir /tmp/boolean-side`
//!
//! `RUST_LOG=winged::model::boolean=debug` logs each boolean's phases to stderr.

#[path = "side/off.rs"]
mod off;
#[path = "side/scenes.rs"]
mod scenes;
#[path = "../side_cli.rs"]
mod side_cli;
#[path = "side/tri.rs"]
mod tri;
#[path = "../triangles.rs"]
mod triangles;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::{Parser, Subcommand};
use glam::DAffine3;
use serde_json::{Value, json};
use winged::model::boolean::{Op, Operand, Solution, boolean};
use winged::model::{Body, Serials};

use off::Mesh;

#[derive(Parser, Debug)]
struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Writes the scenes' input meshes and D/scenes.json.
    Write {
        /// The directory to write into.
        #[arg(long)]
        dir: PathBuf,
        /// The spheres' segment counts (2n² triangles each).
        #[arg(long, value_delimiter = ',', default_values_t = [64usize, 128, 256, 512])]
        sizes: Vec<usize>,
    },
    /// Times winged's booleans on the written inputs.
    Run {
        /// The directory `write` wrote.
        #[arg(long)]
        dir: PathBuf,
        /// Runs per scene (the best is reported).
        #[arg(long, default_value_t = 5)]
        repeat: usize,
        /// Only the scene of this name.
        #[arg(long)]
        only: Option<String>,
    },
}

fn main() -> ExitCode {
    // One line per panic (the kernel's panics are caught and reported per scene).
    side_cli::start();
    let result = match Args::parse().command {
        Command::Write { dir, sizes } => write(&dir, &sizes),
        Command::Run { dir, repeat, only } => run(&dir, repeat.max(1), only.as_deref()),
    };
    side_cli::exit(result)
}

fn write(dir: &Path, sizes: &[usize]) -> Result<(), String> {
    let inputs = dir.join("inputs");
    std::fs::create_dir_all(&inputs).map_err(|e| format!("{}: {e}", inputs.display()))?;
    let mut list = Vec::new();
    for scene in scenes::scenes(sizes).map_err(|e| format!("a scene's solid: {e}"))? {
        let mut polys = Vec::new();
        let mut tris = Vec::new();
        let mut triangles = Vec::new();
        for (k, mesh) in scene.inputs.iter().enumerate() {
            let (p, t) = (
                format!("inputs/{}.{k}.off", scene.name),
                format!("inputs/{}.{k}.tri.off", scene.name),
            );
            off::write(&dir.join(&p), mesh).map_err(|e| format!("{p}: {e}"))?;
            off::write(&dir.join(&t), &tri::triangulate(mesh)).map_err(|e| format!("{t}: {e}"))?;
            triangles.push(mesh.triangle_count());
            polys.push(p);
            tris.push(t);
        }
        println!(
            "{}: {:?} of {} inputs, {:?} triangles",
            scene.name,
            scene.op,
            scene.inputs.len(),
            triangles
        );
        list.push(json!({"name": scene.name, "op": scene.op, "inputs": polys, "tri_inputs": tris, "triangles": triangles}));
    }
    let path = dir.join("scenes.json");
    let text = serde_json::to_string_pretty(&list).map_err(|e| e.to_string())?;
    std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))
}

/// One scene as listed in scenes.json.
struct Listed {
    name: String,
    op: Op,
    inputs: Vec<String>,
}

fn listed(dir: &Path) -> Result<Vec<Listed>, String> {
    let path = dir.join("scenes.json");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("{}: {e} (run `write` first)", path.display()))?;
    let list: Vec<Value> =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    list.into_iter()
        .map(|v| {
            let name = v["name"]
                .as_str()
                .ok_or("a scene without a name")?
                .to_string();
            let op: Op =
                serde_json::from_value(v["op"].clone()).map_err(|e| format!("{name}: op: {e}"))?;
            let inputs = v["inputs"]
                .as_array()
                .ok_or(format!("{name}: no inputs"))?
                .iter()
                .map(|p| {
                    p.as_str()
                        .map(str::to_string)
                        .ok_or(format!("{name}: an input that is not a path"))
                })
                .collect::<Result<Vec<_>, _>>()?;
            if inputs.len() < 2 || (inputs.len() > 2 && op != Op::Intersection) {
                return Err(format!("{name}: two inputs, or more for an intersection"));
            }
            Ok(Listed { name, op, inputs })
        })
        .collect()
}

fn run(dir: &Path, repeat: usize, only: Option<&str>) -> Result<(), String> {
    let out_dir = dir.join("winged");
    std::fs::create_dir_all(&out_dir).map_err(|e| format!("{}: {e}", out_dir.display()))?;
    let mut report = serde_json::Map::new();
    println!("| scene | triangles in | winged best (ms) | runs | shells | faces | status |");
    println!("|---|---:|---:|---:|---:|---:|---|");
    for scene in listed(dir)? {
        if only.is_some_and(|o| o != scene.name) {
            continue;
        }
        let mut bodies = Vec::new();
        let mut triangles = 0;
        for p in &scene.inputs {
            let mesh = off::read(&dir.join(p))?;
            triangles += mesh.triangle_count();
            let body = Body::from_polygons(&mut Serials::new(), &mesh.positions, &mesh.faces)
                .map_err(|e| format!("{p}: {e}"))?;
            bodies.push(body);
        }
        let mut runs = Vec::new();
        let mut outcome = Err("not run".to_string());
        for _ in 0..repeat {
            let t = Instant::now();
            let result = side_cli::caught(|| fold(&bodies, scene.op));
            runs.push(t.elapsed().as_secs_f64());
            let failed = result.is_err();
            outcome = result;
            if failed {
                break;
            }
        }
        let best = runs.iter().copied().fold(f64::INFINITY, f64::min);
        let entry = match &outcome {
            Ok(solution) => {
                let mut mesh = Mesh::default();
                for shell in &solution.shells {
                    mesh.append(&Mesh {
                        positions: shell.positions.clone(),
                        faces: shell.faces.clone(),
                    });
                }
                let base = out_dir.join(&scene.name);
                off::write(&base.with_extension("off"), &mesh).map_err(|e| e.to_string())?;
                off::write(&base.with_extension("tri.off"), &tri::triangulate(&mesh))
                    .map_err(|e| e.to_string())?;
                println!(
                    "| {} | {triangles} | {:.3} | {} | {} | {} | ok |",
                    scene.name,
                    best * 1e3,
                    runs.len(),
                    solution.shells.len(),
                    mesh.faces.len()
                );
                json!({"status": "ok", "best_s": best, "runs_s": runs, "shells": solution.shells.len(), "faces": mesh.faces.len(), "triangles_in": triangles})
            }
            Err(why) => {
                println!(
                    "| {} | {triangles} | — | {} | — | — | {why} |",
                    scene.name,
                    runs.len()
                );
                json!({"status": why, "triangles_in": triangles})
            }
        };
        report.insert(scene.name.clone(), entry);
    }
    let path = dir.join("winged.json");
    let text = serde_json::to_string_pretty(&Value::Object(report)).map_err(|e| e.to_string())?;
    std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))
}

/// `bodies[0] op bodies[1] op …`, left to right; between steps each shell is rebuilt as
/// a body (timed: it is part of chaining booleans) and, for an intersection of more
/// than two, the next operand is intersected with each shell.
fn fold(bodies: &[Body], op: Op) -> Result<Solution, String> {
    fn operand(body: &Body) -> Operand<'_> {
        Operand {
            body,
            place: DAffine3::IDENTITY,
        }
    }
    let mut solution = boolean(operand(&bodies[0]), operand(&bodies[1]), op)
        .map_err(|e| format!("refused: {e}"))?;
    for next in &bodies[2..] {
        let mut shells = Vec::new();
        for shell in &solution.shells {
            let body = Body::from_polygons(&mut Serials::new(), &shell.positions, &shell.faces)
                .map_err(|e| format!("a shell midway does not build: {e}"))?;
            let step =
                boolean(operand(&body), operand(next), op).map_err(|e| format!("refused: {e}"))?;
            shells.extend(step.shells);
        }
        solution = Solution {
            shells,
            unbounded: false,
        };
    }
    Ok(solution)
}
