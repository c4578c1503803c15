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

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::aabb::Aabb;
use super::prefetch::prefetch;

/// Primitives per leaf, as a rule.
const LEAF_MAX: usize = 4;
/// Primitives per leaf at most (a small set with coincident centroids stays whole).
pub const LEAF_LIMIT: usize = 2 * LEAF_MAX;
/// SAH bins per axis.
const BINS: usize = 12;
/// Primitives under a node above which its two subtrees are built in parallel.
const PARALLEL_MIN: usize = 1 << 15;

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

    fn aabb(&self) -> Aabb {
        Aabb::new(
            DVec3::from_array(self.min.map(f64::from)),
            DVec3::from_array(self.max.map(f64::from)),
        )
    }

    fn set_box(&mut self, b: &Aabb) {
        let (min, max) = b.to_f32_outward();
        self.min = min;
        self.max = max;
    }
}

/// A blank node: the root's partner in its line (node 1), which nothing links to.
const PAD: Node = Node {
    min: [0.0; 3],
    max: [0.0; 3],
    first: 0,
    count: 0,
};

/// Two sibling nodes (or the root and [`PAD`]) in one cache line.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Pair([Node; 2]);

const _: () = assert!(std::mem::size_of::<Pair>() == 64);

/// The nodes, in pairs: node `i` is `pairs[i / 2][i % 2]`. Node 0 is the root and node
/// 1 is [`PAD`]; every node's children are nodes `2p` and `2p + 1` of some pair `p`.
#[derive(Clone, Debug, Default)]
struct Nodes(Vec<Pair>);

impl Nodes {
    /// The root alone (with its pad).
    fn with_root(root: Node, capacity: usize) -> Nodes {
        let mut pairs = Vec::with_capacity(capacity.div_ceil(2));
        pairs.push(Pair([root, PAD]));
        Nodes(pairs)
    }

    /// Nodes held, the pad included (0 for an empty hierarchy).
    fn len(&self) -> usize {
        2 * self.0.len()
    }

    fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Adds two siblings; answers the index of the first.
    fn push_pair(&mut self, a: Node, b: Node) -> usize {
        self.0.push(Pair([a, b]));
        self.len() - 2
    }

    /// Each node but the pad, with its index.
    fn enumerate(&self) -> impl Iterator<Item = (usize, &Node)> {
        self.0
            .iter()
            .flat_map(|p| &p.0)
            .enumerate()
            .filter(|&(i, _)| i != 1)
    }

    fn heap_bytes(&self) -> usize {
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

/// The hierarchy: nodes (root first) and the primitive order of the leaves.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Nodes,
    order: Vec<u32>,
}

/// Nodes waiting to be walked: first in, first out while they fit in a ring on the
/// stack (the walk is then breadth first, and allocates nothing); nodes that find the
/// ring full wait in a spill list, taken last in, first out once the ring is empty.
/// Every node pushed is popped once, whatever the order.
struct Frontier {
    ring: [u32; Frontier::RING],
    /// Pops so far from the ring (its head is `head % RING`).
    head: usize,
    /// Pushes so far to the ring.
    tail: usize,
    spill: Vec<u32>,
}

impl Frontier {
    /// Ring slots: more than the widest level of a query of a few hundred leaves.
    const RING: usize = 256;

    fn new() -> Frontier {
        Frontier {
            ring: [0; Frontier::RING],
            head: 0,
            tail: 0,
            spill: Vec::new(),
        }
    }

    #[inline]
    fn push(&mut self, i: u32) {
        if self.tail - self.head < Frontier::RING {
            self.ring[self.tail % Frontier::RING] = i;
            self.tail += 1;
        } else {
            self.spill.push(i);
        }
    }

    #[inline]
    fn pop(&mut self) -> Option<u32> {
        if self.head < self.tail {
            let i = self.ring[self.head % Frontier::RING];
            self.head += 1;
            Some(i)
        } else {
            self.spill.pop()
        }
    }
}

/// A box in `f32`, for the build: the primitives' boxes rounded outward, as the nodes
/// hold them. Rounding outward commutes with the union, so a node's box made from these
/// is the one the primitives' own boxes would give; the build's passes over the items
/// move half the bytes they would in `f64`.
#[derive(Clone, Copy, Debug)]
struct Box32 {
    min: Vec3,
    max: Vec3,
}

impl Box32 {
    const EMPTY: Box32 = Box32 {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    /// `b` rounded outward (empty stays empty).
    fn of(b: &Aabb) -> Box32 {
        let (min, max) = b.to_f32_outward();
        Box32 {
            min: Vec3::from_array(min),
            max: Vec3::from_array(max),
        }
    }

    fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    #[inline]
    fn union(&self, o: &Box32) -> Box32 {
        Box32 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    #[inline]
    fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// Half the surface area (0 when empty), in `f64`: the SAH weighs boxes by it.
    #[inline]
    fn half_area(&self) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        let d = (self.max - self.min).as_dvec3();
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// A primitive while building: its box and centroid (40 bytes).
#[derive(Clone, Copy)]
struct Item {
    bounds: Box32,
    centroid: Vec3,
    index: u32,
}

const _: () = assert!(std::mem::size_of::<Item>() == 40);

impl Item {
    /// Primitive `index`, of box `b`; an empty box is centred at the origin.
    fn new(index: usize, b: &Aabb) -> Item {
        let bounds = Box32::of(b);
        Item {
            bounds,
            centroid: if bounds.is_empty() {
                Vec3::ZERO
            } else {
                (bounds.min + bounds.max) * 0.5
            },
            index: index as u32,
        }
    }
}

impl Bvh {
    /// The hierarchy over `boxes` (one per primitive). Empty boxes (min > max) are
    /// kept but never met by a query.
    pub fn build(boxes: &[Aabb]) -> Bvh {
        Bvh::build_by(boxes.len(), |i| boxes[i])
    }

    /// The hierarchy over `n` primitives, `box_of(i)` the box of primitive `i` (for a
    /// caller whose boxes are not in one slice), as [`Bvh::build`] makes it. Many boxes
    /// are read on rayon's threads.
    pub fn build_by(n: usize, box_of: impl Fn(usize) -> Aabb + Sync) -> Bvh {
        if n == 0 {
            return Bvh::default();
        }
        let item = |i: usize| Item::new(i, &box_of(i));
        let (mut items, span) = if n <= PARALLEL_MIN {
            let items: Vec<Item> = (0..n).map(item).collect();
            let span = Span::of(&items);
            (items, span)
        } else {
            let mut items = Vec::with_capacity(n);
            (0..n)
                .into_par_iter()
                .map(item)
                .collect_into_vec(&mut items);
            let span = items
                .par_chunks(PARALLEL_MIN)
                .map(Span::of)
                .reduce(|| Span::EMPTY, |a, b| a.union(&b));
            (items, span)
        };
        // A hierarchy has about 0.7 nodes per primitive (leaves of about three), at
        // most two. A sequential build reserves one per primitive and gives back what
        // it did not use; a parallel one makes its node list to size (see
        // `split_parallel`).
        let mut nodes = Nodes::with_root(PAD, if n <= PARALLEL_MIN { n + 2 } else { 0 });
        split_parallel(&mut nodes, 0, &mut items, 0, span);
        nodes.0.shrink_to_fit();
        // Collected from a borrow: collected from `items` itself, the order would reuse
        // (and keep) the items' ten times larger buffer.
        Bvh {
            nodes,
            order: items.iter().map(|it| it.index).collect(),
        }
    }

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

/// Fills node `at` over `items` (which start at leaf position `offset`) and its
/// subtree, splitting by binned SAH.
fn split(nodes: &mut Nodes, at: usize, items: &mut [Item], offset: usize, span: Span) {
    if let Some((mid, l, r)) = divide(nodes, at, items, offset, span) {
        let first = nodes[at].first as usize;
        let (left, right) = items.split_at_mut(mid);
        split(nodes, first, left, offset, l);
        split(nodes, first + 1, right, offset + mid, r);
    }
}

/// The box over some items and the box over their centroids.
#[derive(Clone, Copy, Debug)]
struct Span {
    bounds: Box32,
    centroids: Box32,
}

impl Span {
    const EMPTY: Span = Span {
        bounds: Box32::EMPTY,
        centroids: Box32::EMPTY,
    };

    /// The span of `items`, by one pass over them.
    fn of(items: &[Item]) -> Span {
        let mut span = Span::EMPTY;
        for it in items {
            span.add(it);
        }
        span
    }

    #[inline]
    fn add(&mut self, it: &Item) {
        self.bounds = self.bounds.union(&it.bounds);
        self.centroids.grow(it.centroid);
    }

    fn union(&self, o: &Span) -> Span {
        Span {
            bounds: self.bounds.union(&o.bounds),
            centroids: self.centroids.union(&o.centroids),
        }
    }
}

/// Gives node `at` its box over `items` (which start at leaf position `offset`; `span`
/// is theirs) and either makes it a leaf (answering `None`) or partitions `items` by
/// binned SAH, pushes its two children (blank, adjacent, at `nodes[at].first`) and
/// answers where the right child's items start and the two children's spans (from the
/// bins, without another pass over the items).
fn divide(
    nodes: &mut Nodes,
    at: usize,
    items: &mut [Item],
    offset: usize,
    span: Span,
) -> Option<(usize, Span, Span)> {
    let Span {
        bounds,
        centroids: cbounds,
    } = span;
    nodes[at].min = bounds.min.to_array();
    nodes[at].max = bounds.max.to_array();
    let count = items.len() as u32;
    let leaf = |nodes: &mut Nodes| {
        nodes[at].first = offset as u32;
        nodes[at].count = count;
    };
    if items.len() <= LEAF_MAX {
        leaf(nodes);
        return None;
    }
    let extent = cbounds.max - cbounds.min;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = if extent[axis] > 0.0 {
        sah_split(items, axis, cbounds.min[axis], extent[axis])
    } else {
        None
    };
    let split = match mid {
        Some(split) => split,
        None if items.len() <= LEAF_LIMIT && extent[axis] <= 0.0 => {
            // Coincident centroids in a small set: a leaf (a little over the limit).
            leaf(nodes);
            return None;
        }
        None => {
            // No split pays off by SAH, but the leaf is too big: split at the median.
            let m = items.len() / 2;
            items.select_nth_unstable_by(m, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
            (m, Span::of(&items[..m]), Span::of(&items[m..]))
        }
    };
    let blank = nodes[at];
    let first = nodes.push_pair(blank, blank);
    nodes[at].first = first as u32;
    nodes[at].count = 0;
    Some(split)
}

/// [`split`], with the two subtrees of a large node built at once on rayon's threads
/// (each into its own node list, spliced in afterwards). The hierarchy is the same as
/// [`split`] builds, node for node, up to the order of the nodes in memory.
fn split_parallel(nodes: &mut Nodes, at: usize, items: &mut [Item], offset: usize, span: Span) {
    if items.len() <= PARALLEL_MIN {
        split(nodes, at, items, offset, span);
        return;
    }
    // Split this node alone: its children are made, then filled below.
    let mut top = Nodes::with_root(nodes[at], 4);
    let (mid, l_span, r_span) = match divide(&mut top, 0, items, offset, span) {
        Some(split) => split,
        None => {
            nodes[at] = top[0];
            return;
        }
    };
    let (left, right) = items.split_at_mut(mid);
    let blank = top[2];
    let build = |items: &mut [Item], offset: usize, span: Span| {
        let mut sub = Nodes::with_root(blank, items.len() + 2);
        split_parallel(&mut sub, 0, items, offset, span);
        sub
    };
    let (l, r) = rayon::join(
        || build(left, offset, l_span),
        || build(right, offset + mid, r_span),
    );
    // Children side by side, then the rest of each subtree after them (each without
    // its root's pair).
    let l_base = nodes.len() + 2;
    let r_base = l_base + l.len() - 2;
    let l = relocated(l, l_base);
    let r = relocated(r, r_base);
    nodes.0.reserve_exact(l.0.len() + r.0.len() - 1);
    let first = nodes.push_pair(l.0[0].0[0], r.0[0].0[0]);
    nodes[at] = top[0];
    nodes[at].first = first as u32;
    nodes.0.extend_from_slice(&l.0[1..]);
    nodes.0.extend_from_slice(&r.0[1..]);
}

/// A subtree built on its own (root at 0, its pad at 1) with its child links moved to
/// where it is spliced in: its node `i > 1` at `base + i − 2` (no link leads to its
/// root, which the caller places beside its sibling). `base` is even, so siblings stay
/// paired.
fn relocated(mut sub: Nodes, base: usize) -> Nodes {
    for n in sub.0.iter_mut().flat_map(|p| &mut p.0) {
        if !n.is_leaf() && n.first >= 2 {
            n.first = (base + n.first as usize - 2) as u32;
        }
    }
    sub
}

/// The SAH split of `items` along `axis`: partitions them and answers the split point,
/// or `None` when every centroid falls in one bin.
fn sah_split(
    items: &mut [Item],
    axis: usize,
    cmin: f32,
    extent: f32,
) -> Option<(usize, Span, Span)> {
    let scale = BINS as f32 / extent;
    let bin_of = |c: f32| (((c - cmin) * scale) as usize).min(BINS - 1);
    let mut bins = [(Span::EMPTY, 0usize); BINS];
    for it in items.iter() {
        let b = &mut bins[bin_of(it.centroid[axis])];
        b.0.add(it);
        b.1 += 1;
    }
    // Sweep from the right, then from the left, to cost each of the BINS − 1 planes.
    let mut right_area = [0.0f64; BINS];
    let mut acc = Box32::EMPTY;
    for i in (1..BINS).rev() {
        acc = acc.union(&bins[i].0.bounds);
        right_area[i] = acc.half_area();
    }
    let mut best: Option<(f32, usize)> = None;
    let mut acc = Box32::EMPTY;
    let mut left_count = 0;
    for i in 0..BINS - 1 {
        acc = acc.union(&bins[i].0.bounds);
        left_count += bins[i].1;
        let right_count = items.len() - left_count;
        if left_count == 0 || right_count == 0 {
            continue;
        }
        let cost =
            (acc.half_area() * left_count as f64 + right_area[i + 1] * right_count as f64) as f32;
        if best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, i));
        }
    }
    let (_, plane) = best?;
    // Partition in place: bins 0..=plane to the left.
    let mut l = 0;
    for r in 0..items.len() {
        if bin_of(items[r].centroid[axis]) <= plane {
            items.swap(l, r);
            l += 1;
        }
    }
    let side = |range: &[(Span, usize)]| range.iter().fold(Span::EMPTY, |s, b| s.union(&b.0));
    (l > 0 && l < items.len()).then(|| (l, side(&bins[..=plane]), side(&bins[plane + 1..])))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxes(n: usize) -> Vec<Aabb> {
        // A deterministic scatter of small boxes.
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let c = DVec3::new(rnd(), rnd(), rnd()) * 100.0;
                let h = DVec3::new(rnd(), rnd(), rnd()) + 0.01;
                Aabb::new(c - h, c + h)
            })
            .collect()
    }

    /// The hierarchy [`split`] builds on one thread.
    fn sequential(bs: &[Aabb]) -> Bvh {
        let mut items: Vec<Item> = bs
            .iter()
            .enumerate()
            .map(|(i, b)| Item::new(i, b))
            .collect();
        let mut nodes = Nodes::with_root(PAD, 0);
        let span = Span::of(&items);
        split(&mut nodes, 0, &mut items, 0, span);
        Bvh {
            nodes,
            order: items.iter().map(|it| it.index).collect(),
        }
    }

    /// Whether the subtrees at `i` of `a` and `j` of `b` are the same, node for node.
    fn same_tree(a: &Bvh, i: usize, b: &Bvh, j: usize) -> bool {
        let (m, n) = (a.nodes[i], b.nodes[j]);
        if m.min != n.min || m.max != n.max || m.count != n.count {
            return false;
        }
        if m.is_leaf() {
            return m.first == n.first;
        }
        let (ma, nb) = (m.first as usize, n.first as usize);
        same_tree(a, ma, b, nb) && same_tree(a, ma + 1, b, nb + 1)
    }

    #[test]
    fn the_parallel_build_makes_the_sequential_hierarchy() {
        let bs = boxes(5 * PARALLEL_MIN);
        let parallel = Bvh::build(&bs);
        let one = sequential(&bs);
        assert_eq!(parallel.order, one.order);
        assert_eq!(parallel.nodes.len(), one.nodes.len());
        assert!(same_tree(&parallel, 0, &one, 0));
        // Every link stays inside the node list, and children sit inside their parent.
        for (_, n) in parallel.nodes.enumerate().filter(|(_, n)| !n.is_leaf()) {
            for c in [n.first as usize, n.first as usize + 1] {
                let c = parallel.nodes[c];
                assert!((0..3).all(|k| n.min[k] <= c.min[k] && c.max[k] <= n.max[k]));
            }
        }
    }

    /// A built hierarchy holds what it needs and no build leftovers: one order entry per
    /// primitive, and room for its nodes only, built on one thread or on several.
    #[test]
    fn a_built_hierarchy_keeps_no_build_leftovers() {
        for n in [1, 7, 1000, 3 * PARALLEL_MIN] {
            let bvh = Bvh::build(&boxes(n));
            assert_eq!(bvh.order.capacity(), n, "{n} boxes");
            assert_eq!(bvh.nodes.0.capacity(), bvh.nodes.0.len(), "{n} boxes");
        }
    }

    #[test]
    fn every_box_near_a_point_is_visited() {
        let bs = boxes(5000);
        let bvh = Bvh::build(&bs);
        let mut seen = vec![false; bs.len()];
        for k in 0..bs.len() {
            assert!(!seen[bvh.order()[k] as usize]);
            seen[bvh.order()[k] as usize] = true;
        }
        let p = DVec3::new(50.0, 40.0, 60.0);
        let r2 = 64.0;
        let mut got: Vec<u32> = Vec::new();
        bvh.within(p, r2, |k| {
            let i = bvh.order()[k];
            if bs[i as usize].distance_squared(p) <= r2 {
                got.push(i);
            }
        });
        got.sort_unstable();
        let want: Vec<u32> = (0..bs.len() as u32)
            .filter(|&i| bs[i as usize].distance_squared(p) <= r2)
            .collect();
        assert!(!want.is_empty());
        assert_eq!(got, want);
    }

    #[test]
    fn a_walk_wider_than_the_ring_visits_every_leaf_position_once() {
        // A box over everything: every level is in the frontier at once, far more than
        // the ring holds, so the spill list carries the rest.
        let bs = boxes(20_000);
        let bvh = Bvh::build(&bs);
        let leaves = bvh.leaves().count();
        assert!(leaves > 2 * Frontier::RING, "{leaves} leaves");
        let mut visits = vec![0u32; bs.len()];
        bvh.overlapping(DVec3::splat(-10.0), DVec3::splat(110.0), |k| visits[k] += 1);
        assert!(visits.iter().all(|&v| v == 1));
        // A walk told to stop visits nothing more.
        let mut seen = 0;
        bvh.overlapping_until(DVec3::splat(-10.0), DVec3::splat(110.0), |_| {
            seen += 1;
            seen < 1000
        });
        assert_eq!(seen, 1000);
    }

    #[test]
    fn the_frontier_pops_every_push_once_in_and_beyond_its_ring() {
        let mut f = Frontier::new();
        let n = 3 * Frontier::RING as u32;
        let mut popped = Vec::new();
        // Interleaved pushes and pops, so that the ring wraps and then overflows.
        for i in 0..n {
            f.push(i);
            if i % 3 == 0 {
                popped.extend(f.pop());
            }
        }
        while let Some(i) = f.pop() {
            popped.push(i);
        }
        popped.sort_unstable();
        assert_eq!(popped, (0..n).collect::<Vec<_>>());
    }

    #[test]
    fn nearest_and_ray_walks_find_the_brute_force_answer() {
        let bs = boxes(3000);
        let bvh = Bvh::build(&bs);
        let p = DVec3::new(10.0, 90.0, 30.0);
        let best = bvh.nearest(p, f64::INFINITY, |k, best| {
            best.min(bs[bvh.order()[k] as usize].distance_squared(p))
        });
        let want = bs
            .iter()
            .map(|b| b.distance_squared(p))
            .fold(f64::INFINITY, f64::min);
        assert_eq!(best, want);
        let d = DVec3::new(1.0, -0.3, 0.2).normalize();
        let t = bvh.ray(p, d, f64::INFINITY, |k, t| {
            bs[bvh.order()[k] as usize]
                .ray_entry(p, d)
                .map_or(t, |x| t.min(x))
        });
        let want = bs
            .iter()
            .filter_map(|b| b.ray_entry(p, d))
            .fold(f64::INFINITY, f64::min);
        assert_eq!(t, want);
    }

    /// `touch_path` reads the ancestors of a leaf, nearest first, as far as asked and no
    /// further than the root.
    #[test]
    fn touch_path_reads_the_ancestors_up_to_the_root() {
        let bvh = Bvh::build(&boxes(2000));
        let parents = bvh.parents();
        let mut deepest = 0;
        for &leaf in bvh.leaf_of_positions().iter().step_by(37) {
            let mut path = Vec::new();
            let mut n = leaf as usize;
            while n != 0 {
                n = parents[n] as usize;
                path.push(u64::from(bvh.node(n).first));
            }
            deepest = deepest.max(path.len());
            for levels in 0..=path.len() + 2 {
                let want = path.iter().take(levels).fold(0, |acc, f| acc ^ f);
                assert_eq!(bvh.touch_path(&parents, leaf, levels), want, "leaf {leaf}");
            }
        }
        assert!(deepest > 4, "a hierarchy {deepest} deep");
        assert_eq!(bvh.touch_path(&parents, 0, 3), 0);
    }

    #[test]
    fn refit_keeps_every_box_inside_its_ancestors() {
        let mut bs = boxes(2000);
        let mut bvh = Bvh::build(&bs);
        let parents = bvh.parents();
        let leaves = bvh.leaf_of_positions();
        let order = bvh.order().to_vec();
        let mut pos_of = vec![0usize; bs.len()];
        for (k, &i) in order.iter().enumerate() {
            pos_of[i as usize] = k;
        }
        for i in (0..bs.len()).step_by(7) {
            bs[i] = Aabb::new(bs[i].min + 30.0, bs[i].max + 30.0);
            let k = pos_of[i];
            bvh.refit(&parents, leaves[k], |k| bs[order[k] as usize]);
        }
        for (k, &i) in order.iter().enumerate() {
            let mut n = leaves[k] as usize;
            loop {
                let node = bvh.node(n).aabb();
                assert!(node.contains(&bs[i as usize]), "position {k} node {n}");
                if n == 0 {
                    break;
                }
                n = parents[n] as usize;
            }
        }
    }
}
