//! A face that surrounds holes, cut into faces of one ring each.
//!
//! A winged-edge face is one ring, so where carving leaves a face around a hole (a box's
//! top face seen through a frame's opening), the face is cut in two by two chords, each
//! from a corner of the hole to a corner of the ring around it, inside the face and
//! crossing nothing; each part keeps the holes it holds, and is cut again for them.
//! The chords are new edges between two coplanar faces made by the same maker.
//!
//! Every decision is an exact orientation of the points' planar coordinates (`robust`).

use glam::DVec2;
use robust::{Coord, orient2d};

/// The rings of one planar face (outer rings turning counter-clockwise in the
/// coordinates `at` gives, holes clockwise) as rings without holes; `None` when a hole
/// lies in no outer ring or no clear chords join it to the ring around it.
///
/// Postconditions: the rings returned tile the same region; each is simple where the
/// input was; every point of the input is in one of them or more.
pub fn without_holes<K: Copy + PartialEq>(
    rings: Vec<Vec<K>>,
    at: impl Fn(&K) -> DVec2,
) -> Option<Vec<Vec<K>>> {
    let area = |r: &[K]| -> f64 {
        let p: Vec<DVec2> = r.iter().map(&at).collect();
        (0..p.len())
            .map(|k| p[k].perp_dot(p[(k + 1) % p.len()]))
            .sum()
    };
    let (outer, holes): (Vec<Vec<K>>, Vec<Vec<K>>) = rings.into_iter().partition(|r| area(r) > 0.0);
    if holes.is_empty() {
        return Some(outer);
    }
    // Each outer ring with the holes it holds (the smallest outer ring holding each).
    let mut groups: Vec<(Vec<K>, Vec<Vec<K>>)> =
        outer.into_iter().map(|o| (o, Vec::new())).collect();
    for hole in holes {
        let probe = at(&hole[0]);
        let mut best: Option<(usize, f64)> = None;
        for (i, (o, _)) in groups.iter().enumerate() {
            let ring: Vec<DVec2> = o.iter().map(&at).collect();
            if inside(&ring, probe)? {
                let a = area(o);
                if best.is_none_or(|(_, b)| a < b) {
                    best = Some((i, a));
                }
            }
        }
        groups[best?.0].1.push(hole);
    }
    let mut out = Vec::new();
    for (ring, holes) in groups {
        cut(ring, holes, &at, &mut out)?;
    }
    Some(out)
}

/// Cuts `ring` around `holes` into rings without holes, pushed onto `out`.
fn cut<K: Copy + PartialEq>(
    ring: Vec<K>,
    mut holes: Vec<Vec<K>>,
    at: &impl Fn(&K) -> DVec2,
    out: &mut Vec<Vec<K>>,
) -> Option<()> {
    let Some(hole) = holes.pop() else {
        out.push(ring);
        return Some(());
    };
    let pts = |r: &[K]| -> Vec<DVec2> { r.iter().map(at).collect() };
    let (rp, hp) = (pts(&ring), pts(&hole));
    let others: Vec<Vec<DVec2>> = holes.iter().map(|h| pts(h)).collect();
    // The hole's corners least and greatest in u (ties by v): the chords leave from there.
    let order = |a: &DVec2, b: &DVec2| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y));
    let lo = (0..hp.len()).min_by(|&i, &j| order(&hp[i], &hp[j]))?;
    let hi = (0..hp.len()).max_by(|&i, &j| order(&hp[i], &hp[j]))?;
    let mut obstacles: Vec<(DVec2, DVec2)> = Vec::new();
    for r in std::iter::once(&rp)
        .chain(std::iter::once(&hp))
        .chain(others.iter())
    {
        for k in 0..r.len() {
            obstacles.push((r[k], r[(k + 1) % r.len()]));
        }
    }
    let first = chord(&rp, &hp, lo, &obstacles, None)?;
    obstacles.push((hp[lo], rp[first]));
    let second = chord(&rp, &hp, hi, &obstacles, Some(first))?;
    // Two rings: along the outer ring from one chord's end to the other's, across, along
    // the hole (clockwise, as it is listed) back, and across again.
    let walk = |r: &[K], from: usize, to: usize| -> Vec<K> {
        let mut v = vec![r[from]];
        let mut k = from;
        while k != to {
            k = (k + 1) % r.len();
            v.push(r[k]);
        }
        v
    };
    let mut a = walk(&ring, first, second);
    a.extend(walk(&hole, hi, lo));
    let mut b = walk(&ring, second, first);
    b.extend(walk(&hole, lo, hi));
    // The other holes go with the part that holds them.
    let mut holes_a = Vec::new();
    let mut holes_b = Vec::new();
    let pa = pts(&a);
    for h in holes {
        if inside(&pa, at(&h[0]))? {
            holes_a.push(h);
        } else {
            holes_b.push(h);
        }
    }
    cut(a, holes_a, at, out)?;
    cut(b, holes_b, at, out)
}

/// The corner of `ring` nearest to hole corner `m` that a chord reaches inside the face
/// without meeting an obstacle, other than `not`.
fn chord(
    ring: &[DVec2],
    hole: &[DVec2],
    m: usize,
    obstacles: &[(DVec2, DVec2)],
    not: Option<usize>,
) -> Option<usize> {
    let n = ring.len();
    let h = hole.len();
    let mp = hole[m];
    let (m0, m1) = (hole[(m + h - 1) % h], hole[(m + 1) % h]);
    let mut candidates: Vec<usize> = (0..n).filter(|&k| Some(k) != not).collect();
    candidates.sort_by(|&a, &b| {
        (ring[a] - mp)
            .length_squared()
            .total_cmp(&(ring[b] - mp).length_squared())
    });
    candidates.into_iter().find(|&k| {
        let p = ring[k];
        let (p0, p1) = (ring[(k + n - 1) % n], ring[(k + 1) % n]);
        within_wedge(p0, p, p1, mp)
            && within_wedge(m0, mp, m1, p)
            && obstacles.iter().all(|&(a, b)| {
                let shares = a == p || b == p || a == mp || b == mp;
                shares || !segments_meet(p, mp, a, b)
            })
    })
}

/// Whether the direction from corner `p` toward `q` points strictly into the region at
/// `p`, which lies on the left of edges `p0 → p` and `p → p1`.
fn within_wedge(p0: DVec2, p: DVec2, p1: DVec2, q: DVec2) -> bool {
    let (a, b) = (orient(p0, p, q), orient(p, p1, q));
    if orient(p0, p, p1) > 0.0 {
        a > 0.0 && b > 0.0
    } else {
        a > 0.0 || b > 0.0
    }
}

/// Whether closed segments `a b` and `c d` share a point.
fn segments_meet(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    if a.max(b).cmplt(c.min(d)).any() || c.max(d).cmplt(a.min(b)).any() {
        return false;
    }
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    if (o1 > 0.0 && o2 > 0.0) || (o1 < 0.0 && o2 < 0.0) {
        return false;
    }
    if (o3 > 0.0 && o4 > 0.0) || (o3 < 0.0 && o4 < 0.0) {
        return false;
    }
    // Both pairs straddle or touch; collinear segments whose boxes overlap share a point.
    true
}

/// Whether `q` is inside `ring` (exactly); `None` on its boundary.
fn inside(ring: &[DVec2], q: DVec2) -> Option<bool> {
    let mut odd = false;
    for k in 0..ring.len() {
        let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
        let within = q.cmpge(a.min(b)).all() && q.cmple(a.max(b)).all();
        let o = orient(a, b, q);
        if o == 0.0 && within {
            return None;
        }
        if (a.y > q.y) != (b.y > q.y) && ((b.y > a.y && o > 0.0) || (b.y < a.y && o < 0.0)) {
            odd = !odd;
        }
    }
    Some(odd)
}

fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    orient2d(
        Coord { x: a.x, y: a.y },
        Coord { x: b.x, y: b.y },
        Coord { x: c.x, y: c.y },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(r: &[DVec2]) -> f64 {
        (0..r.len())
            .map(|k| r[k].perp_dot(r[(k + 1) % r.len()]))
            .sum::<f64>()
            / 2.0
    }

    #[test]
    fn a_square_around_a_square_hole_becomes_two_rings_of_the_same_area() {
        let outer = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(4.0, 0.0),
            DVec2::new(4.0, 4.0),
            DVec2::new(0.0, 4.0),
        ];
        let hole = vec![
            DVec2::new(1.0, 1.0),
            DVec2::new(1.0, 3.0),
            DVec2::new(3.0, 3.0),
            DVec2::new(3.0, 1.0),
        ];
        let rings = without_holes(vec![outer, hole], |p| *p).expect("cut");
        assert_eq!(rings.len(), 2);
        let total: f64 = rings.iter().map(|r| area(r)).sum();
        assert_eq!(total, 12.0);
        for r in &rings {
            assert!(area(r) > 0.0);
        }
    }

    #[test]
    fn two_holes_give_three_rings() {
        let outer = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(9.0, 0.0),
            DVec2::new(9.0, 4.0),
            DVec2::new(0.0, 4.0),
        ];
        let square = |x: f64| {
            vec![
                DVec2::new(x, 1.0),
                DVec2::new(x, 3.0),
                DVec2::new(x + 2.0, 3.0),
                DVec2::new(x + 2.0, 1.0),
            ]
        };
        let rings = without_holes(vec![outer, square(1.0), square(5.0)], |p| *p).expect("cut");
        assert_eq!(rings.len(), 3);
        let total: f64 = rings.iter().map(|r| area(r)).sum();
        assert_eq!(total, 36.0 - 8.0);
    }
}
