//! Refitting a hierarchy after primitives moved: the parent of every node, the leaf of
//! every leaf position, the boxes from a leaf up to the root, and the total surface area
//! that measures what refitting lost.

use super::Bvh;
use crate::spatial::aabb::Aabb;

impl Bvh {
    /// The parent of every node (the root's is itself), for [`Bvh::refit`].
    pub fn parents(&self) -> Vec<u32> {
        let mut parent = vec![0u32; self.nodes.len()];
        for (i, n) in self.nodes.enumerate() {
            if !n.is_leaf() {
                parent[n.first as usize] = i as u32;
                parent[n.first as usize + 1] = i as u32;
            }
        }
        parent
    }

    /// The leaf holding each leaf position, for [`Bvh::refit`].
    pub fn leaf_of_positions(&self) -> Vec<u32> {
        let mut leaf = vec![0u32; self.order.len()];
        for (i, n) in self.nodes.enumerate() {
            if n.is_leaf() {
                for k in n.first..n.first + n.count {
                    leaf[k as usize] = i as u32;
                }
            }
        }
        leaf
    }

    /// Refits after the box of a primitive in leaf `leaf` changed: the leaf's box
    /// becomes the union of `boxes` of its positions, and each ancestor the union of
    /// its two children, up to the root (stopping early once a box is unchanged).
    /// Returns the growth in total node surface area, a measure of lost quality.
    pub fn refit(&mut self, parents: &[u32], leaf: u32, boxes: impl Fn(usize) -> Aabb) -> f64 {
        let n = self.nodes[leaf as usize];
        let mut b = Aabb::EMPTY;
        for k in n.first..n.first + n.count {
            b = b.union(&boxes(k as usize));
        }
        let mut growth = 0.0;
        let mut i = leaf as usize;
        loop {
            let old = self.nodes[i];
            let before = old.aabb().half_area();
            self.nodes[i].set_box(&b);
            let now = self.nodes[i];
            growth += now.aabb().half_area() - before;
            if now.min == old.min && now.max == old.max && i != leaf as usize {
                break;
            }
            if i == 0 {
                break;
            }
            let p = parents[i] as usize;
            let f = self.nodes[p].first as usize;
            b = self.nodes[f].aabb().union(&self.nodes[f + 1].aabb());
            i = p;
        }
        growth
    }

    /// Reads the nodes of the first `levels` ancestors of node `leaf`, found through
    /// `parents` (as [`Bvh::refit`] takes it). The answer means nothing; a caller reads
    /// them so before it refits, for their cache misses to overlap the reads of the
    /// leaf's own boxes instead of following them one level at a time.
    #[inline]
    pub fn touch_path(&self, parents: &[u32], leaf: u32, levels: usize) -> u64 {
        let mut i = leaf as usize;
        let mut acc = 0;
        for _ in 0..levels {
            if i == 0 {
                break;
            }
            i = parents[i] as usize;
            acc ^= u64::from(self.nodes[i].first);
        }
        acc
    }

    /// Total half surface area of all nodes (the SAH cost scale).
    pub fn total_half_area(&self) -> f64 {
        self.nodes
            .enumerate()
            .map(|(_, n)| n.aabb().half_area())
            .sum()
    }
}
