//! One case through ∩, ∪ and −: panics caught, outputs verified, volume identities
//! checked, and (when asked) the same booleans run again on the calling thread and on
//! rayon pools of one and of two threads, whose outputs must be bit-identical.

use rayon::{ThreadPool, ThreadPoolBuildError, ThreadPoolBuilder};
use winged::model::boolean::{BooleanError, Op, Solution, boolean};

use super::cases::Case;
use super::identity::{self, Volumes};
use super::quiet::catching;
use super::verify::{Fault, bit_identical, operand_volume, verify};

/// The three operations, in the order they are run.
pub const OPS: [Op; 3] = [Op::Intersection, Op::Union, Op::Difference];

/// Rayon pools of one and two threads for the determinism checks.
pub struct Pools {
    one: ThreadPool,
    two: ThreadPool,
}

impl Pools {
    /// Builds both pools.
    pub fn new() -> Result<Pools, ThreadPoolBuildError> {
        Ok(Pools {
            one: ThreadPoolBuilder::new().num_threads(1).build()?,
            two: ThreadPoolBuilder::new().num_threads(2).build()?,
        })
    }
}

/// A fault found in a case, with the operation it came from (`None` for the
/// identities, which involve all three).
pub type Found = (Option<Op>, Fault);

/// Runs `op` on the case's operands, a panic caught as an `Err`.
fn solve(case: &Case, op: Op) -> Result<Result<Solution, BooleanError>, String> {
    let (a, b) = case.operands();
    catching(|| boolean(a, b, op))
}

/// Runs the case's three booleans and every check; determinism is checked when
/// `pools` is given. Returns every fault found (none when the case passes).
pub fn run_case(case: &Case, pools: Option<&Pools>) -> Vec<Found> {
    let (a, b) = case.operands();
    let scale = case.scale();
    let mut found = Vec::new();
    let mut volumes = [f64::NAN; 3];
    for (k, op) in OPS.into_iter().enumerate() {
        let solution = match solve(case, op) {
            Err(message) => {
                found.push((Some(op), Fault::Panicked(message)));
                continue;
            }
            Ok(Err(error)) => {
                found.push((Some(op), Fault::Refused(error)));
                continue;
            }
            Ok(Ok(solution)) => solution,
        };
        match verify(a, b, op, &solution, scale) {
            Ok(built) => volumes[k] = built.volume,
            Err(faults) => found.extend(faults.into_iter().map(|f| (Some(op), f))),
        }
        if let Some(pools) = pools {
            let runs = [
                ("a second run", solve(case, op)),
                ("a pool of 1 thread", pools.one.install(|| solve(case, op))),
                ("a pool of 2 threads", pools.two.install(|| solve(case, op))),
            ];
            for (name, again) in runs {
                let same = matches!(&again, Ok(Ok(s)) if bit_identical(s, &solution));
                if !same {
                    found.push((Some(op), Fault::Nondeterministic(format!("{name} differs"))));
                }
            }
        }
    }
    if volumes.iter().all(|v| !v.is_nan()) {
        let v = Volumes {
            a: operand_volume(a),
            b: operand_volume(b),
            intersection: volumes[0],
            union: volumes[1],
            difference: volumes[2],
        };
        if let Err(message) = identity::check(v, case.exact) {
            found.push((None, Fault::Identity(message)));
        }
    }
    found
}
