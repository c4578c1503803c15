//! The kept pieces sewn into shells of polygons.
//!
//! 1. Each piece's edges are paired with the opposite edges of other pieces. Where more
//!    than two pieces meet at an edge (bodies that touch along it), the pieces are
//!    ordered about the edge exactly and each is paired with its neighbour across a
//!    wedge of the solid, so that touching solids stay apart; where that would leave
//!    two edges between the same two vertices (the solid wraps round the edge and
//!    meets itself there), with its neighbour across a wedge outside it.
//! 2. A vertex around which the pieces form several fans (solids touching at a point)
//!    becomes one vertex per fan.
//! 3. Loci are rounded to the nearest f64, once, and the edges and triangles narrower
//!    than the rounding can keep are cleared ([`round`]).
//! 4. Pieces joined by edges form shells.
//! 5. Within a shell, the pieces of one input face are merged into polygons: a region
//!    grows across the edges it shares with pieces of the same face for as long as it
//!    stays a disc (it never swallows a hole or pinches at a vertex); a face around one
//!    hole is then cut again through its own corners ([`holes`]). Vertices where
//!    only two faces meet (they lie on the line the faces share) are dropped; shells
//!    thinner than the rounding are dropped.

use std::collections::BTreeMap;

use super::Map;

use glam::DVec3;

use super::point::{Pid, Points};
use super::sets::Sets;
use super::{BooleanError, Shell, Source, holes, round};

/// A kept piece: its points (counter-clockwise seen from outside the result) and the
/// input face it is part of.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Kept {
    pub tri: [Pid; 3],
    pub source: Source,
}

const NONE: u32 = u32::MAX;

/// Sews `kept` into shells, largest first.
pub(crate) fn assemble(pts: &Points, kept: &[Kept]) -> Result<Vec<Shell>, BooleanError> {
    let open = || BooleanError::Unresolved {
        what: "the kept pieces do not close",
    };
    let nh = kept.len() * 3;
    let from = |h: usize| kept[h / 3].tri[h % 3];
    let to = |h: usize| kept[h / 3].tri[(h % 3 + 1) % 3];
    // 1. Twins.
    let mut by_edge: BTreeMap<(Pid, Pid), Vec<u32>> = BTreeMap::new();
    for h in 0..nh {
        by_edge.entry((from(h), to(h))).or_default().push(h as u32);
    }
    let next = round::next;
    let prev = round::prev;
    let mut twin = vec![NONE; nh];
    let link = |twin: &mut Vec<u32>, pairs: &[(u32, u32)]| {
        for &(o, i) in pairs {
            twin[o as usize] = i;
            twin[i as usize] = o;
        }
    };
    // Edges where several sheets meet: the pairing into the solid's wedges, and the
    // other one (into the wedges outside), used where the first would give two edges
    // between the same two vertices.
    let mut sheets: Vec<Pairings> = Vec::new();
    for (&(p, q), outs) in &by_edge {
        if p > q {
            continue;
        }
        let ins = by_edge.get(&(q, p)).ok_or_else(open)?;
        if ins.len() != outs.len() {
            return Err(open());
        }
        if outs.len() == 1 {
            link(&mut twin, &[(outs[0], ins[0])]);
            continue;
        }
        let third = |h: u32| from(prev(h as usize));
        match radial(pts, p, q, outs, ins, third) {
            Some((inside, outside)) => {
                link(&mut twin, &inside);
                sheets.push((inside, outside));
            }
            None => link(&mut twin, &by_operand(kept, outs, ins)),
        }
    }
    // 2. One vertex per fan: corner h (the origin of half-edge h) gets a vertex index.
    let (mut vertex_of, mut locus) = fans(&twin, from, prev);
    let doubled: Vec<usize> = (0..sheets.len())
        .filter(|&k| {
            let ends: Vec<(u32, u32)> = sheets[k]
                .0
                .iter()
                .map(|&(o, _)| (vertex_of[o as usize], vertex_of[next(o as usize)]))
                .collect();
            (1..ends.len()).any(|i| ends[..i].contains(&ends[i]))
        })
        .collect();
    if !doubled.is_empty() {
        for k in doubled {
            link(&mut twin, &sheets[k].1);
        }
        (vertex_of, locus) = fans(&twin, from, prev);
    }
    // 3. Rounding, and the features narrower than it cleared.
    let pos: Vec<DVec3> = locus.iter().map(|&p| pts.rounded(p)).collect();
    let eps = round::eps_for(&pos);
    let mut tris = round::Tris {
        corner: vertex_of,
        twin,
        source: kept.iter().map(|k| k.source).collect(),
        alive: vec![true; kept.len()],
    };
    tris.clean(&pos, eps);
    let (vertex_of, twin, source) = compact(tris);
    // 4. Shells.
    let nt = source.len();
    let mut sets = Sets::new(nt);
    for (h, &t) in twin.iter().enumerate() {
        sets.join((h / 3) as u32, t / 3);
    }
    let mut shells_of: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for t in 0..nt as u32 {
        let r = sets.find(t);
        shells_of.entry(r).or_default().push(t);
    }
    // 5. Faces, per shell; shells thinner than the rounding dropped.
    let mut region = vec![NONE; nt];
    let mut shells = Vec::with_capacity(shells_of.len());
    for tris in shells_of.values() {
        let mut faces: Vec<(Vec<u32>, Source)> = Vec::new();
        for &t in tris {
            if region[t as usize] != NONE {
                continue;
            }
            let id = faces.len() as u32;
            let ring = grow(&source, &twin, &vertex_of, &mut region, t, id, next);
            faces.push((ring, source[t as usize]));
        }
        let faces = holes::recut(pts, &locus, faces);
        let shell = finish(pts, &locus, &pos, faces);
        if !round::thin(&shell.positions, &shell.faces, eps) {
            shells.push(shell);
        }
    }
    shells.sort_by_key(|s: &Shell| std::cmp::Reverse(s.faces.len()));
    Ok(shells)
}

/// Pairs of half-edges (from `p` to `q`, from `q` to `p`) made twins.
type Pairing = Vec<(u32, u32)>;

/// The two pairings at an edge where several sheets meet: into the solid's wedges, and
/// into the wedges outside it.
type Pairings = (Pairing, Pairing);

/// Pairs the half-edges `outs` (from `p` to `q`) with `ins` (from `q` to `p`) of one
/// operand first, then the rest in order.
fn by_operand(kept: &[Kept], outs: &[u32], ins: &[u32]) -> Pairing {
    let mut ins_left: Vec<u32> = ins.to_vec();
    let mut outs_left: Vec<u32> = Vec::new();
    let mut pairs = Vec::with_capacity(outs.len());
    for &o in outs {
        let op = kept[o as usize / 3].source.operand;
        if let Some(k) = ins_left
            .iter()
            .position(|&i| kept[i as usize / 3].source.operand == op)
        {
            pairs.push((o, ins_left.remove(k)));
        } else {
            outs_left.push(o);
        }
    }
    pairs.extend(outs_left.into_iter().zip(ins_left));
    pairs
}

/// The two pairings of the half-edges `outs` (from `p` to `q`) with `ins` (from `q` to
/// `p`) that keep the surface from crossing itself at the edge, found by ordering the
/// pieces about the edge exactly (`third(h)` is the corner of `h`'s piece off the
/// edge): each out with the piece met first turning from it into the solid, and each
/// out with the piece met first turning from it out of the solid. `None` if the pieces
/// do not alternate out, in, out, … about the edge (two coincide).
fn radial(
    pts: &Points,
    p: Pid,
    q: Pid,
    outs: &[u32],
    ins: &[u32],
    third: impl Fn(u32) -> Pid,
) -> Option<Pairings> {
    let mut all: Vec<(u32, bool)> = outs.iter().map(|&h| (h, true)).collect();
    all.extend(ins.iter().map(|&h| (h, false)));
    let r = third(all[0].0);
    let axis = super::split::dominant_axis(pts, [p, q, r]);
    let r_side = pts.orient2d(axis, [p, q, r]);
    // Angle θ about p → q (right-handed), from r at θ = 0: 0 for θ = 0, 1 for θ in
    // (0, π), 2 for θ = π, 3 for θ in (π, 2π).
    let half = |c: Pid| match pts.side_any([p, q, r], c) {
        1 => 1,
        -1 => 3,
        _ if pts.orient2d(axis, [p, q, c]) == r_side => 0,
        _ => 2,
    };
    let mut keyed: Vec<(u8, u32, bool)> = all
        .iter()
        .map(|&(h, out)| (half(third(h)), h, out))
        .collect();
    let mut tie = false;
    keyed.sort_by(|x, y| {
        x.0.cmp(&y.0).then_with(|| {
            if x.1 == y.1 {
                return std::cmp::Ordering::Equal;
            }
            // Within one half, y is further round than x if it is in front of the
            // plane through the edge and x.
            match pts.side_any([p, q, third(x.1)], third(y.1)) {
                1 => std::cmp::Ordering::Less,
                -1 => std::cmp::Ordering::Greater,
                _ => {
                    tie = true;
                    x.1.cmp(&y.1)
                }
            }
        })
    });
    let n = keyed.len();
    if tie || (0..n).any(|k| keyed[k].2 == keyed[(k + 1) % n].2) {
        return None;
    }
    // A piece from p to q has the solid just before it in θ, one from q to p just
    // after it.
    let mut inside = Vec::with_capacity(n / 2);
    let mut outside = Vec::with_capacity(n / 2);
    for k in 0..n {
        if keyed[k].2 {
            inside.push((keyed[k].1, keyed[(k + n - 1) % n].1));
            outside.push((keyed[k].1, keyed[(k + 1) % n].1));
        }
    }
    Some((inside, outside))
}

/// One vertex per fan of pieces about a point: the vertex of each corner (the origin of
/// each half-edge) and the locus of each vertex.
fn fans(
    twin: &[u32],
    from: impl Fn(usize) -> Pid,
    prev: impl Fn(usize) -> usize,
) -> (Vec<u32>, Vec<Pid>) {
    let nh = twin.len();
    let mut vertex_of = vec![NONE; nh];
    let mut locus: Vec<Pid> = Vec::new();
    for h0 in 0..nh {
        if vertex_of[h0] != NONE {
            continue;
        }
        let v = locus.len() as u32;
        locus.push(from(h0));
        let mut h = h0;
        loop {
            vertex_of[h] = v;
            // The next outgoing half-edge about the same point.
            h = twin[prev(h)] as usize;
            if h == h0 || vertex_of[h] != NONE {
                break;
            }
        }
    }
    (vertex_of, locus)
}

/// Grows the region of piece `seed` across edges shared with pieces of the same input
/// face, keeping it a disc; returns its boundary as vertex indices, counter-clockwise.
fn grow(
    sources: &[Source],
    twin: &[u32],
    vertex_of: &[u32],
    region: &mut [u32],
    seed: u32,
    id: u32,
    next: impl Fn(usize) -> usize,
) -> Vec<u32> {
    let source = sources[seed as usize];
    region[seed as usize] = id;
    let s = seed as usize * 3;
    let mut rim = Rim::default();
    for k in 0..3 {
        rim.link(s + k, s + (k + 1) % 3);
        *rim.on_rim.entry(vertex_of[s + k]).or_default() += 1;
    }
    let mut start = s;
    loop {
        let mut grew = false;
        let mut edges: Vec<usize> = rim.succ.keys().copied().collect();
        edges.sort_unstable();
        for h in edges {
            if !rim.succ.contains_key(&h) {
                continue;
            }
            let g = twin[h] as usize;
            let u = g / 3;
            if region[u] != NONE || sources[u] != source {
                continue;
            }
            let g1 = next(g);
            let g2 = next(g1);
            let (ph, nh) = (rim.pred[&h], rim.succ[&h]);
            if ph == twin[g1] as usize && nh == twin[g2] as usize {
                continue;
            }
            if ph == twin[g1] as usize {
                // The piece fills the notch before h: ph and h leave, g2 joins.
                rim.replace_pair(vertex_of, ph, h, g2);
            } else if nh == twin[g2] as usize {
                // The piece fills the notch after h: h and nh leave, g1 joins.
                rim.replace_pair(vertex_of, h, nh, g1);
            } else {
                let w = vertex_of[g2];
                if rim.on_rim.get(&w).copied().unwrap_or(0) > 0 {
                    continue; // it would pinch the region at w
                }
                rim.succ.remove(&h);
                rim.pred.remove(&h);
                rim.link(ph, g1);
                rim.link(g1, g2);
                rim.link(g2, nh);
                *rim.on_rim.entry(w).or_default() += 1;
            }
            region[u] = id;
            grew = true;
        }
        if !grew {
            break;
        }
    }
    let succ = rim.succ;
    if !succ.contains_key(&start) {
        start = *succ.keys().min().expect("a region has a rim");
    }
    let mut ring = Vec::with_capacity(succ.len());
    let mut h = start;
    loop {
        ring.push(vertex_of[h]);
        h = succ[&h];
        if h == start || ring.len() > succ.len() {
            break;
        }
    }
    ring
}

/// A growing region's boundary: each rim half-edge's successor and predecessor, and how
/// often each vertex is on the rim.
#[derive(Default)]
struct Rim {
    succ: Map<usize, usize>,
    pred: Map<usize, usize>,
    on_rim: Map<u32, u32>,
}

impl Rim {
    /// Makes `b` follow `a` along the rim.
    fn link(&mut self, a: usize, b: usize) {
        self.succ.insert(a, b);
        self.pred.insert(b, a);
    }

    /// Replaces consecutive rim half-edges `a` then `b` by the one half-edge `g` (a
    /// piece filling the notch between them).
    fn replace_pair(&mut self, vertex_of: &[u32], a: usize, b: usize, g: usize) {
        let (before, after) = (self.pred[&a], self.succ[&b]);
        for x in [a, b] {
            self.succ.remove(&x);
            self.pred.remove(&x);
            *self.on_rim.get_mut(&vertex_of[x]).expect("on the rim") -= 1;
        }
        *self.on_rim.entry(vertex_of[g]).or_default() += 1;
        self.link(before, g);
        self.link(g, after);
    }
}

/// Whether vertex `v` of `ring` lies on the segment between its neighbours there
/// (exactly: collinear in every coordinate projection).
fn straight(pts: &Points, locus: &[Pid], ring: &[u32], v: u32) -> bool {
    let n = ring.len();
    let Some(i) = ring.iter().position(|&x| x == v) else {
        return false;
    };
    let (u, w) = (ring[(i + n - 1) % n], ring[(i + 1) % n]);
    let p = [u, v, w].map(|x| locus[x as usize]);
    (0..3).all(|axis| pts.orient2d(axis, p) == 0)
}

/// Drops vertices where only two faces meet and the boundary runs straight through, numbers the shell's vertices and rounds
/// their loci.
fn finish(pts: &Points, locus: &[Pid], pos: &[DVec3], faces: Vec<(Vec<u32>, Source)>) -> Shell {
    let mut faces_at: Map<u32, Vec<usize>> = Map::default();
    for (fi, (ring, _)) in faces.iter().enumerate() {
        for &v in ring {
            faces_at.entry(v).or_default().push(fi);
        }
    }
    let mut index: Map<u32, u32> = Map::default();
    let mut positions = Vec::new();
    let mut out_faces = Vec::with_capacity(faces.len());
    let mut sources = Vec::with_capacity(faces.len());
    // A vertex is dropped only if both its faces keep three vertices or more.
    let mut keep_count: Vec<usize> = faces.iter().map(|(r, _)| r.len()).collect();
    let mut dropped: Map<u32, bool> = Map::default();
    let mut candidates: Vec<(u32, usize, usize)> = faces_at
        .iter()
        .filter(|(_, f)| f.len() == 2 && f[0] != f[1])
        .map(|(&v, f)| (v, f[0], f[1]))
        .collect();
    candidates.sort_unstable();
    for (v, fi, fj) in candidates {
        let ok = keep_count[fi] > 3 && keep_count[fj] > 3 && straight(pts, locus, &faces[fi].0, v);
        dropped.insert(v, ok);
        if ok {
            keep_count[fi] -= 1;
            keep_count[fj] -= 1;
        }
    }
    for (ring, source) in faces {
        let mut f = Vec::with_capacity(ring.len());
        for v in ring {
            if dropped.get(&v).copied().unwrap_or(false) {
                continue;
            }
            let i = *index.entry(v).or_insert_with(|| {
                positions.push(pos[v as usize]);
                (positions.len() - 1) as u32
            });
            f.push(i);
        }
        out_faces.push(f);
        sources.push(source);
    }
    let (positions, faces, sources) = collapse(positions, out_faces, sources);
    Shell {
        positions,
        faces,
        sources,
        cavity_of: None,
    }
}

/// The surviving triangles of `tris`, renumbered: each corner's vertex, each half-edge's
/// twin and each triangle's source.
fn compact(tris: round::Tris) -> (Vec<u32>, Vec<u32>, Vec<Source>) {
    let mut new_of = vec![NONE; tris.alive.len()];
    let mut n = 0u32;
    for (t, &alive) in tris.alive.iter().enumerate() {
        if alive {
            new_of[t] = n;
            n += 1;
        }
    }
    let mut corner = Vec::with_capacity(3 * n as usize);
    let mut twin = Vec::with_capacity(3 * n as usize);
    let mut source = Vec::with_capacity(n as usize);
    for (t, &alive) in tris.alive.iter().enumerate() {
        if !alive {
            continue;
        }
        source.push(tris.source[t]);
        for h in 3 * t..3 * t + 3 {
            corner.push(tris.corner[h]);
            let g = tris.twin[h] as usize;
            twin.push(3 * new_of[g / 3] + (g % 3) as u32);
        }
    }
    (corner, twin, source)
}

/// Merges the ends of every edge whose two distinct exact ends round to one locus, and
/// drops the faces that leave fewer than three corners (slivers narrower than the f64
/// grid, which rounding flattens into an edge).
fn collapse(
    positions: Vec<glam::DVec3>,
    faces: Vec<Vec<u32>>,
    sources: Vec<Source>,
) -> (Vec<glam::DVec3>, Vec<Vec<u32>>, Vec<Source>) {
    let short = faces.iter().any(|f| {
        (0..f.len()).any(|k| positions[f[k] as usize] == positions[f[(k + 1) % f.len()] as usize])
    });
    if !short {
        return (positions, faces, sources);
    }
    let mut sets = Sets::new(positions.len());
    for f in &faces {
        for k in 0..f.len() {
            let (a, b) = (f[k], f[(k + 1) % f.len()]);
            if positions[a as usize] == positions[b as usize] {
                sets.join(a, b);
            }
        }
    }
    let mut index: Map<u32, u32> = Map::default();
    let mut out_pos = Vec::new();
    let mut out_faces = Vec::new();
    let mut out_sources = Vec::new();
    for (f, src) in faces.into_iter().zip(sources) {
        let mut ring: Vec<u32> = Vec::with_capacity(f.len());
        for v in f {
            let r = sets.find(v);
            if ring.last() != Some(&r) {
                ring.push(r);
            }
        }
        while ring.len() > 1 && ring.first() == ring.last() {
            ring.pop();
        }
        if ring.len() < 3 {
            continue;
        }
        let ring = ring
            .into_iter()
            .map(|r| {
                *index.entry(r).or_insert_with(|| {
                    out_pos.push(positions[r as usize]);
                    (out_pos.len() - 1) as u32
                })
            })
            .collect();
        out_faces.push(ring);
        out_sources.push(src);
    }
    (out_pos, out_faces, out_sources)
}
