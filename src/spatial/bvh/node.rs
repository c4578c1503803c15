//! The layout of a hierarchy's nodes: a node (its box in `f32` and its links), and the
//! node list in pairs of siblings, one pair to an aligned cache line.

use glam::DVec3;

use crate::spatial::aabb::Aabb;

/// One node: its box and either two children (at `first` and `first + 1`) or a range
/// of primitives (`first .. first + count`).
#[derive(Clone, Copy, Debug)]
pub struct Node {
    /// Smallest corner.
    pub min: [f32; 3],
    /// Largest corner.
    pub max: [f32; 3],
    /// The first child, or the first primitive position when `count > 0`.
    pub first: u32,
    /// Primitives in this leaf; 0 for an inner node.
    pub count: u32,
}

impl Node {
    /// Whether this node is a leaf.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// Squared distance from `p` to the node's box (0 inside). Without branches: on
    /// each axis the larger of `lo − x` and `x − hi` is the gap when positive.
    #[inline]
    pub fn distance_squared(&self, p: DVec3) -> f64 {
        let lo = DVec3::from_array(self.min.map(f64::from));
        let hi = DVec3::from_array(self.max.map(f64::from));
        (lo - p).max(p - hi).max(DVec3::ZERO).length_squared()
    }

    /// Whether the node's box meets the closed box `lo..=hi`.
    #[inline]
    pub fn overlaps(&self, lo: DVec3, hi: DVec3) -> bool {
        (0..3).all(|k| f64::from(self.min[k]) <= hi[k] && f64::from(self.max[k]) >= lo[k])
    }

    /// The parameter interval where the ray `o + t·d` (with `inv` = 1/d per axis) is in
    /// the box, clipped to `[0, t_max]`, or `None`.
    #[inline]
    pub fn ray_interval(&self, o: DVec3, inv: DVec3, t_max: f64) -> Option<f64> {
        let (mut t0, mut t1) = (0.0f64, t_max);
        for k in 0..3 {
            let lo = f64::from(self.min[k]);
            let hi = f64::from(self.max[k]);
            if inv[k].is_infinite() {
                if o[k] < lo || o[k] > hi {
                    return None;
                }
                continue;
            }
            let (mut a, mut b) = ((lo - o[k]) * inv[k], (hi - o[k]) * inv[k]);
            if a > b {
                std::mem::swap(&mut a, &mut b);
            }
            // Widen by a hair so that rounding never loses a grazing hit.
            t0 = t0.max(a - a.abs() * 1e-12);
            t1 = t1.min(b + b.abs() * 1e-12);
        }
        (t0 <= t1).then_some(t0)
    }

    /// The node's box.
    #[inline]
    pub(super) fn aabb(&self) -> Aabb {
        Aabb::new(
            DVec3::from_array(self.min.map(f64::from)),
            DVec3::from_array(self.max.map(f64::from)),
        )
    }

    /// Sets the node's box to `b` rounded outward.
    #[inline]
    pub(super) fn set_box(&mut self, b: &Aabb) {
        let (min, max) = b.to_f32_outward();
        self.min = min;
        self.max = max;
    }
}

/// A blank node: the root's partner in its line (node 1), which nothing links to.
pub(super) const PAD: Node = Node {
    min: [0.0; 3],
    max: [0.0; 3],
    first: 0,
    count: 0,
};

/// Two sibling nodes (or the root and [`PAD`]) in one cache line.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct Pair(pub(super) [Node; 2]);

const _: () = assert!(std::mem::size_of::<Pair>() == 64);

/// The nodes, in pairs: node `i` is `pairs[i / 2][i % 2]`. Node 0 is the root and node
/// 1 is [`PAD`]; every node's children are nodes `2p` and `2p + 1` of some pair `p`.
#[derive(Clone, Debug, Default)]
pub(super) struct Nodes(pub(super) Vec<Pair>);

impl Nodes {
    /// The root alone (with its pad).
    #[inline]
    pub(super) fn with_root(root: Node, capacity: usize) -> Nodes {
        let mut pairs = Vec::with_capacity(capacity.div_ceil(2));
        pairs.push(Pair([root, PAD]));
        Nodes(pairs)
    }

    /// Nodes held, the pad included (0 for an empty hierarchy).
    #[inline]
    pub(super) fn len(&self) -> usize {
        2 * self.0.len()
    }

    /// Whether there are no nodes (an empty hierarchy).
    #[inline]
    pub(super) fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Adds two siblings; answers the index of the first.
    #[inline]
    pub(super) fn push_pair(&mut self, a: Node, b: Node) -> usize {
        self.0.push(Pair([a, b]));
        self.len() - 2
    }

    /// Each node but the pad, with its index.
    #[inline]
    pub(super) fn enumerate(&self) -> impl Iterator<Item = (usize, &Node)> {
        self.0
            .iter()
            .flat_map(|p| &p.0)
            .enumerate()
            .filter(|&(i, _)| i != 1)
    }

    /// Heap bytes held.
    pub(super) fn heap_bytes(&self) -> usize {
        self.0.capacity() * std::mem::size_of::<Pair>()
    }
}

impl std::ops::Index<usize> for Nodes {
    type Output = Node;

    #[inline]
    fn index(&self, i: usize) -> &Node {
        &self.0[i >> 1].0[i & 1]
    }
}

impl std::ops::IndexMut<usize> for Nodes {
    #[inline]
    fn index_mut(&mut self, i: usize) -> &mut Node {
        &mut self.0[i >> 1].0[i & 1]
    }
}
