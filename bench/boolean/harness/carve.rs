//! Successive differences on the 1/1024 grid: the block [0, 1]³ less `steps` random
//! boxes whose corners are multiples of 1/1024, taken one after another through the
//! kernel; after every step the pieces' volume must equal, exactly, the volume counted
//! by [`BoxSet`] on the grid.
//!
//! Every cutter reaches the block's boundary (most go beyond it), so no cavity can
//! form: what a cutter removes joins the outside. The region may fall apart into
//! several pieces; each piece is a body of its own and every cutter is taken from each
//! piece whose bounds it touches. Every locus must stay a multiple of 2⁻¹⁰ (the
//! coordinates do not drift), and each piece's volume is summed exactly, in integers of
//! the grid, from its faces.

use glam::{DAffine3, DVec3};
use winged::model::boolean::{Op, Operand, boolean};
use winged::model::solids::box_solid;
use winged::model::{Body, Serials};

use super::draw::{Draw, rng_for};
use super::grid::{BoxSet, IBox};
use super::quiet::catching;
use super::shapes::box_at;
use super::verify::{Fault, verify};

/// Grid cells per meter.
pub const UNIT: i64 = 1024;

/// The block the cutters are taken from, in grid units.
pub const BLOCK: IBox = IBox {
    lo: [0, 0, 0],
    hi: [UNIT, UNIT, UNIT],
};

/// `count` cutters for `seed`: boxes of 64 to 384 units a side (half of the corners
/// snapped to multiples of 64, so that cutters share planes), each reaching past the
/// block on one side (or flush with it, one time in five).
pub fn cutters(seed: u64, count: usize) -> Vec<IBox> {
    let mut rng = rng_for(100, seed);
    (0..count)
        .map(|_| {
            let mut lo = [0; 3];
            let mut hi = [0; 3];
            for k in 0..3 {
                if rng.chance(0.5) {
                    lo[k] = rng.int(0, 15) * 64;
                    hi[k] = (lo[k] + rng.int(1, 6) * 64).min(UNIT);
                } else {
                    lo[k] = rng.int(0, UNIT - 64);
                    hi[k] = (lo[k] + rng.int(64, 384)).min(UNIT);
                }
            }
            let k = rng.below(3);
            let beyond = if rng.chance(0.2) { 0 } else { 32 };
            if rng.chance(0.5) {
                lo[k] = -beyond;
            } else {
                hi[k] = UNIT + beyond;
            }
            IBox { lo, hi }
        })
        .collect()
}

/// What a carving run ended with.
#[derive(Clone, Debug)]
pub struct Carved {
    /// Steps taken.
    pub steps: usize,
    /// Pieces left.
    pub pieces: usize,
    /// Faces over all pieces.
    pub faces: usize,
    /// The pieces' volume (m³).
    pub volume: f64,
    /// The volume counted on the grid (m³).
    pub exact: f64,
    /// Boxes the grid count held at the end.
    pub grid_boxes: usize,
}

/// A fault at a step of the run.
#[derive(Clone, Debug)]
pub struct CarveFault {
    /// The step (0-based).
    pub step: usize,
    /// What went wrong.
    pub fault: Fault,
}

/// Meters from grid units (exact: a power-of-two scale).
fn meters(v: [i64; 3]) -> DVec3 {
    DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64) / UNIT as f64
}

/// Takes `steps` cutters of `seed` from the block, checking every output and the exact
/// volume after every step.
pub fn carve(seed: u64, steps: usize) -> Result<Carved, CarveFault> {
    let at = |step: usize| move |fault: Fault| CarveFault { step, fault };
    let mut serials = Serials::new();
    let block = box_at(&mut serials, meters(BLOCK.lo), meters(BLOCK.hi))
        .map_err(|e| at(0)(Fault::Panicked(format!("the block: {e}"))))?;
    let mut pieces = vec![block];
    let mut grid = BoxSet::new(BLOCK);
    let cuts = cutters(seed, steps);
    for (step, cut) in cuts.iter().enumerate() {
        let (lo, hi) = (meters(cut.lo), meters(cut.hi));
        let cutter = box_solid(&mut serials, hi - lo)
            .map_err(|e| at(step)(Fault::Panicked(format!("the cutter: {e}"))))?;
        let place = DAffine3::from_translation((lo + hi) * 0.5);
        let mut next = Vec::with_capacity(pieces.len() + 2);
        for piece in pieces {
            let touches = piece
                .bounds()
                .is_some_and(|b| (0..3).all(|k| b.min[k] <= hi[k] && lo[k] <= b.max[k]));
            if !touches {
                next.push(piece);
                continue;
            }
            next.extend(cut_piece(&piece, &cutter, place).map_err(at(step))?);
        }
        pieces = next;
        grid.subtract(cut);
        let mut six: i128 = 0;
        for piece in &pieces {
            six += six_volume_in_cells(piece).map_err(|e| at(step)(Fault::Identity(e)))?;
        }
        let counted = 6 * grid.volume() as i128;
        if six != counted {
            return Err(at(step)(Fault::Identity(format!(
                "the pieces hold {} cells, the grid counts {} (off by {} sixths of a cell)",
                six as f64 / 6.0,
                grid.volume(),
                six - counted
            ))));
        }
    }
    Ok(Carved {
        steps,
        pieces: pieces.len(),
        faces: pieces.iter().map(Body::face_count).sum(),
        volume: pieces.iter().map(Body::volume).sum(),
        exact: grid.volume() as f64 / (UNIT * UNIT * UNIT) as f64,
        grid_boxes: grid.len(),
    })
}

/// Six times `body`'s volume in grid cells, summed exactly over fans of its faces;
/// refused if a locus is off the grid.
fn six_volume_in_cells(body: &Body) -> Result<i128, String> {
    let cell = |p: DVec3| -> Result<[i128; 3], String> {
        let q = p * UNIT as f64;
        if q.round() != q {
            return Err(format!("locus {p} is off the 1/{UNIT} grid"));
        }
        Ok([q.x as i128, q.y as i128, q.z as i128])
    };
    let mut six = 0i128;
    for f in body.faces() {
        let ring: Vec<[i128; 3]> = body
            .face_vertices(f)
            .map(|v| cell(body.position(v)))
            .collect::<Result<_, _>>()?;
        for k in 1..ring.len().saturating_sub(1) {
            let (a, b, c) = (ring[0], ring[k], ring[k + 1]);
            let cross = [
                b[1] * c[2] - b[2] * c[1],
                b[2] * c[0] - b[0] * c[2],
                b[0] * c[1] - b[1] * c[0],
            ];
            six += a[0] * cross[0] + a[1] * cross[1] + a[2] * cross[2];
        }
    }
    Ok(six)
}

/// `piece − cutter`, checked; its shells as bodies (none may be a cavity).
fn cut_piece(piece: &Body, cutter: &Body, place: DAffine3) -> Result<Vec<Body>, Fault> {
    let a = Operand {
        body: piece,
        place: DAffine3::IDENTITY,
    };
    let b = Operand {
        body: cutter,
        place,
    };
    let solution = match catching(|| boolean(a, b, Op::Difference)) {
        Err(message) => return Err(Fault::Panicked(message)),
        Ok(Err(error)) => return Err(Fault::Refused(error)),
        Ok(Ok(solution)) => solution,
    };
    let built = verify(a, b, Op::Difference, &solution, 2.0).map_err(|faults| {
        faults
            .into_iter()
            .next()
            .unwrap_or(Fault::Identity("no fault".into()))
    })?;
    if let Some(shell) = built.bodies.iter().position(|b| b.volume() < 0.0) {
        return Err(Fault::Invalid {
            shell,
            report: "a cavity, which no cutter can make".into(),
        });
    }
    Ok(built.bodies)
}
