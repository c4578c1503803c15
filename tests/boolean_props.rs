//! Properties of `winged::model::boolean` on thousands of generated cases.
//!
//! For each case (see `bench/boolean/harness/cases/` for the families) and each of
//! ∩, ∪ and −: every shell builds and is a valid solid, no face has zero area, Euler's
//! formula holds per shell, every face names a real source face in whose plane it lies,
//! and the volume identities hold (exactly on integer-grid cases, to 1e-12 of the
//! largest volume otherwise; everted operands included, with signed volumes). One case
//! in eight is also run again, and on rayon pools of one and two threads, and must give
//! bit-identical output. Then 200 successive differences on the 1/1024 grid must keep
//! the exact volume (the bench program `boolean_cases` runs 1,000).
//!
//! A failure prints its family and seed; rerun just that case with
//! `BOOLEAN_PROPS_CASE=family:seed cargo test --test boolean_props`. Scale the number of
//! cases with `BOOLEAN_PROPS_SCALE` (a factor, 1 by default).

#[allow(dead_code)]
#[path = "../bench/boolean/harness/mod.rs"]
mod harness;

use harness::carve::carve;
use harness::cases::{Family, generate, validate};
use harness::grid::{BoxSet, IBox};
use harness::run::{Pools, run_case};

/// Every how many cases the determinism checks run.
const DETERMINISM_EVERY: u64 = 8;

/// The single case asked for by `BOOLEAN_PROPS_CASE=family:seed`, if any.
fn only_case() -> Option<(Family, u64)> {
    let spec = std::env::var("BOOLEAN_PROPS_CASE").ok()?;
    let (family, seed) = spec.split_once(':')?;
    Some((Family::parse(family)?, seed.trim().parse().ok()?))
}

/// The number of cases to run, scaled by `BOOLEAN_PROPS_SCALE`.
fn scaled(count: u64) -> u64 {
    let factor: f64 = std::env::var("BOOLEAN_PROPS_SCALE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0);
    ((count as f64 * factor).round() as u64).max(1)
}

/// Runs `count` cases of `family` and fails with the first few failures.
fn run_family(family: Family, count: u64) {
    let seeds: Vec<u64> = match only_case() {
        Some((f, seed)) if f == family => vec![seed],
        Some(_) => return,
        None => (0..scaled(count)).collect(),
    };
    let pools = Pools::new().expect("rayon pools of 1 and 2 threads");
    let mut failures = Vec::new();
    let mut failed_cases = 0;
    for &seed in &seeds {
        let case = generate(family, seed).expect("the generators make valid bodies");
        let check = seed.is_multiple_of(DETERMINISM_EVERY) || seeds.len() == 1;
        let found = run_case(&case, check.then_some(&pools));
        if !found.is_empty() {
            failed_cases += 1;
            if failures.len() < 10 {
                let (op, fault) = &found[0];
                failures.push(format!(
                    "{}:{seed} ({}) {op:?}: {fault} [and {} more]",
                    family.name(),
                    case.what,
                    found.len() - 1
                ));
            }
            if failed_cases >= 50 {
                break;
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{failed_cases} failing cases of {} (rerun one with BOOLEAN_PROPS_CASE=family:seed):\n{}",
        family.name(),
        failures.join("\n")
    );
}

#[test]
fn generated_bodies_are_valid_solids() {
    for family in Family::ALL {
        for seed in 0..300 {
            let case = generate(family, seed)
                .unwrap_or_else(|e| panic!("{}:{seed} not generated: {e}", family.name()));
            if let Err(why) = validate(&case) {
                panic!("{}:{seed}: {why}", family.name());
            }
        }
    }
}

#[test]
fn generators_are_deterministic() {
    for family in Family::ALL {
        for seed in [0, 1, 77, 12_345] {
            let (x, y) = (generate(family, seed), generate(family, seed));
            let (x, y) = (x.expect("generated"), y.expect("generated"));
            let points = |b: &winged::model::Body| -> Vec<[u64; 3]> {
                b.vertices()
                    .map(|v| b.position(v).to_array().map(f64::to_bits))
                    .collect()
            };
            assert_eq!(x.what, y.what);
            assert_eq!(points(&x.a), points(&y.a));
            assert_eq!(points(x.body_b()), points(y.body_b()));
            assert_eq!(x.place_b.to_cols_array(), y.place_b.to_cols_array());
        }
    }
}

#[test]
fn every_family_draws_each_of_its_kinds() {
    // Families mix several kinds of pair; 300 seeds should reach them all.
    let kinds = |family: Family, words: &[&str]| {
        for word in words {
            assert!(
                (0..300).any(|s| generate(family, s).is_ok_and(|c| c.what.contains(word))),
                "{} never draws {word}",
                family.name()
            );
        }
    };
    kinds(
        Family::Grid,
        &["independent", "touching", "inside", "equal"],
    );
    kinds(
        Family::Rotated,
        &["0e0°", "1e-12°", "1e-9°", "1e-6°", "moved [0"],
    );
    kinds(
        Family::Concave,
        &["L", "comb", "star", "interleaved", "on its side"],
    );
    kinds(
        Family::Handles,
        &[
            "bar",
            "cut",
            "linked frames",
            "torus and box",
            "linked tori",
            "hole",
        ],
    );
    kinds(
        Family::Everted,
        &["everted A:", "everted B:", "everted A and B:"],
    );
}

#[test]
fn exact_box_sets_match_a_voxel_count() {
    let n = 16i64;
    let mut rng = harness::draw::rng_for(7, 0);
    use harness::draw::Draw;
    let start = IBox {
        lo: [0; 3],
        hi: [n; 3],
    };
    let mut set = BoxSet::new(start);
    let mut voxels = vec![true; (n * n * n) as usize];
    for _ in 0..200 {
        let mut lo = [0; 3];
        let mut hi = [0; 3];
        for k in 0..3 {
            lo[k] = rng.int(-2, n);
            hi[k] = rng.int(lo[k] + 1, n + 2);
        }
        let cut = IBox { lo, hi };
        set.subtract(&cut);
        for (i, v) in voxels.iter_mut().enumerate() {
            let p = [i as i64 % n, i as i64 / n % n, i as i64 / (n * n)];
            if (0..3).all(|k| lo[k] <= p[k] && p[k] < hi[k]) {
                *v = false;
            }
        }
        let count = voxels.iter().filter(|&&v| v).count() as i64;
        assert_eq!(set.volume(), count);
    }
}

#[test]
fn grid_boxes() {
    run_family(Family::Grid, 800);
}

#[test]
#[ignore = "known failure (4 of 600): clusters of vertices a few hundred ulps apart whose edges cannot collapse without breaking the surface leave zero-area faces; issue 29 open"]
fn rotated_boxes() {
    run_family(Family::Rotated, 600);
}

#[test]
#[ignore = "known failure (1 of 200): a turned comb prism is found self-intersecting by 1e-17 m, where its rounded bottom face bends across a side of its own triangulation; issue 29 open"]
fn the_same_body_twice() {
    run_family(Family::Same, 200);
}

#[test]
#[ignore = "known failure (1 of 400): a zero-area face left by a cluster of vertices that cannot collapse, as in rotated_boxes; issue 29 open"]
fn concave_prisms() {
    run_family(Family::Concave, 400);
}

#[test]
fn bodies_with_handles() {
    run_family(Family::Handles, 300);
}

#[test]
fn everted_operands() {
    run_family(Family::Everted, 400);
}

#[test]
fn successive_differences_keep_the_exact_grid_volume() {
    if only_case().is_some() {
        return;
    }
    match carve(1, 200) {
        Ok(done) => assert_eq!(done.steps, 200),
        Err(e) => panic!("carving seed 1, step {}: {}", e.step, e.fault),
    }
}

/// Exact answers for the cases that need no kernel: A op A, and two operands whose
/// bounds are apart (each operand's faces, placed, as shells of their own).
mod trivial {
    use glam::DAffine3;
    use winged::model::Body;
    use winged::model::boolean::{Op, Shell, Solution, Source, Which};

    /// The shell of one placed body, reversed when `flip`.
    pub fn shell(body: &Body, place: DAffine3, which: Which, flip: bool) -> Shell {
        let vertices: Vec<_> = body.vertices().collect();
        let mut index = vec![0u32; vertices.iter().map(|v| v.index() + 1).max().unwrap_or(0)];
        for (i, v) in vertices.iter().enumerate() {
            index[v.index()] = i as u32;
        }
        let mut faces = Vec::new();
        let mut sources = Vec::new();
        for f in body.faces() {
            let mut ring: Vec<u32> = body.face_vertices(f).map(|v| index[v.index()]).collect();
            if flip {
                ring.reverse();
            }
            faces.push(ring);
            sources.push(Source {
                operand: which,
                face: body.face_serial(f),
            });
        }
        let positions = vertices
            .iter()
            .map(|&v| place.transform_point3(body.position(v)))
            .collect();
        Shell {
            positions,
            faces,
            sources,
            cavity_of: None,
        }
    }

    /// A op A for a finite A.
    pub fn same(a: &Body, place: DAffine3, op: Op) -> Solution {
        match op {
            Op::Difference => Solution::default(),
            _ => Solution {
                shells: vec![shell(a, place, Which::A, false)],
                unbounded: false,
            },
        }
    }

    /// A op B for finite A and B whose bounds are apart.
    pub fn apart(a: (&Body, DAffine3), b: (&Body, DAffine3), op: Op) -> Solution {
        let sa = shell(a.0, a.1, Which::A, false);
        let sb = shell(b.0, b.1, Which::B, false);
        Solution {
            shells: match op {
                Op::Intersection => vec![],
                Op::Union => vec![sa, sb],
                Op::Difference => vec![sa],
            },
            unbounded: false,
        }
    }
}

/// Runs the checks of `harness::verify` and `harness::identity` on the three answers.
fn check_answers(
    case: &harness::cases::Case,
    answers: [winged::model::boolean::Solution; 3],
) -> Result<(), String> {
    use harness::identity::{Volumes, check};
    use harness::run::OPS;
    use harness::verify::{operand_volume, verify};
    let (a, b) = case.operands();
    let mut v = [0.0; 3];
    for (k, (op, s)) in OPS.into_iter().zip(&answers).enumerate() {
        let built = verify(a, b, op, s, case.scale()).map_err(|f| {
            format!(
                "{op:?}: {}",
                f.iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join("; ")
            )
        })?;
        v[k] = built.volume;
    }
    let volumes = Volumes {
        a: operand_volume(a),
        b: operand_volume(b),
        intersection: v[0],
        union: v[1],
        difference: v[2],
    };
    check(volumes, case.exact)
}

#[test]
fn the_checks_pass_exact_answers_of_trivial_cases() {
    use harness::run::OPS;
    let mut checked = 0;
    for seed in 0..200 {
        // A op A.
        let case = generate(Family::Same, seed).expect("generated");
        let answers = OPS.map(|op| trivial::same(&case.a, case.place_a, op));
        check_answers(&case, answers).unwrap_or_else(|e| panic!("same:{seed}: {e}"));
        // Grid and everted-grid pairs whose boxes are apart.
        for family in [Family::Grid, Family::Everted] {
            let case = generate(family, seed).expect("generated");
            let (a, b) = case.operands();
            let bounds = |o: winged::model::boolean::Operand<'_>| {
                let bb = o.body.bounds().expect("bounds");
                (
                    o.place.transform_point3(bb.min),
                    o.place.transform_point3(bb.max),
                )
            };
            let ((alo, ahi), (blo, bhi)) = (bounds(a), bounds(b));
            let apart = (0..3).any(|k| ahi[k] < blo[k] || bhi[k] < alo[k]);
            if !apart || a.body.volume() < 0.0 || b.body.volume() < 0.0 {
                continue;
            }
            let answers = OPS.map(|op| trivial::apart((a.body, a.place), (b.body, b.place), op));
            check_answers(&case, answers)
                .unwrap_or_else(|e| panic!("{}:{seed}: {e}", family.name()));
            checked += 1;
        }
    }
    assert!(checked > 20, "only {checked} separated pairs");
    // An everted A op A: A' ∩ A' = A' ∪ A' = A' (one negative shell), A' − A' = ∅.
    let mut case = generate(Family::Grid, 3).expect("generated");
    case.a.evert();
    case.b = None;
    case.place_b = case.place_a;
    let answers = OPS.map(|op| trivial::same(&case.a, case.place_a, op));
    check_answers(&case, answers).expect("an everted body twice");
}

#[test]
fn the_checks_catch_broken_answers() {
    use winged::model::boolean::{Op, Which};
    let case = generate(Family::Grid, 5).expect("generated");
    let (a, b) = case.operands();
    let good = trivial::same(&case.a, case.place_a, Op::Union);
    let verify = |s| harness::verify::verify(a, b, Op::Union, s, case.scale());
    assert!(verify(&good).is_ok());
    // A face turned round: the shell no longer closes consistently.
    let mut bad = good.clone();
    bad.shells[0].faces[0].reverse();
    assert!(verify(&bad).is_err());
    // A source naming the other operand's face serial space wrongly.
    let mut bad = good.clone();
    bad.shells[0].sources[0].operand = Which::B;
    assert!(verify(&bad).is_err());
    // A source naming a face in another plane.
    let mut bad = good.clone();
    bad.shells[0].sources.swap(0, 1);
    assert!(verify(&bad).is_err());
    // A vertex moved off its faces' planes.
    let mut bad = good.clone();
    bad.shells[0].positions[0].x += 0.25;
    assert!(verify(&bad).is_err());
    // A volume identity broken: the union answered with A alone where B is elsewhere.
    assert!(
        harness::identity::check(
            harness::identity::Volumes {
                a: 1.0,
                b: 1.0,
                intersection: 0.0,
                union: 1.0,
                difference: 1.0
            },
            true
        )
        .is_err()
    );
    assert!(!harness::verify::bit_identical(&good, &bad));
    assert!(harness::verify::bit_identical(&good, &good.clone()));
}
