//! A triangle cut along the traces of the other surface: a constrained triangulation
//! of its corners, the points on its edges, and the traces' ends, built with exact
//! orientations in the projection along its dominant normal axis.
//!
//! Points are inserted one by one (splitting the triangle, or the two triangles, that
//! hold each), then each trace is recovered by flipping the edges that cross it (Sloan's
//! method), after cutting it at any point that lies on it. Traces do not cross each
//! other (the surfaces do not cross themselves); if they do, the cut is refused.

use super::Map;

use super::exact::{Fx, Poly, Ring};
use super::intersect::{EdgeKey, edge_key};
use super::point::{Def, Pid, Points};

/// Why a triangle could not be cut.
#[derive(Debug)]
pub(crate) struct CutError;

/// The axis to project a triangle along: one whose projection keeps its area.
pub(crate) fn dominant_axis(pts: &Points, tri: [Pid; 3]) -> u8 {
    let [a, b, c] = tri.map(|p| pts.approx[p as usize]);
    let n = (b - a).cross(c - a).abs();
    let mut order = [0u8, 1, 2];
    order.sort_by(|&i, &j| n[j as usize].total_cmp(&n[i as usize]));
    order
        .into_iter()
        .find(|&k| pts.orient2d(k, tri) != 0)
        .unwrap_or(order[0])
}

/// A cut triangle: its pieces (counter-clockwise as the triangle) and the edges among
/// them that lie on a trace.
#[derive(Debug, Default)]
pub(crate) struct Cut {
    pub pieces: Vec<[Pid; 3]>,
    pub traced: Vec<EdgeKey>,
}

struct Tri2 {
    pts: Vec<[Pid; 3]>,
    alive: Vec<bool>,
    /// Directed edge → the triangle holding it.
    edge: Map<(Pid, Pid), usize>,
}

impl Tri2 {
    fn add(&mut self, t: [Pid; 3]) {
        let i = self.pts.len();
        self.pts.push(t);
        self.alive.push(true);
        for k in 0..3 {
            self.edge.insert((t[k], t[(k + 1) % 3]), i);
        }
    }

    fn kill(&mut self, i: usize) {
        self.alive[i] = false;
        let t = self.pts[i];
        for k in 0..3 {
            if self.edge.get(&(t[k], t[(k + 1) % 3])) == Some(&i) {
                self.edge.remove(&(t[k], t[(k + 1) % 3]));
            }
        }
    }
}

/// Cuts triangle `tri` (input points) by the points `extra` (on its edges or inside
/// it) and the traces `segs` (between its corners and those points). Each extra point
/// comes with the edges of `tri` it is known to lie on (bit `k` for the edge from
/// corner `k` to corner `k + 1`): three points on one edge are collinear without
/// arithmetic.
pub(crate) fn cut(
    pts: &Points,
    tri: [Pid; 3],
    extra: &[(Pid, u8)],
    segs: &[[Pid; 2]],
) -> Result<Cut, CutError> {
    let axis = dominant_axis(pts, tri);
    let sense = pts.orient2d(axis, tri);
    if sense == 0 {
        return Err(CutError);
    }
    let mut on_edges: Map<Pid, u8> =
        Map::with_capacity_and_hasher(extra.len() + 3, Default::default());
    for (k, &corner) in tri.iter().enumerate() {
        on_edges.insert(corner, (1 << k) | (1 << ((k + 2) % 3)));
    }
    for &(p, m) in extra {
        *on_edges.entry(p).or_default() |= m;
    }
    let mask = |p: Pid| on_edges.get(&p).copied().unwrap_or(0);
    let orient = |p: Pid, q: Pid, r: Pid| {
        if mask(p) & mask(q) & mask(r) != 0 {
            0
        } else {
            pts.orient2d(axis, [p, q, r]) * sense
        }
    };
    let mut t = Tri2 {
        pts: Vec::new(),
        alive: Vec::new(),
        edge: Map::default(),
    };
    t.add(tri);
    let mut verts: Vec<Pid> = tri.to_vec();
    for &(p, _) in extra {
        if verts.contains(&p) {
            continue;
        }
        insert_point(pts, &mut t, &orient, p)?;
        verts.push(p);
    }
    let mut traced: Vec<EdgeKey> = Vec::new();
    for &[p, q] in segs {
        insert_segment(pts, &mut t, &orient, &verts, p, q, &mut traced, 0)?;
    }
    let pieces = t
        .pts
        .iter()
        .zip(&t.alive)
        .filter(|(_, a)| **a)
        .map(|(p, _)| *p)
        .collect();
    Ok(Cut { pieces, traced })
}

fn insert_point(
    pts: &Points,
    t: &mut Tri2,
    orient: &impl Fn(Pid, Pid, Pid) -> i8,
    p: Pid,
) -> Result<(), CutError> {
    let (at, slack) = (pts.approx[p as usize], pts.slack[p as usize] + 1e-300);
    for i in 0..t.pts.len() {
        if !t.alive[i] {
            continue;
        }
        let [a, b, c] = t.pts[i];
        // Skip triangles whose box (of approximations, widened by their bounds) misses p.
        let outside = (0..3).any(|k| {
            let vs = [a, b, c].map(|v| (pts.approx[v as usize][k], pts.slack[v as usize]));
            let min = vs.iter().map(|(x, e)| x - e).fold(f64::INFINITY, f64::min);
            let max = vs
                .iter()
                .map(|(x, e)| x + e)
                .fold(f64::NEG_INFINITY, f64::max);
            at[k] + slack < min || at[k] - slack > max
        });
        if outside {
            continue;
        }
        let o = [orient(a, b, p), orient(b, c, p), orient(c, a, p)];
        if o.iter().any(|&s| s < 0) {
            continue;
        }
        let zeros = o.iter().filter(|&&s| s == 0).count();
        match zeros {
            0 => {
                t.kill(i);
                t.add([a, b, p]);
                t.add([b, c, p]);
                t.add([c, a, p]);
                return Ok(());
            }
            1 => {
                let k = o.iter().position(|&s| s == 0).unwrap_or(0);
                let tri = t.pts[i];
                let (u, v, w) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
                let other = t.edge.get(&(v, u)).copied();
                t.kill(i);
                t.add([u, p, w]);
                t.add([p, v, w]);
                if let Some(j) = other {
                    let oj = t.pts[j];
                    let m = (0..3).find(|&m| oj[m] == v).unwrap_or(0);
                    let x = oj[(m + 2) % 3];
                    t.kill(j);
                    t.add([v, p, x]);
                    t.add([p, u, x]);
                }
                return Ok(());
            }
            _ => return Ok(()), // a vertex already
        }
    }
    Err(CutError)
}

/// Whether `w`, on the line through `p` and `q`, lies strictly between them.
fn strictly_between(pts: &Points, p: Pid, q: Pid, w: Pid) -> bool {
    for k in 0..3 {
        let s = coord_cmp_at(pts, k, p, q);
        if s != 0 {
            return coord_cmp_at(pts, k, p, w) == s && coord_cmp_at(pts, k, w, q) == s;
        }
    }
    false
}

#[allow(clippy::too_many_arguments)]
fn insert_segment(
    pts: &Points,
    t: &mut Tri2,
    orient: &impl Fn(Pid, Pid, Pid) -> i8,
    verts: &[Pid],
    p: Pid,
    q: Pid,
    traced: &mut Vec<EdgeKey>,
    depth: usize,
) -> Result<(), CutError> {
    if p == q {
        return Ok(());
    }
    if depth > verts.len() + 2 {
        return Err(CutError);
    }
    // Cut the trace at any vertex on it.
    for &w in verts {
        // The cheap test first: most points are not within the segment's span.
        if w != p && w != q && strictly_between(pts, p, q, w) && orient(p, q, w) == 0 {
            insert_segment(pts, t, orient, verts, p, w, traced, depth + 1)?;
            return insert_segment(pts, t, orient, verts, w, q, traced, depth + 1);
        }
    }
    if t.edge.contains_key(&(p, q)) || t.edge.contains_key(&(q, p)) {
        traced.push(edge_key(p, q));
        return Ok(());
    }
    // Sloan's recovery: a queue of the edges crossing p–q; a convex quadrilateral's
    // diagonal is flipped, and the new diagonal goes back in the queue while it still
    // crosses; a non-convex one waits at the back.
    let crosses = |u: Pid, v: Pid| {
        u != p
            && u != q
            && v != p
            && v != q
            && orient(p, q, u) * orient(p, q, v) < 0
            && orient(u, v, p) * orient(u, v, q) < 0
    };
    let mut queue: std::collections::VecDeque<(Pid, Pid)> = {
        let mut e: Vec<(Pid, Pid)> = t
            .edge
            .iter()
            .filter(|((u, v), i)| u < v && t.alive[**i])
            .map(|(k, _)| *k)
            .filter(|&(u, v)| crosses(u, v))
            .collect();
        e.sort_unstable();
        e.into()
    };
    let limit = 8 * (queue.len() + 1) * (queue.len() + 1) + 64;
    let mut steps = 0usize;
    while let Some((u, v)) = queue.pop_front() {
        steps += 1;
        if steps > limit {
            return Err(CutError);
        }
        let (Some(&i), Some(&j)) = (t.edge.get(&(u, v)), t.edge.get(&(v, u))) else {
            continue; // flipped away already
        };
        if traced.contains(&edge_key(u, v)) {
            return Err(CutError); // two traces cross
        }
        let x = third(t.pts[i], u, v);
        let y = third(t.pts[j], v, u);
        // Convex: the other diagonal crosses this one.
        if orient(x, y, u) * orient(x, y, v) >= 0 {
            queue.push_back((u, v));
            continue;
        }
        t.kill(i);
        t.kill(j);
        // (u, v, x) and (v, u, y) become (u, y, x) and (v, x, y), counter-clockwise.
        t.add([u, y, x]);
        t.add([v, x, y]);
        if crosses(x, y) {
            queue.push_back((x, y));
        }
    }
    if t.edge.contains_key(&(p, q)) || t.edge.contains_key(&(q, p)) {
        traced.push(edge_key(p, q));
        Ok(())
    } else {
        Err(CutError)
    }
}

/// The vertex of triangle `t` other than the ends of its edge `u → v`.
fn third(t: [Pid; 3], u: Pid, v: Pid) -> Pid {
    t.into_iter().find(|&x| x != u && x != v).unwrap_or(u)
}

/// The sign of `q_k − p_k` for two definitions (points made or about to be made).
pub(crate) fn coord_cmp(pts: &Points, k: usize, p: Def, q: Def) -> i8 {
    if p == q {
        return 0;
    }
    if let Some(s) = known_cmp(pts, k, p, q) {
        return s;
    }
    let (hp, hq) = (pts.homog::<Fx>(p), pts.homog::<Fx>(q));
    let w = |h: &[Fx; 4], d: Def| h[3].sign().unwrap_or_else(|| pts.w_sign_def(d));
    homog_cmp(pts, k, (p, &hp), (q, &hq), w(&hp, p) * w(&hq, q))
}

/// The sign of `q_k − p_k` for two points of the table: their approximations' bounds
/// first, then the filter kept from when they were made, then exact arithmetic.
pub(crate) fn coord_cmp_at(pts: &Points, k: usize, p: Pid, q: Pid) -> i8 {
    if p == q {
        return 0;
    }
    let (ap, aq) = (pts.approx[p as usize][k], pts.approx[q as usize][k]);
    let gap = pts.slack[p as usize] + pts.slack[q as usize];
    if aq - ap > gap {
        return 1;
    }
    if ap - aq > gap {
        return -1;
    }
    let (dp, dq) = (pts.defs[p as usize], pts.defs[q as usize]);
    if let Some(s) = known_cmp(pts, k, dp, dq) {
        return s;
    }
    let (hp, hq) = (pts.homog_of::<Fx>(p), pts.homog_of::<Fx>(q));
    homog_cmp(pts, k, (dp, &hp), (dq, &hq), pts.w_sign(p) * pts.w_sign(q))
}

/// The comparison of two coordinates that both definitions fix.
fn known_cmp(pts: &Points, k: usize, p: Def, q: Def) -> Option<i8> {
    let (a, b) = (pts.known(p, k)?, pts.known(q, k)?);
    Some(b.partial_cmp(&a).map_or(0, |o| o as i8))
}

/// The comparison through homogeneous coordinates (`hp`, `hq` in the filter; `w` the
/// sign of `W_p W_q`), exactly when the filter cannot decide.
fn homog_cmp(
    pts: &Points,
    k: usize,
    (p, hp): (Def, &[Fx; 4]),
    (q, hq): (Def, &[Fx; 4]),
    w: i8,
) -> i8 {
    let diff = hq[k] * hp[3] - hp[k] * hq[3];
    diff.sign()
        .unwrap_or_else(|| CoordDiff { pts, k, p, q }.sign())
        * w
}

/// `q_k W_p − p_k W_q`.
struct CoordDiff<'a> {
    pts: &'a Points,
    k: usize,
    p: Def,
    q: Def,
}

impl Poly for CoordDiff<'_> {
    fn eval<R: Ring>(&self) -> R {
        let hp = self.pts.homog::<R>(self.p);
        let hq = self.pts.homog::<R>(self.q);
        hq[self.k].clone() * hp[3].clone() - hp[self.k].clone() * hq[3].clone()
    }
}
