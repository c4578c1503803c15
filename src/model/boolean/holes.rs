//! A face with a hole, cut into two polygons through its own corners.
//!
//! Where the merge of one input face's pieces stopped although their union is a disc
//! (its growth pinched on the way), the union becomes one polygon.
//!
//! A winged-edge face is one ring, so a piece of an input face that surrounds a hole
//! (a box face a cutter went through) must be two polygons. Merging the pieces leaves
//! the cut wherever the merge stopped, which may end at a point where a trace crossed
//! a diagonal of a triangulation: such a point would stay a corner of three faces, a
//! locus rounded off the input's grid. Here the pieces of such a face are merged whole
//! and cut again by two chords, each from a corner of the hole to a corner of the
//! outer boundary, inside the face and crossing nothing.
//!
//! Holes are taken one at a time: two chords from a hole's corners to corners of the
//! outer ring cut the face in two, and each part keeps the holes it holds. A group
//! whose boundary pinches at a vertex, or one where no hole can be joined to the outer
//! ring by two clear chords, keeps the cut the merge made.

use std::collections::BTreeMap;

use super::{Map, Set};

use super::Source;
use super::point::{Pid, Points};
use super::sets::Sets;

/// The most corners a face may have to be cut again (the chord search is quadratic
/// in them, each chord tested against every boundary edge).
const MAX_CORNERS: usize = 256;

/// Cuts again, through corners, every face of `faces` (rings of vertex indices whose
/// loci are `locus`) that surrounds holes and was split by the merge.
pub(crate) fn recut(
    pts: &Points,
    locus: &[Pid],
    faces: Vec<(Vec<u32>, Source)>,
) -> Vec<(Vec<u32>, Source)> {
    // Faces of one source that share an edge form a group.
    let mut by_source: BTreeMap<SourceKey, Vec<usize>> = BTreeMap::new();
    for (i, (_, s)) in faces.iter().enumerate() {
        by_source.entry(key(*s)).or_default().push(i);
    }
    // Groups of two faces or more: the merge left those in parts.
    let groups: Vec<Vec<usize>> = by_source
        .values()
        .filter(|members| members.len() > 1)
        .flat_map(|members| adjacent_groups(&faces, members))
        .filter(|group| group.len() > 1)
        .collect();
    if groups.is_empty() {
        return faces;
    }
    // Every edge of the shell: a chord may not join two vertices an edge joins already.
    let mut edges: Set<(u32, u32)> = Set::default();
    for (r, _) in &faces {
        for k in 0..r.len() {
            let (u, v) = (r[k], r[(k + 1) % r.len()]);
            edges.insert((u.min(v), u.max(v)));
        }
    }
    let mut replaced: Map<usize, Option<Vec<Vec<u32>>>> = Map::default();
    for group in groups {
        let rings: Vec<&Vec<u32>> = group.iter().map(|&i| &faces[i].0).collect();
        if let Some(new) = cut_through_corners(pts, locus, &rings, &edges) {
            replaced.insert(group[0], Some(new));
            for &i in &group[1..] {
                replaced.insert(i, None);
            }
        }
    }
    if replaced.is_empty() {
        return faces;
    }
    let mut out = Vec::with_capacity(faces.len());
    for (i, (ring, source)) in faces.into_iter().enumerate() {
        match replaced.remove(&i) {
            None => out.push((ring, source)),
            Some(None) => {}
            Some(Some(new)) => out.extend(new.into_iter().map(|r| (r, source))),
        }
    }
    out
}

type SourceKey = (u8, u64);

fn key(s: Source) -> SourceKey {
    (s.operand as u8, s.face.0)
}

/// The members that share edges, in groups (each sorted).
fn adjacent_groups(faces: &[(Vec<u32>, Source)], members: &[usize]) -> Vec<Vec<usize>> {
    // Member k of `members` is set k.
    let mut owner: Map<(u32, u32), u32> = Map::default();
    for (k, &i) in members.iter().enumerate() {
        let r = &faces[i].0;
        for e in 0..r.len() {
            owner.insert((r[e], r[(e + 1) % r.len()]), k as u32);
        }
    }
    let mut sets = Sets::new(members.len());
    for (k, &i) in members.iter().enumerate() {
        let r = &faces[i].0;
        for e in 0..r.len() {
            if let Some(&j) = owner.get(&(r[(e + 1) % r.len()], r[e])) {
                sets.join(k as u32, j);
            }
        }
    }
    let mut groups: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
    for (k, &i) in members.iter().enumerate() {
        let r = sets.find(k as u32);
        groups.entry(r).or_default().push(i);
    }
    groups.into_values().collect()
}

/// The boundary loops of the union of `rings`: the edges no other ring runs back
/// along, chained. `None` if the boundary pinches (a vertex starts two of them).
fn loops(rings: &[&Vec<u32>]) -> Option<Vec<Vec<u32>>> {
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for r in rings {
        for k in 0..r.len() {
            edges.push((r[k], r[(k + 1) % r.len()]));
        }
    }
    let all: Set<(u32, u32)> = edges.iter().copied().collect();
    let mut from: BTreeMap<u32, u32> = BTreeMap::new();
    for &(u, v) in &edges {
        if !all.contains(&(v, u)) && from.insert(u, v).is_some() {
            return None;
        }
    }
    let mut out = Vec::new();
    while let Some((&start, _)) = from.iter().next() {
        let mut ring = vec![start];
        let mut v = from.remove(&start)?;
        while v != start {
            ring.push(v);
            v = from.remove(&v)?;
        }
        out.push(ring);
    }
    Some(out)
}

/// The union of `rings`: one polygon if it is a disc; for a face with holes, polygons
/// joined by chords between corners; `None` if its boundary pinches or chords are not
/// found.
fn cut_through_corners(
    pts: &Points,
    locus: &[Pid],
    rings: &[&Vec<u32>],
    edges: &Set<(u32, u32)>,
) -> Option<Vec<Vec<u32>>> {
    let loops = loops(rings)?;
    if loops.is_empty() {
        return None; // the faces close on themselves: nothing to cut
    }
    if loops.len() == 1 {
        // A disc the merge left in parts (its growth pinched on the way): one polygon.
        return loops.into_iter().next().map(|l| vec![l]);
    }
    if loops.iter().map(Vec::len).sum::<usize>() > MAX_CORNERS {
        return None;
    }
    let at = |v: u32| locus[v as usize];
    // Project along the axis where the outer loop's area is largest; orient with the
    // outer loop counter-clockwise.
    let area = |ring: &[u32], axis: usize| {
        let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut a = 0.0;
        for k in 0..ring.len() {
            let p = pts.approx[at(ring[k]) as usize];
            let q = pts.approx[at(ring[(k + 1) % ring.len()]) as usize];
            a += p[i] * q[j] - p[j] * q[i];
        }
        a
    };
    let biggest = (0..loops.len())
        .max_by(|&x, &y| {
            let m = |r: usize| (0..3).map(|k| area(&loops[r], k).abs()).fold(0.0, f64::max);
            m(x).total_cmp(&m(y))
        })
        .unwrap_or(0);
    let axis = (0..3)
        .max_by(|&x, &y| {
            area(&loops[biggest], x)
                .abs()
                .total_cmp(&area(&loops[biggest], y).abs())
        })
        .unwrap_or(2);
    let outer_area = area(&loops[biggest], axis);
    if outer_area == 0.0 {
        return None;
    }
    let sense: i8 = if outer_area > 0.0 { 1 } else { -1 };
    let mut holes = Vec::new();
    for (k, l) in loops.iter().enumerate() {
        if k != biggest {
            // Every other loop must turn the other way: a hole.
            if area(l, axis) * outer_area >= 0.0 {
                return None;
            }
            holes.push(l.clone());
        }
    }
    let geo = Plane {
        pts,
        locus,
        axis: axis as u8,
        sense,
        edges,
    };
    let mut out = Vec::new();
    geo.split(loops[biggest].clone(), holes, &mut out, 0)?;
    Some(out)
}

/// Exact orientation in the projection of one face's plane.
struct Plane<'a> {
    pts: &'a Points,
    locus: &'a [Pid],
    axis: u8,
    sense: i8,
    /// The shell's edges, as (smaller, larger) vertex pairs.
    edges: &'a Set<(u32, u32)>,
}

impl Plane<'_> {
    fn at(&self, v: u32) -> Pid {
        self.locus[v as usize]
    }

    fn turn(&self, a: u32, b: u32, c: u32) -> i8 {
        self.pts
            .orient2d(self.axis, [self.at(a), self.at(b), self.at(c)])
            * self.sense
    }

    fn approx(&self, v: u32) -> glam::DVec3 {
        self.pts.approx[self.at(v) as usize]
    }

    /// The corners of `ring` (where it does not run straight).
    fn corners(&self, ring: &[u32]) -> Vec<usize> {
        let n = ring.len();
        (0..n)
            .filter(|&k| self.turn(ring[(k + n - 1) % n], ring[k], ring[(k + 1) % n]) != 0)
            .collect()
    }

    /// Whether u → v leaves corner `k` of `ring` into the face (on the ring's left).
    fn into(&self, ring: &[u32], k: usize, v: u32) -> bool {
        let n = ring.len();
        let (p, u, q) = (ring[(k + n - 1) % n], ring[k], ring[(k + 1) % n]);
        let (left_out, left_in) = (self.turn(u, q, v) > 0, self.turn(p, u, v) > 0);
        if self.turn(p, u, q) > 0 {
            left_out && left_in
        } else {
            left_out || left_in
        }
    }

    /// Whether segments a–b and c–d meet anywhere but at one shared end (collinear
    /// contacts count as meeting).
    fn meet(&self, a: u32, b: u32, c: u32, d: u32) -> bool {
        let shared = [c, d].iter().filter(|&&x| x == a || x == b).count();
        if shared == 2 {
            return true;
        }
        if shared == 1 {
            let other = if c == a || c == b { d } else { c };
            if self.turn(a, b, other) != 0 {
                return false;
            }
            // Collinear with a shared end: they overlap if `other` lies on the
            // segment's side of the shared end.
            let s = if c == a || d == a { a } else { b };
            let t = if s == a { b } else { a };
            let (ps, pt, po) = (self.approx(s), self.approx(t), self.approx(other));
            return (pt - ps).dot(po - ps) > 0.0;
        }
        let (o1, o2) = (self.turn(a, b, c), self.turn(a, b, d));
        let (o3, o4) = (self.turn(c, d, a), self.turn(c, d, b));
        if o1 == 0 && o2 == 0 {
            let dir = self.approx(b) - self.approx(a);
            let (t0, t1) = (
                dir.dot(self.approx(c) - self.approx(a)),
                dir.dot(self.approx(d) - self.approx(a)),
            );
            return t0.max(t1) >= 0.0 && t0.min(t1) <= dir.length_squared();
        }
        o1 * o2 <= 0 && o3 * o4 <= 0
    }

    /// Whether point `x` (on no edge of `ring`) lies inside `ring`: its winding number,
    /// by a ray along the second projected axis, exactly.
    fn inside(&self, ring: &[u32], x: u32) -> bool {
        let j = (self.axis as usize + 2) % 3;
        // The sign of v_j − x_j.
        let above = |v: u32| super::split::coord_cmp_at(self.pts, j, self.at(x), self.at(v)) > 0;
        let mut winding = 0i32;
        for k in 0..ring.len() {
            let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
            match (above(a), above(b)) {
                (false, true) if self.turn(a, b, x) > 0 => winding += 1,
                (true, false) if self.turn(a, b, x) < 0 => winding -= 1,
                _ => {}
            }
        }
        winding != 0
    }

    /// Splits `outer` less `holes` into polygons without holes, appended to `out`, by
    /// two chords from a hole to the outer ring at a time.
    fn split(
        &self,
        outer: Vec<u32>,
        holes: Vec<Vec<u32>>,
        out: &mut Vec<Vec<u32>>,
        depth: usize,
    ) -> Option<()> {
        if holes.is_empty() {
            out.push(outer);
            return Some(());
        }
        if depth > MAX_CORNERS {
            return None;
        }
        let edges: Vec<(u32, u32)> = std::iter::once(&outer)
            .chain(&holes)
            .flat_map(|r| (0..r.len()).map(move |k| (r[k], r[(k + 1) % r.len()])))
            .collect();
        let clear = |u: u32, v: u32| edges.iter().all(|&(c, d)| !self.meet(u, v, c, d));
        let outer_corners = self.corners(&outer);
        for (hi, hole) in holes.iter().enumerate() {
            let mut chords: Vec<(f64, usize, usize)> = Vec::new();
            for &h in &self.corners(hole) {
                for &o in &outer_corners {
                    chords.push((
                        self.approx(hole[h]).distance_squared(self.approx(outer[o])),
                        h,
                        o,
                    ));
                }
            }
            chords.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
            let valid = |h: usize, o: usize| {
                let (u, v) = (hole[h], outer[o]);
                !self.edges.contains(&(u.min(v), u.max(v)))
                    && self.into(hole, h, v)
                    && self.into(&outer, o, u)
                    && clear(u, v)
            };
            let Some(&(_, ha, oa)) = chords.iter().find(|&&(_, h, o)| valid(h, o)) else {
                continue;
            };
            let Some(&(_, hb, ob)) = chords.iter().find(|&&(_, h, o)| {
                h != ha
                    && o != oa
                    && valid(h, o)
                    && !self.meet(hole[h], outer[o], hole[ha], outer[oa])
            }) else {
                continue;
            };
            // Outer from oa to ob, chord to hb, hole from hb to ha, chord back to oa;
            // and the other side.
            let arc = |ring: &[u32], from: usize, to: usize| {
                let n = ring.len();
                let mut arc = vec![ring[from]];
                let mut k = from;
                while k != to {
                    k = (k + 1) % n;
                    arc.push(ring[k]);
                }
                arc
            };
            let mut first = arc(&outer, oa, ob);
            first.extend(arc(hole, hb, ha));
            let mut second = arc(&outer, ob, oa);
            second.extend(arc(hole, ha, hb));
            let (mut in_first, mut in_second) = (Vec::new(), Vec::new());
            for (k, other) in holes.iter().enumerate() {
                if k == hi {
                    continue;
                }
                if self.inside(&first, other[0]) {
                    in_first.push(other.clone());
                } else {
                    in_second.push(other.clone());
                }
            }
            self.split(first, in_first, out, depth + 1)?;
            return self.split(second, in_second, out, depth + 1);
        }
        None
    }
}
