//! A bounding-volume hierarchy over axis-aligned boxes: built by binned surface-area
//! heuristic, stored flat, boxes in `f32` rounded outward so that a node always contains
//! what is under it. A node's two children are adjacent and share one aligned cache line
//! (a node is 32 bytes), so a walk that tests both reads one line.
//!
//! The hierarchy orders its primitives: after [`Bvh::build`], `order()[k]` is the index
//! of the primitive stored at leaf position `k`, and leaves address ranges of that
//! order. Callers keep their primitive data in that order so that a leaf's primitives
//! are contiguous in memory.
//!
//! Traversals are conservative: they visit every leaf whose box could meet the query
//! (within rounding), and the caller runs the exact test on each primitive.
//!
//! The layout of the nodes is in `node`; the build in `build`; the walks (within a
//! distance, overlapping a box, nearest first, along a ray) in `walk`; and refitting
//! after a primitive's box changed in `refit`.

mod build;
mod node;
mod refit;
#[cfg(test)]
mod tests;
mod walk;

pub use build::LEAF_LIMIT;
pub use node::Node;

use node::Nodes;

/// The hierarchy: nodes (root first) and the primitive order of the leaves.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Nodes,
    order: Vec<u32>,
}

impl Bvh {
    /// Node `i` (0 is the root). Precondition: `i` is the root or a node some node
    /// links to.
    #[inline]
    pub fn node(&self, i: usize) -> &Node {
        &self.nodes[i]
    }

    /// The leaves.
    pub fn leaves(&self) -> impl Iterator<Item = &Node> {
        self.nodes
            .enumerate()
            .map(|(_, n)| n)
            .filter(|n| n.is_leaf())
    }

    /// `order()[k]`: the primitive at leaf position `k`.
    #[inline]
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Whether there are no primitives.
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// Renumbers the primitives by leaf position (`order()[k] == k` afterwards), for a
    /// caller that has laid its primitive data out in [`Bvh::order`].
    pub fn identity_order(&mut self) {
        for (k, i) in self.order.iter_mut().enumerate() {
            *i = k as u32;
        }
    }

    /// Heap bytes held.
    pub fn heap_bytes(&self) -> usize {
        self.nodes.heap_bytes() + self.order.capacity() * 4
    }

    /// Reads a word of every node pair (each one cache line). The answer means nothing:
    /// see [`BodyShape::touch_all`](super::shape::BodyShape::touch_all).
    #[inline]
    pub fn touch(&self) -> u64 {
        self.nodes
            .0
            .iter()
            .fold(0, |acc, p| acc ^ u64::from(p.0[0].first))
    }
}
