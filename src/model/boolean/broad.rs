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

    /// Every index whose subtree's box meets `[lo, hi]` (closed boxes), in
    /// ascending order; the caller tests each box itself.
    pub fn query(&self, lo: DVec3, hi: DVec3, out: &mut Vec<u32>) {
        out.clear();
        if self.order.is_empty() {
            return;
        }
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            if node.lo.cmpgt(hi).any() || node.hi.cmplt(lo).any() {
                continue;
            }
            if node.count > 0 {
                let s = node.start as usize;
                out.extend_from_slice(&self.order[s..s + node.count as usize]);
            } else {
                stack.push(node.start as usize);
                stack.push(node.start as usize + 1);
            }
        }
        out.sort_unstable();
    }
}
