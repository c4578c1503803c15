//! The kept pieces sewn into shells of polygons.
//!
//! 1. Each piece's edges are paired with the opposite edges of other pieces. Where more
//!    than two pieces meet at an edge (bodies that touch along it), pieces of one
//!    operand pair first, so that touching solids stay separate shells.
//! 2. A vertex around which the pieces form several fans (solids touching at a point)
//!    becomes one vertex per fan.
//! 3. Pieces joined by edges form shells.
//! 4. Within a shell, the pieces of one input face are merged into polygons: a region
//!    grows across the edges it shares with pieces of the same face for as long as it
//!    stays a disc (it never swallows a hole or pinches at a vertex).
//! 5. Vertices where only two faces meet (they lie on the line the faces share) are
//!    dropped.
//! 6. Loci are rounded to the nearest f64, once.

use std::collections::{BTreeMap, HashMap};

use glam::DVec3;

use super::point::{Pid, Points};
use super::{BooleanError, Shell, Source, round};

/// A kept piece: its points (counter-clockwise seen from outside the result) and the
/// input face it is part of.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Kept {
    pub tri: [Pid; 3],
    pub source: Source,
}

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        parent[x as usize] = parent[parent[x as usize] as usize];
        x = parent[x as usize];
    }
    x
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
    let mut twin = vec![NONE; nh];
    for (&(p, q), outs) in &by_edge {
        if p > q {
            continue;
        }
        let ins = by_edge.get(&(q, p)).ok_or_else(open)?;
        if ins.len() != outs.len() {
            return Err(open());
        }
        if outs.len() == 1 {
            twin[outs[0] as usize] = ins[0];
            twin[ins[0] as usize] = outs[0];
            continue;
        }
        let mut ins_left: Vec<u32> = ins.clone();
        let mut outs_left: Vec<u32> = Vec::new();
        for &o in outs {
            let op = kept[o as usize / 3].source.operand;
            if let Some(k) = ins_left
                .iter()
                .position(|&i| kept[i as usize / 3].source.operand == op)
            {
                let i = ins_left.remove(k);
                twin[o as usize] = i;
                twin[i as usize] = o;
            } else {
                outs_left.push(o);
            }
        }
        for (o, i) in outs_left.into_iter().zip(ins_left) {
            twin[o as usize] = i;
            twin[i as usize] = o;
        }
    }
    let next = |h: usize| h - h % 3 + (h % 3 + 1) % 3;
    let prev = |h: usize| h - h % 3 + (h % 3 + 2) % 3;
    // 2. One vertex per fan: corner h (the origin of half-edge h) gets a vertex index.
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
    let mut parent: Vec<u32> = (0..nt as u32).collect();
    for (h, &t) in twin.iter().enumerate() {
        let (a, b) = (find(&mut parent, (h / 3) as u32), find(&mut parent, t / 3));
        if a != b {
            parent[a.max(b) as usize] = a.min(b);
        }
    }
    let mut shells_of: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for t in 0..nt as u32 {
        let r = find(&mut parent, t);
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
        let shell = finish(pts, &locus, &pos, faces);
        if !round::thin(&shell.positions, &shell.faces, eps) {
            shells.push(shell);
        }
    }
    shells.sort_by_key(|s: &Shell| std::cmp::Reverse(s.faces.len()));
    Ok(shells)
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
    succ: HashMap<usize, usize>,
    pred: HashMap<usize, usize>,
    on_rim: HashMap<u32, u32>,
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
    let mut faces_at: HashMap<u32, Vec<usize>> = HashMap::new();
    for (fi, (ring, _)) in faces.iter().enumerate() {
        for &v in ring {
            faces_at.entry(v).or_default().push(fi);
        }
    }
    let mut index: HashMap<u32, u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut out_faces = Vec::with_capacity(faces.len());
    let mut sources = Vec::with_capacity(faces.len());
    // A vertex is dropped only if both its faces keep three vertices or more.
    let mut keep_count: Vec<usize> = faces.iter().map(|(r, _)| r.len()).collect();
    let mut dropped: HashMap<u32, bool> = HashMap::new();
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
    let mut parent: Vec<u32> = (0..positions.len() as u32).collect();
    for f in &faces {
        for k in 0..f.len() {
            let (a, b) = (f[k], f[(k + 1) % f.len()]);
            if positions[a as usize] == positions[b as usize] {
                let (x, y) = (find(&mut parent, a), find(&mut parent, b));
                if x != y {
                    parent[x.max(y) as usize] = x.min(y);
                }
            }
        }
    }
    let mut index: HashMap<u32, u32> = HashMap::new();
    let mut out_pos = Vec::new();
    let mut out_faces = Vec::new();
    let mut out_sources = Vec::new();
    for (f, src) in faces.into_iter().zip(sources) {
        let mut ring: Vec<u32> = Vec::with_capacity(f.len());
        for v in f {
            let r = find(&mut parent, v);
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
