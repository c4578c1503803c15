//! Candidate pairs of triangles whose bounding boxes overlap: a bounding volume
//! hierarchy over one mesh's triangle boxes, queried with the other's.

use glam::DVec3;

/// A bounding volume hierarchy over boxes, split at the median of the longest axis.
pub(crate) struct Tree {
    nodes: Vec<Node>,
    order: Vec<u32>,
}

struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: `order[start..start + count]`; inner: children `start` and `start + 1`.
    start: u32,
    count: u32,
}

const LEAF: usize = 4;

impl Tree {
    /// The tree over `boxes` (each `[lo, hi]`).
    pub fn new(boxes: &[[DVec3; 2]]) -> Tree {
        let mut t = Tree {
            nodes: Vec::with_capacity(2 * boxes.len() / LEAF + 1),
            order: (0..boxes.len() as u32).collect(),
        };
        t.nodes.push(Node {
            lo: DVec3::ZERO,
            hi: DVec3::ZERO,
            start: 0,
            count: 0,
        });
        t.build(boxes, 0, 0, boxes.len());
        t
    }

    fn build(&mut self, boxes: &[[DVec3; 2]], node: usize, start: usize, end: usize) {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &i in &self.order[start..end] {
            lo = lo.min(boxes[i as usize][0]);
            hi = hi.max(boxes[i as usize][1]);
        }
        self.nodes[node].lo = lo;
        self.nodes[node].hi = hi;
        if end - start <= LEAF {
            self.nodes[node].start = start as u32;
            self.nodes[node].count = (end - start) as u32;
            return;
        }
        let ext = hi - lo;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mid = (start + end) / 2;
        let centre = |i: u32| boxes[i as usize][0][axis] + boxes[i as usize][1][axis];
        self.order[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
            centre(a).total_cmp(&centre(b)).then(a.cmp(&b))
        });
        let left = self.nodes.len();
        for _ in 0..2 {
            self.nodes.push(Node {
                lo: DVec3::ZERO,
                hi: DVec3::ZERO,
                start: 0,
                count: 0,
            });
        }
        self.nodes[node].start = left as u32;
        self.nodes[node].count = 0;
        self.build(boxes, left, start, mid);
        self.build(boxes, left + 1, mid, end);
    }

    /// Every pair `(i, j)` of an index of this tree and one of `other` whose boxes
    /// meet and which `keep` accepts, found by descending both trees together
    /// (`boxes` and `other_boxes` are the boxes each was built over). Postcondition:
    /// each such pair once, in an order fixed by the boxes alone.
    pub fn pairs(
        &self,
        boxes: &[[DVec3; 2]],
        other: &Tree,
        other_boxes: &[[DVec3; 2]],
        mut keep: impl FnMut(u32, u32) -> bool,
        out: &mut Vec<(u32, u32)>,
    ) {
        out.clear();
        if self.order.is_empty() || other.order.is_empty() {
            return;
        }
        let mut stack = vec![(0usize, 0usize)];
        while let Some((n, m)) = stack.pop() {
            let (a, b) = (&self.nodes[n], &other.nodes[m]);
            if !meet([a.lo, a.hi], [b.lo, b.hi]) {
                continue;
            }
            if a.count > 0 && b.count > 0 {
                for &i in self.leaf(a) {
                    for &j in other.leaf(b) {
                        if meet(boxes[i as usize], other_boxes[j as usize]) && keep(i, j) {
                            out.push((i, j));
                        }
                    }
                }
            } else {
                stack.extend(descend(a, b, n, m));
            }
        }
    }

    /// Every pair `(i, j)`, `i < j`, of this tree's indices whose boxes meet and which
    /// `keep` accepts (`boxes` are the boxes the tree was built over). Postcondition:
    /// each such pair once, in an order fixed by the boxes alone.
    pub fn self_pairs(
        &self,
        boxes: &[[DVec3; 2]],
        mut keep: impl FnMut(u32, u32) -> bool,
        out: &mut Vec<(u32, u32)>,
    ) {
        out.clear();
        if self.order.is_empty() {
            return;
        }
        let mut test = |i: u32, j: u32, out: &mut Vec<(u32, u32)>| {
            let (i, j) = (i.min(j), i.max(j));
            if meet(boxes[i as usize], boxes[j as usize]) && keep(i, j) {
                out.push((i, j));
            }
        };
        self.self_pairs_under(boxes, (0, 0), &mut test, out);
    }

    /// Splits the search of [`Tree::self_pairs`] into independent parts, about `parts`
    /// of them: each is a pair of nodes, `(n, n)` standing for the pairs within `n`'s
    /// subtree. Together they cover every pair once.
    pub fn self_pair_parts(&self, parts: usize) -> Vec<(usize, usize)> {
        let mut out = vec![(0usize, 0usize)];
        if self.order.is_empty() {
            return Vec::new();
        }
        while out.len() < parts {
            let before = out.len();
            let mut next = Vec::with_capacity(3 * out.len());
            for (n, m) in out {
                let (a, b) = (&self.nodes[n], &self.nodes[m]);
                if n == m && a.count == 0 {
                    let (l, r) = (a.start as usize, a.start as usize + 1);
                    next.extend([(l, l), (r, r), (l, r)]);
                } else if n != m && (a.count == 0 || b.count == 0) {
                    if meet([a.lo, a.hi], [b.lo, b.hi]) {
                        next.extend(descend(a, b, n, m));
                    }
                } else {
                    next.push((n, m));
                }
            }
            out = next;
            if out.len() == before {
                break;
            }
        }
        out
    }

    /// [`Tree::self_pairs`] for one part of [`Tree::self_pair_parts`], `out` not
    /// cleared.
    pub fn self_pairs_in(
        &self,
        boxes: &[[DVec3; 2]],
        part: (usize, usize),
        mut keep: impl FnMut(u32, u32) -> bool,
        out: &mut Vec<(u32, u32)>,
    ) {
        let mut test = |i: u32, j: u32, out: &mut Vec<(u32, u32)>| {
            let (i, j) = (i.min(j), i.max(j));
            if meet(boxes[i as usize], boxes[j as usize]) && keep(i, j) {
                out.push((i, j));
            }
        };
        self.self_pairs_under(boxes, part, &mut test, out);
    }

    fn self_pairs_under(
        &self,
        _boxes: &[[DVec3; 2]],
        part: (usize, usize),
        test: &mut impl FnMut(u32, u32, &mut Vec<(u32, u32)>),
        out: &mut Vec<(u32, u32)>,
    ) {
        // A node paired with itself stands for the pairs within its subtree.
        let mut stack = vec![part];
        while let Some((n, m)) = stack.pop() {
            let (a, b) = (&self.nodes[n], &self.nodes[m]);
            if n == m {
                if a.count > 0 {
                    let leaf = self.leaf(a);
                    for (k, &i) in leaf.iter().enumerate() {
                        for &j in &leaf[k + 1..] {
                            test(i, j, out);
                        }
                    }
                } else {
                    let (l, r) = (a.start as usize, a.start as usize + 1);
                    stack.extend([(l, l), (r, r), (l, r)]);
                }
            } else if !meet([a.lo, a.hi], [b.lo, b.hi]) {
                continue;
            } else if a.count > 0 && b.count > 0 {
                for &i in self.leaf(a) {
                    for &j in self.leaf(b) {
                        test(i, j, out);
                    }
                }
            } else {
                stack.extend(descend(a, b, n, m));
            }
        }
    }

    fn leaf(&self, node: &Node) -> &[u32] {
        let s = node.start as usize;
        &self.order[s..s + node.count as usize]
    }
}

/// The plane of a triangle in f64, with what bounds its rounding, for culling boxes.
pub(crate) struct Plane {
    /// A corner.
    a: DVec3,
    /// The normal `(b − a) × (c − a)`, rounded.
    n: DVec3,
    /// Per component, `|e_j||f_k| + |e_k||f_j|` for `e = b − a`, `f = c − a`: it bounds
    /// the normal's component and scales its rounding error.
    span: DVec3,
}

/// Unit roundoff of f64.
const U: f64 = f64::EPSILON / 2.0;

impl Plane {
    /// The plane through `a`, `b` and `c` (finite).
    pub fn new(a: DVec3, b: DVec3, c: DVec3) -> Plane {
        let (e, f) = (b - a, c - a);
        let (ea, fa) = (e.abs(), f.abs());
        Plane {
            a,
            n: e.cross(f),
            span: DVec3::new(
                ea.y * fa.z + ea.z * fa.y,
                ea.z * fa.x + ea.x * fa.z,
                ea.x * fa.y + ea.y * fa.x,
            ),
        }
    }

    /// Whether the points `x` all lie strictly on one side of the exact plane through
    /// the three corners. Conservative: `false` whenever rounding could hide a point on
    /// the plane or across it (the margin covers the normal's error, ≤ 5u per unit of
    /// `span`, and the evaluation's, with room to spare).
    pub fn apart(&self, x: &[DVec3]) -> bool {
        let mut side = 0.0;
        for &p in x {
            let g = p - self.a;
            let s = self.n.dot(g);
            let margin = 32.0 * U * self.span.dot(g.abs()) + f64::MIN_POSITIVE;
            if s.abs() <= margin || s * side < 0.0 {
                return false;
            }
            side = s;
        }
        true
    }
}

/// The children to pair next when node `a` (index `n`) meets node `b` (index `m`) and
/// one of them is inner: the larger inner box is split.
fn descend(a: &Node, b: &Node, n: usize, m: usize) -> [(usize, usize); 2] {
    let split_a =
        b.count > 0 || (a.count == 0 && (a.hi - a.lo).max_element() >= (b.hi - b.lo).max_element());
    if split_a {
        [a.start, a.start + 1].map(|c| (c as usize, m))
    } else {
        [b.start, b.start + 1].map(|c| (n, c as usize))
    }
}

/// Whether two closed boxes meet.
#[inline]
pub(crate) fn meet(a: [DVec3; 2], b: [DVec3; 2]) -> bool {
    a[0].cmple(b[1]).all() && b[0].cmple(a[1]).all()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxes(seed: u64, n: usize) -> Vec<[DVec3; 2]> {
        let mut x = seed;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let lo = DVec3::new(next(), next(), next()) * 10.0;
                [lo, lo + DVec3::new(next(), next(), next())]
            })
            .collect()
    }

    /// Both descents find exactly the pairs a test of every pair finds.
    #[test]
    fn descents_find_every_meeting_pair_once() {
        let (a, b) = (boxes(7, 300), boxes(11, 200));
        let (ta, tb) = (Tree::new(&a), Tree::new(&b));
        let odd = |i: u32, j: u32| !(i + j).is_multiple_of(3);
        let mut got = Vec::new();
        ta.pairs(&a, &tb, &b, odd, &mut got);
        got.sort_unstable();
        let mut want = Vec::new();
        for (i, x) in a.iter().enumerate() {
            for (j, y) in b.iter().enumerate() {
                if meet(*x, *y) && odd(i as u32, j as u32) {
                    want.push((i as u32, j as u32));
                }
            }
        }
        assert!(!want.is_empty());
        assert_eq!(got, want);
        ta.self_pairs(&a, odd, &mut got);
        got.sort_unstable();
        let mut want = Vec::new();
        for i in 0..a.len() {
            for j in i + 1..a.len() {
                if meet(a[i], a[j]) && odd(i as u32, j as u32) {
                    want.push((i as u32, j as u32));
                }
            }
        }
        assert!(!want.is_empty());
        assert_eq!(got, want);
    }

    /// A plane keeps points apart only when the exact orientation puts every one of
    /// them strictly on one side; points on the plane are never apart.
    #[test]
    fn a_plane_parts_points_only_when_they_are_strictly_on_one_side() {
        let c = |v: DVec3| robust::Coord3D {
            x: v.x,
            y: v.y,
            z: v.z,
        };
        let corners = boxes(3, 600);
        let mut parted = 0;
        for t in corners.chunks(6) {
            let (p, q, r) = (t[0][0], t[1][1], t[2][0]);
            let plane = Plane::new(p, q, r);
            let x = [t[3][0], t[4][1], t[5][0]];
            let o: Vec<f64> = x
                .iter()
                .map(|&v| robust::orient3d(c(p), c(q), c(r), c(v)))
                .collect();
            let strictly = o.iter().all(|&s| s > 0.0) || o.iter().all(|&s| s < 0.0);
            if plane.apart(&x) {
                parted += 1;
                assert!(strictly, "{p} {q} {r} parts {x:?}");
            }
            // A point on the plane (a corner, or the exact midpoint of a side).
            assert!(!plane.apart(&[x[0], p]));
            assert!(
                !plane.apart(&[(p + q) * 0.5])
                    || robust::orient3d(c(p), c(q), c(r), c((p + q) * 0.5)) != 0.0
            );
        }
        assert!(parted > 20, "the plane parts little: {parted}");
    }
}
