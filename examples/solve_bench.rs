//! Camera solution side by side with OpenCV: winged's solvers on the data of
//! `bench/solve/data.py` (the EPnP paper's protocol), time per solve and accuracy.
//!
//! ```sh
//! cargo run --release --example solve_bench -- DIR OUT.json
//! ```
//!
//! Reads `DIR/index.json` and `DIR/data.f64` (see `bench/solve/data.py`) and, for every
//! set, times each call once per problem (after one warm-up call): `sqpnp` (pixels
//! normalised with the same K as OpenCV, SQPnP on all points) on the sets without
//! outliers, `solve_pnp` with its default options on the sets with at least 6 points, and
//! `solve_pnp_focal` (the focal length unknown, the principal point and aspect known) on
//! the sets with at least 6 points and at most half of them outliers.
//! Writes per set and solver the median and p90 time (µs), the median rotation error
//! (degrees), the median relative translation error (%) and the failures (no answer, or a
//! rotation error over 5°) to `OUT.json`, in the layout of `bench/solve/peer.py`;
//! `bench/solve/report.py` puts the two side by side (see `bench/solve/run.sh`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::{DMat3, DVec2, DVec3};
use serde_json::{Value, json};
use winged::vision::solve::{
    CvPose, PixelIntrinsics, PnpOptions, solve_pnp, solve_pnp_focal, sqpnp,
};

const FAIL_DEGREES: f64 = 5.0;

/// The fewest points the focal length is solved from (the solver's least in general
/// position).
const FOCAL_MIN_POINTS: usize = 6;

/// One problem of a set.
struct Problem {
    truth: CvPose,
    world: Vec<DVec3>,
    pixels: Vec<DVec2>,
}

/// One set of the index.
struct Set {
    name: String,
    n: usize,
    outliers: f64,
    problems: Vec<Problem>,
}

type Error = Box<dyn std::error::Error>;

fn field<'a>(v: &'a Value, key: &str) -> Result<&'a Value, Error> {
    v.get(key)
        .ok_or_else(|| format!("index.json: no {key:?}").into())
}

fn number(v: &Value, key: &str) -> Result<f64, Error> {
    field(v, key)?
        .as_f64()
        .ok_or_else(|| format!("index.json: {key:?} is not a number").into())
}

fn count(v: &Value, key: &str) -> Result<usize, Error> {
    field(v, key)?
        .as_u64()
        .map(|c| c as usize)
        .ok_or_else(|| format!("index.json: {key:?} is not a count").into())
}

/// The intrinsics and sets of `dir`.
fn read(dir: &Path) -> Result<(PixelIntrinsics, Vec<Set>), Error> {
    let index: Value = serde_json::from_slice(&std::fs::read(dir.join("index.json"))?)?;
    let bytes = std::fs::read(dir.join("data.f64"))?;
    let data: Vec<f64> = bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().expect("chunks of 8")))
        .collect();
    let k = PixelIntrinsics {
        fx: number(&index, "fx")?,
        fy: number(&index, "fy")?,
        cx: number(&index, "cx")?,
        cy: number(&index, "cy")?,
    };
    let mut sets = Vec::new();
    for s in field(&index, "sets")?
        .as_array()
        .ok_or("index.json: sets is not a list")?
    {
        let n = count(s, "n")?;
        let mut at = count(s, "offset")?;
        let mut problems = Vec::new();
        for _ in 0..count(s, "trials")? {
            let chunk = data
                .get(at..at + 12 + 6 * n)
                .ok_or("data.f64 is shorter than index.json says")?;
            let r = &chunk[..9];
            let rotation =
                DMat3::from_cols_array(&[r[0], r[3], r[6], r[1], r[4], r[7], r[2], r[5], r[8]]);
            let truth = CvPose::new(rotation, DVec3::new(chunk[9], chunk[10], chunk[11]));
            let world = chunk[12..12 + 3 * n]
                .chunks_exact(3)
                .map(|c| DVec3::new(c[0], c[1], c[2]))
                .collect();
            let pixels = chunk[12 + 3 * n..12 + 5 * n]
                .chunks_exact(2)
                .map(|c| DVec2::new(c[0], c[1]))
                .collect();
            problems.push(Problem {
                truth,
                world,
                pixels,
            });
            at += 12 + 6 * n;
        }
        sets.push(Set {
            name: field(s, "name")?
                .as_str()
                .ok_or("index.json: name is not a string")?
                .to_owned(),
            n,
            outliers: number(s, "outliers")?,
            problems,
        });
    }
    Ok((k, sets))
}

fn median(v: &mut [f64]) -> f64 {
    percentile(v, 0.5)
}

/// The `p` quantile (nearest rank on the sorted samples, as numpy's default
/// interpolates between them; the difference is below the timing noise), NaN when empty.
fn percentile(v: &mut [f64], p: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let x = (v.len() - 1) as f64 * p;
    let (lo, hi) = (x.floor() as usize, x.ceil() as usize);
    v[lo] + (v[hi] - v[lo]) * (x - lo as f64)
}

/// Times `solve` on every problem of `set` and measures its accuracy.
/// A solver's answer: the pose, and the focal length when it solved that too.
type Answer = Option<(CvPose, Option<f64>)>;

/// One of the solvers compared.
type Solver<'a> = Box<dyn Fn(&Problem) -> Answer + 'a>;

/// Times `solve` on every problem of `set` and measures its accuracy (and, for a solver
/// that answers a focal length, the median of its error relative to the true one, %).
fn run(set: &Set, focal: f64, mut solve: impl FnMut(&Problem) -> Answer) -> Value {
    if let Some(first) = set.problems.first() {
        std::hint::black_box(solve(first));
    }
    let mut times = Vec::new();
    let mut rot = Vec::new();
    let mut trans = Vec::new();
    let mut focal_errors = Vec::new();
    let mut failures = 0;
    for p in &set.problems {
        let start = Instant::now();
        let pose = std::hint::black_box(solve(p));
        times.push(start.elapsed().as_secs_f64() * 1e6);
        let Some((pose, f)) = pose else {
            failures += 1;
            continue;
        };
        if let Some(f) = f {
            focal_errors.push(100.0 * (f - focal).abs() / focal);
        }
        let degrees = pose.rotation_angle_to(&p.truth).to_degrees();
        failures += usize::from(degrees > FAIL_DEGREES);
        rot.push(degrees);
        trans.push(
            100.0 * (pose.translation - p.truth.translation).length()
                / p.truth.translation.length(),
        );
    }
    let mut row = json!({
        "median_us": median(&mut times),
        "p90_us": percentile(&mut times, 0.9),
        "rot_deg": median(&mut rot),
        "trans_pct": median(&mut trans),
        "failures": failures,
        "trials": set.problems.len(),
    });
    if !focal_errors.is_empty() {
        row["focal_pct"] = json!(median(&mut focal_errors));
    }
    row
}

fn main() -> Result<(), Error> {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [dir, out] = args.as_slice() else {
        return Err("usage: solve_bench DIR OUT.json".into());
    };
    let (k, sets) = read(dir)?;
    let options = PnpOptions::default();
    let mut rows = Vec::new();
    for set in &sets {
        let mut solvers: Vec<(&str, Solver)> = Vec::new();
        if set.outliers == 0.0 {
            solvers.push((
                "sqpnp",
                Box::new(|p: &Problem| {
                    let m: Vec<DVec2> = p.pixels.iter().map(|&q| k.normalise(q)).collect();
                    sqpnp(&p.world, &m, None).ok().map(|s| (s.best.pose, None))
                }),
            ));
        }
        if set.n >= options.min_inliers {
            solvers.push((
                "solve_pnp",
                Box::new(|p: &Problem| {
                    solve_pnp(&p.world, &p.pixels, &k, &options)
                        .ok()
                        .map(|s| (s.pose, None))
                }),
            ));
        }
        if set.n >= FOCAL_MIN_POINTS && set.outliers <= 0.5 {
            let principal = DVec2::new(k.cx, k.cy);
            let aspect = k.fy / k.fx;
            solvers.push((
                "focal",
                Box::new(move |p: &Problem| {
                    solve_pnp_focal(&p.world, &p.pixels, principal, aspect, &options)
                        .ok()
                        .map(|s| (s.solution.pose, Some(s.fx)))
                }),
            ));
        }
        for (name, solve) in solvers {
            let mut row = run(set, k.fx, solve);
            let focal = row
                .get("focal_pct")
                .and_then(Value::as_f64)
                .map_or(String::new(), |f| format!(", focal {f:.3} %"));
            println!(
                "{:>16} {name:>10}: {:9.1} us (p90 {:9.1}), {:.4} deg, {:.3} %, {} failures{focal}",
                set.name,
                row["median_us"].as_f64().unwrap_or(f64::NAN),
                row["p90_us"].as_f64().unwrap_or(f64::NAN),
                row["rot_deg"].as_f64().unwrap_or(f64::NAN),
                row["trans_pct"].as_f64().unwrap_or(f64::NAN),
                row["failures"],
            );
            row["set"] = json!(set.name);
            row["solver"] = json!(name);
            rows.push(row);
        }
    }
    let report = json!({
        "library": format!("winged {}", env!("CARGO_PKG_VERSION")),
        "threshold_px": options.threshold_px,
        "rows": rows,
    });
    std::fs::write(out, serde_json::to_string_pretty(&report)?)?;
    Ok(())
}
