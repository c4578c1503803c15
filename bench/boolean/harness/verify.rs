//! The checks of one boolean's output, shell by shell:
//!
//! 1. the shell builds with `Body::from_polygons`; a shell that bounds an infinite
//!    interior or a cavity (negative volume) cannot, since `from_polygons` refuses
//!    inward surfaces, so it is built with its rings reversed and then everted;
//! 2. the body passes `check_solid(_, 1e-9)`, except the `Inward` check for such a
//!    negative shell;
//! 3. no face has zero area;
//! 4. F − E + V = 2(1 − H), counted on the shell's own lists;
//! 5. every face's source names a face of the operand it says, the face lies in that
//!    source face's placed plane, and faces the same way (the opposite way for B's faces
//!    in a difference).

use glam::DVec3;
use winged::model::boolean::{BooleanError, Op, Operand, Shell, Solution, Which};
use winged::model::solids::BuildError;
use winged::model::{Body, Serials, Violation, check_solid};

/// One thing wrong with a case's outputs.
#[derive(Clone, Debug)]
pub enum Fault {
    /// The kernel panicked.
    Panicked(String),
    /// The kernel refused valid operands.
    Refused(BooleanError),
    /// A shell does not build.
    Build { shell: usize, error: BuildError },
    /// A built shell fails the validator.
    Invalid { shell: usize, report: String },
    /// A face of zero area.
    ZeroArea { shell: usize, face: usize },
    /// The shell's F − E + V disagrees with its handles.
    Euler {
        shell: usize,
        chi: i64,
        handles: u32,
    },
    /// A face's source is wrong.
    Source {
        shell: usize,
        face: usize,
        why: String,
    },
    /// A volume identity fails.
    Identity(String),
    /// The same inputs gave different outputs.
    Nondeterministic(String),
}

/// The kinds of [`Fault`] counted apart in the summaries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// A panic.
    Panic,
    /// A refusal.
    Refused,
    /// An output that fails a check of this module.
    Invalid,
    /// A volume identity.
    Identity,
    /// Run-to-run or pool-to-pool differences.
    Nondeterministic,
}

impl Fault {
    /// Its kind.
    pub fn kind(&self) -> Kind {
        match self {
            Fault::Panicked(_) => Kind::Panic,
            Fault::Refused(_) => Kind::Refused,
            Fault::Identity(_) => Kind::Identity,
            Fault::Nondeterministic(_) => Kind::Nondeterministic,
            _ => Kind::Invalid,
        }
    }
}

impl std::fmt::Display for Fault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fault::Panicked(m) => write!(f, "panicked: {m}"),
            Fault::Refused(e) => write!(f, "refused: {e}"),
            Fault::Build { shell, error } => write!(f, "shell {shell} does not build: {error}"),
            Fault::Invalid { shell, report } => write!(f, "shell {shell} is invalid: {report}"),
            Fault::ZeroArea { shell, face } => write!(f, "shell {shell} face {face} has zero area"),
            Fault::Euler {
                shell,
                chi,
                handles,
            } => {
                write!(f, "shell {shell}: F−E+V = {chi} with {handles} handles")
            }
            Fault::Source { shell, face, why } => write!(f, "shell {shell} face {face}: {why}"),
            Fault::Identity(m) => write!(f, "volume identity: {m}"),
            Fault::Nondeterministic(m) => write!(f, "nondeterministic: {m}"),
        }
    }
}

/// A checked output: its shells as bodies and its signed volume.
#[derive(Debug)]
pub struct Built {
    /// Each shell's body (everted where the shell's volume is negative).
    pub bodies: Vec<Body>,
    /// The sum of the shells' signed volumes.
    pub volume: f64,
}

/// Builds one shell: directly, or reversed and everted when it faces inward. Returns
/// the body and whether it was everted.
pub fn build_shell(shell: &Shell) -> Result<(Body, bool), BuildError> {
    let mut serials = Serials::new();
    match Body::from_polygons(&mut serials, &shell.positions, &shell.faces) {
        Err(BuildError::Inward { .. }) => {
            let reversed: Vec<Vec<u32>> = shell
                .faces
                .iter()
                .map(|f| f.iter().rev().copied().collect())
                .collect();
            let mut body = Body::from_polygons(&mut serials, &shell.positions, &reversed)?;
            body.evert();
            Ok((body, true))
        }
        other => other.map(|b| (b, false)),
    }
}

/// Checks `solution`, the output of `op` on `a` and `b`; `scale` is the operands' size
/// (for the plane tolerance).
pub fn verify(
    a: Operand<'_>,
    b: Operand<'_>,
    op: Op,
    solution: &Solution,
    scale: f64,
) -> Result<Built, Vec<Fault>> {
    let mut faults = Vec::new();
    let mut bodies = Vec::with_capacity(solution.shells.len());
    let mut volume = 0.0;
    for (i, shell) in solution.shells.iter().enumerate() {
        let (body, everted) = match build_shell(shell) {
            Ok(built) => built,
            Err(error) => {
                faults.push(Fault::Build { shell: i, error });
                continue;
            }
        };
        let report = check_solid(&body, 1e-9);
        let bad: Vec<String> = report
            .violations
            .iter()
            .filter(|v| !(everted && matches!(v, Violation::Inward { .. })))
            .map(|v| v.to_string())
            .collect();
        if !bad.is_empty() {
            faults.push(Fault::Invalid {
                shell: i,
                report: bad.join("; "),
            });
        }
        for (k, f) in body.faces().enumerate() {
            if body.face_area(f).is_nan() || body.face_area(f) <= 0.0 {
                faults.push(Fault::ZeroArea { shell: i, face: k });
            }
        }
        let corners: usize = shell.faces.iter().map(Vec::len).sum();
        let chi = shell.faces.len() as i64 - (corners / 2) as i64 + shell.positions.len() as i64;
        if !corners.is_multiple_of(2) || chi != 2 * (1 - i64::from(body.handles())) {
            faults.push(Fault::Euler {
                shell: i,
                chi,
                handles: body.handles(),
            });
        }
        check_sources(a, b, op, i, shell, scale, &mut faults);
        volume += body.volume();
        bodies.push(body);
    }
    if faults.is_empty() {
        Ok(Built { bodies, volume })
    } else {
        Err(faults)
    }
}

/// Check 5 for every face of one shell.
fn check_sources(
    a: Operand<'_>,
    b: Operand<'_>,
    op: Op,
    i: usize,
    shell: &Shell,
    scale: f64,
    faults: &mut Vec<Fault>,
) {
    if shell.sources.len() != shell.faces.len() {
        faults.push(Fault::Source {
            shell: i,
            face: 0,
            why: format!(
                "{} sources for {} faces",
                shell.sources.len(),
                shell.faces.len()
            ),
        });
        return;
    }
    let tolerance = 1e-9 * scale;
    for (k, (ring, source)) in shell.faces.iter().zip(&shell.sources).enumerate() {
        let operand = match source.operand {
            Which::A => a,
            Which::B => b,
        };
        let Some(face) = operand.body.face_by_serial(source.face) else {
            faults.push(Fault::Source {
                shell: i,
                face: k,
                why: format!("{source:?} names no face of {:?}", source.operand),
            });
            continue;
        };
        let placed: Vec<DVec3> = operand
            .body
            .face_vertices(face)
            .map(|v| operand.place.transform_point3(operand.body.position(v)))
            .collect();
        let (normal, center) = newell(&placed);
        if normal.length() == 0.0 {
            continue;
        }
        let unit = normal.normalize();
        let points: Vec<DVec3> = ring
            .iter()
            .filter_map(|&v| shell.positions.get(v as usize).copied())
            .collect();
        let off = points
            .iter()
            .map(|p| unit.dot(*p - center).abs())
            .fold(0.0, f64::max);
        if off > tolerance {
            faults.push(Fault::Source {
                shell: i,
                face: k,
                why: format!("a vertex is {off:e} off the plane of {source:?}"),
            });
        }
        let (out, _) = newell(&points);
        // Slivers' normals are unreliable once rounded; check the sizeable faces.
        if out.length() * 0.5 > 1e-9 * scale * scale {
            let flipped = op == Op::Difference && source.operand == Which::B;
            let agree = out.normalize().dot(unit);
            if (flipped && agree > -0.5) || (!flipped && agree < 0.5) {
                faults.push(Fault::Source {
                    shell: i,
                    face: k,
                    why: format!("faces the wrong way for {source:?} (cosine {agree:.3})"),
                });
            }
        }
    }
}

/// The Newell normal (twice the vector area) and the mean point of a ring.
fn newell(points: &[DVec3]) -> (DVec3, DVec3) {
    let mut n = DVec3::ZERO;
    let mut sum = DVec3::ZERO;
    for (k, &p) in points.iter().enumerate() {
        let q = points[(k + 1) % points.len()];
        n += DVec3::new(
            (p.y - q.y) * (p.z + q.z),
            (p.z - q.z) * (p.x + q.x),
            (p.x - q.x) * (p.y + q.y),
        );
        sum += p;
    }
    (n, sum / points.len().max(1) as f64)
}

/// Whether two solutions are bit for bit the same.
pub fn bit_identical(x: &Solution, y: &Solution) -> bool {
    let same_points = |p: &[DVec3], q: &[DVec3]| {
        p.len() == q.len()
            && p.iter()
                .zip(q)
                .all(|(u, v)| u.to_array().map(f64::to_bits) == v.to_array().map(f64::to_bits))
    };
    x.shells.len() == y.shells.len()
        && x.shells.iter().zip(&y.shells).all(|(s, t)| {
            same_points(&s.positions, &t.positions) && s.faces == t.faces && s.sources == t.sources
        })
}

/// The signed volume of an operand (a rigid place keeps it).
pub fn operand_volume(o: Operand<'_>) -> f64 {
    o.body.volume()
}
