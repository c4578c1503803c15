//! The boolean kernel's correctness run: `--cases N` cases (100,000 by default) drawn
//! round-robin from the property tests' families, each through ∩, ∪ and −, counting
//! panics, refusals, invalid outputs, volume identity failures and (one case in
//! `--determinism-every`) run-to-run or pool-to-pool differences; then
//! `--carve-steps` successive differences (1,000 by default) on the 1/1024 grid,
//! checked against the exact grid volume. Prints a table, the first failures with
//! their family and seed, and the time.
//!
//! `cargo run --release --example boolean_cases -- --cases 100000`

#[allow(dead_code)]
#[path = "harness/mod.rs"]
mod harness;

use std::collections::{HashMap, HashSet};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::Parser;
use harness::carve::carve;
use harness::cases::{Family, generate, validate};
use harness::run::{Pools, run_case};
use harness::verify::Kind;

/// Runs the generated boolean cases and prints what failed.
#[derive(Parser, Debug)]
struct Args {
    /// Number of cases, spread round-robin over the families.
    #[arg(long, default_value_t = 100_000)]
    cases: u64,
    /// The first seed (case i of a family uses seed `seed + i`).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Only this family (grid, rotated, same, concave, handles, everted).
    #[arg(long)]
    family: Option<String>,
    /// Check determinism (second run, pools of 1 and 2 threads) every this many cases
    /// of a family; 0 for never.
    #[arg(long, default_value_t = 100)]
    determinism_every: u64,
    /// Successive differences on the 1/1024 grid; 0 to skip.
    #[arg(long, default_value_t = 1000)]
    carve_steps: usize,
    /// How many failures to print.
    #[arg(long, default_value_t = 20)]
    show: usize,
}

/// Counts for one family.
#[derive(Default)]
struct Tally {
    cases: u64,
    failed: u64,
    by_kind: HashMap<Kind, u64>,
    time: Duration,
}

const KINDS: [(Kind, &str); 5] = [
    (Kind::Panic, "panics"),
    (Kind::Refused, "refused"),
    (Kind::Invalid, "invalid"),
    (Kind::Identity, "identity"),
    (Kind::Nondeterministic, "nondeterministic"),
];

fn main() -> ExitCode {
    let args = Args::parse();
    let families: Vec<Family> = match &args.family {
        None => Family::ALL.to_vec(),
        Some(name) => match Family::parse(name) {
            Some(f) => vec![f],
            None => {
                eprintln!(
                    "no family {name:?}; the families are grid, rotated, same, concave, handles, everted"
                );
                return ExitCode::from(2);
            }
        },
    };
    let pools = match Pools::new() {
        Ok(p) => p,
        Err(e) => {
            eprintln!("rayon pools: {e}");
            return ExitCode::FAILURE;
        }
    };
    let start = Instant::now();
    let mut tallies: Vec<Tally> = families.iter().map(|_| Tally::default()).collect();
    let mut shown = Vec::new();
    let mut bad = false;
    for i in 0..args.cases {
        let k = (i % families.len() as u64) as usize;
        let family = families[k];
        let index = i / families.len() as u64;
        let seed = args.seed + index;
        let tally = &mut tallies[k];
        let t = Instant::now();
        let case = match generate(family, seed) {
            Ok(c) => c,
            Err(e) => {
                eprintln!("{}:{seed} could not be generated: {e}", family.name());
                bad = true;
                continue;
            }
        };
        if let Err(why) = validate(&case) {
            eprintln!("{}:{seed} generated an invalid body: {why}", family.name());
            bad = true;
            continue;
        }
        let check = args.determinism_every > 0 && index.is_multiple_of(args.determinism_every);
        let found = run_case(&case, check.then_some(&pools));
        tally.time += t.elapsed();
        tally.cases += 1;
        if !found.is_empty() {
            tally.failed += 1;
            let kinds: HashSet<Kind> = found.iter().map(|(_, f)| f.kind()).collect();
            for kind in kinds {
                *tally.by_kind.entry(kind).or_default() += 1;
            }
            if shown.len() < args.show {
                let (op, fault) = &found[0];
                shown.push(format!(
                    "{}:{seed} ({}) {op:?}: {fault}",
                    family.name(),
                    case.what
                ));
            }
        }
    }
    print_table(&families, &tallies);
    if !shown.is_empty() {
        println!(
            "\nfirst failures (family:seed; rerun one with BOOLEAN_PROPS_CASE=family:seed cargo test --test boolean_props):"
        );
        for s in &shown {
            println!("  {s}");
        }
    }
    println!("\ncases: {:.1} s", start.elapsed().as_secs_f64());
    if args.carve_steps > 0 {
        let t = Instant::now();
        match carve(args.seed, args.carve_steps) {
            Ok(done) => println!(
                "carving: {} differences on the 1/1024 grid: {} pieces, {} faces, volume {} m³ = exact {} m³ ({} grid boxes); {:.1} s",
                done.steps,
                done.pieces,
                done.faces,
                done.volume,
                done.exact,
                done.grid_boxes,
                t.elapsed().as_secs_f64()
            ),
            Err(e) => {
                bad = true;
                println!(
                    "carving: FAILED at step {}: {}; {:.1} s",
                    e.step,
                    e.fault,
                    t.elapsed().as_secs_f64()
                );
            }
        }
    }
    println!("total: {:.1} s", start.elapsed().as_secs_f64());
    let failed: u64 = tallies.iter().map(|t| t.failed).sum();
    if failed > 0 || bad {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}

/// The summary table, one row per family and a total.
fn print_table(families: &[Family], tallies: &[Tally]) {
    print!("| family | cases | failed |");
    for (_, name) in KINDS {
        print!(" {name} |");
    }
    println!(" ms/case |");
    println!("|---|---:|---:|{}---:|", "---:|".repeat(KINDS.len()));
    let mut total = Tally::default();
    for (family, t) in families.iter().zip(tallies) {
        row(family.name(), t);
        total.cases += t.cases;
        total.failed += t.failed;
        total.time += t.time;
        for (k, n) in &t.by_kind {
            *total.by_kind.entry(*k).or_default() += n;
        }
    }
    row("all", &total);
}

fn row(name: &str, t: &Tally) {
    print!("| {name} | {} | {} |", t.cases, t.failed);
    for (kind, _) in KINDS {
        print!(" {} |", t.by_kind.get(&kind).copied().unwrap_or(0));
    }
    println!(
        " {:.3} |",
        t.time.as_secs_f64() * 1e3 / t.cases.max(1) as f64
    );
}
