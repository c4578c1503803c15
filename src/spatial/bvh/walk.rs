//! Walks of a hierarchy: the leaves within a distance of a point or overlapping a box
//! (breadth first), nearest first from a point, and front to back along a ray.

use glam::DVec3;

use super::Bvh;
use super::node::Node;
use crate::spatial::prefetch::prefetch;

/// Nodes waiting to be walked: first in, first out while they fit in a ring on the
/// stack (the walk is then breadth first, and allocates nothing); nodes that find the
/// ring full wait in a spill list, taken last in, first out once the ring is empty.
/// Every node pushed is popped once, whatever the order.
pub(super) struct Frontier {
    ring: [u32; Frontier::RING],
    /// Pops so far from the ring (its head is `head % RING`).
    head: usize,
    /// Pushes so far to the ring.
    tail: usize,
    spill: Vec<u32>,
}

impl Frontier {
    /// Ring slots: more than the widest level of a query of a few hundred leaves.
    pub(super) const RING: usize = 256;

    pub(super) fn new() -> Frontier {
        Frontier {
            ring: [0; Frontier::RING],
            head: 0,
            tail: 0,
            spill: Vec::new(),
        }
    }

    #[inline]
    pub(super) fn push(&mut self, i: u32) {
        if self.tail - self.head < Frontier::RING {
            self.ring[self.tail % Frontier::RING] = i;
            self.tail += 1;
        } else {
            self.spill.push(i);
        }
    }

    #[inline]
    pub(super) fn pop(&mut self) -> Option<u32> {
        if self.head < self.tail {
            let i = self.ring[self.head % Frontier::RING];
            self.head += 1;
            Some(i)
        } else {
            self.spill.pop()
        }
    }
}

impl Bvh {
    /// Calls `visit(k)` for each leaf position `k` whose box (by its leaf) lies within
    /// `r2_cull` (a squared distance) of `p`.
    #[inline]
    pub fn within(&self, p: DVec3, r2_cull: f64, mut visit: impl FnMut(usize)) {
        self.walk(|n| n.distance_squared(p) <= r2_cull, &mut |k| {
            visit(k);
            true
        });
    }

    /// Calls `visit(k)` for each leaf position `k` whose leaf box meets `lo..=hi`.
    #[inline]
    pub fn overlapping(&self, lo: DVec3, hi: DVec3, mut visit: impl FnMut(usize)) {
        self.overlapping_until(lo, hi, |k| {
            visit(k);
            true
        });
    }

    /// [`Bvh::overlapping`] until `visit` answers `false`: no leaf position is visited
    /// after that.
    #[inline]
    pub fn overlapping_until(&self, lo: DVec3, hi: DVec3, mut visit: impl FnMut(usize) -> bool) {
        self.walk(|n| n.overlaps(lo, hi), &mut visit);
    }

    /// Prefetches the line of `node`'s children, when it is an inner node: a walk that
    /// will go down into `node` later calls this when it decides to, so that the line
    /// is on its way while the walk reads other nodes.
    #[inline(always)]
    fn prefetch_children(&self, node: &Node) {
        if !node.is_leaf()
            && let Some(pair) = self.nodes.0.get(node.first as usize >> 1)
        {
            prefetch(pair);
        }
    }

    /// Visits the leaf positions of the leaves reached through nodes `enter` accepts,
    /// until `visit` answers `false`.
    ///
    /// The walk is breadth first (see [`Frontier`]): every node of one level is read
    /// before any of the next so that, on a hierarchy out of cache, their misses overlap
    /// (a depth-first walk waits for each node's line before it can read the next).
    /// Each node entered has its children's line prefetched as it joins the frontier,
    /// a level before the walk reads it.
    fn walk(&self, mut enter: impl FnMut(&Node) -> bool, visit: &mut impl FnMut(usize) -> bool) {
        if self.nodes.is_empty() || !enter(&self.nodes[0]) {
            return;
        }
        let mut frontier = Frontier::new();
        frontier.push(0);
        while let Some(i) = frontier.pop() {
            let n = &self.nodes[i as usize];
            if n.is_leaf() {
                for k in n.first..n.first + n.count {
                    if !visit(k as usize) {
                        return;
                    }
                }
                continue;
            }
            for c in [n.first, n.first + 1] {
                let child = &self.nodes[c as usize];
                if enter(child) {
                    self.prefetch_children(child);
                    frontier.push(c);
                }
            }
        }
    }

    /// Best-first search: calls `test(k, best)` for leaf positions in order of their
    /// leaf's distance from `p`, while that distance (squared) is below `best`;
    /// `test` answers the new best squared distance (or `best` unchanged).
    pub fn nearest(&self, p: DVec3, mut best: f64, mut test: impl FnMut(usize, f64) -> f64) -> f64 {
        if self.nodes.is_empty() {
            return best;
        }
        let mut heap = std::collections::BinaryHeap::new();
        heap.push(Near(self.nodes[0].distance_squared(p), 0));
        while let Some(Near(d, i)) = heap.pop() {
            if d > best {
                break;
            }
            let n = &self.nodes[i as usize];
            if n.is_leaf() {
                for k in n.first..n.first + n.count {
                    best = test(k as usize, best);
                }
                continue;
            }
            for c in [n.first, n.first + 1] {
                let child = &self.nodes[c as usize];
                let dc = child.distance_squared(p);
                if dc <= best {
                    self.prefetch_children(child);
                    heap.push(Near(dc, c));
                }
            }
        }
        best
    }

    /// Front-to-back ray walk: calls `test(k, t_best)` for leaf positions whose leaf the
    /// ray `o + t·d` enters before `t_best`; `test` answers the new `t_best`.
    pub fn ray(
        &self,
        o: DVec3,
        d: DVec3,
        mut t_best: f64,
        mut test: impl FnMut(usize, f64) -> f64,
    ) -> f64 {
        if self.nodes.is_empty() {
            return t_best;
        }
        let inv = DVec3::ONE / d;
        let mut stack: Vec<(f64, u32)> = Vec::with_capacity(64);
        if let Some(t) = self.nodes[0].ray_interval(o, inv, t_best) {
            stack.push((t, 0));
        }
        while let Some((t, i)) = stack.pop() {
            if t > t_best {
                continue;
            }
            let n = &self.nodes[i as usize];
            if n.is_leaf() {
                for k in n.first..n.first + n.count {
                    t_best = test(k as usize, t_best);
                }
                continue;
            }
            let a = self.nodes[n.first as usize].ray_interval(o, inv, t_best);
            let b = self.nodes[n.first as usize + 1].ray_interval(o, inv, t_best);
            // Push the farther child first so the nearer one is walked first.
            match (a, b) {
                (Some(ta), Some(tb)) if ta <= tb => {
                    stack.push((tb, n.first + 1));
                    stack.push((ta, n.first));
                }
                (Some(ta), Some(tb)) => {
                    stack.push((ta, n.first));
                    stack.push((tb, n.first + 1));
                }
                (Some(ta), None) => stack.push((ta, n.first)),
                (None, Some(tb)) => stack.push((tb, n.first + 1)),
                (None, None) => {}
            }
        }
        t_best
    }
}

/// A heap entry for best-first search: nearest first.
#[derive(PartialEq)]
struct Near(f64, u32);
impl Eq for Near {}
impl PartialOrd for Near {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Near {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
    }
}
