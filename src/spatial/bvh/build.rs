//! Building a hierarchy: binned surface-area heuristic over the primitives' boxes
//! (rounded outward to `f32`), the two subtrees of a large node built at once on rayon's
//! threads.

use glam::Vec3;
use rayon::prelude::*;

use super::Bvh;
use super::node::{Nodes, PAD};
use crate::spatial::aabb::Aabb;

/// Primitives per leaf, as a rule.
const LEAF_MAX: usize = 4;
/// Primitives per leaf at most (a small set with coincident centroids stays whole).
pub const LEAF_LIMIT: usize = 2 * LEAF_MAX;
/// SAH bins per axis.
const BINS: usize = 12;
/// Primitives under a node above which its two subtrees are built in parallel.
pub(super) const PARALLEL_MIN: usize = 1 << 15;

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
pub(super) struct Item {
    bounds: Box32,
    centroid: Vec3,
    pub(super) index: u32,
}

const _: () = assert!(std::mem::size_of::<Item>() == 40);

impl Item {
    /// Primitive `index`, of box `b`; an empty box is centred at the origin.
    pub(super) fn new(index: usize, b: &Aabb) -> Item {
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
}

/// Fills node `at` over `items` (which start at leaf position `offset`) and its
/// subtree, splitting by binned SAH.
pub(super) fn split(nodes: &mut Nodes, at: usize, items: &mut [Item], offset: usize, span: Span) {
    if let Some((mid, l, r)) = divide(nodes, at, items, offset, span) {
        let first = nodes[at].first as usize;
        let (left, right) = items.split_at_mut(mid);
        split(nodes, first, left, offset, l);
        split(nodes, first + 1, right, offset + mid, r);
    }
}

/// The box over some items and the box over their centroids.
#[derive(Clone, Copy, Debug)]
pub(super) struct Span {
    bounds: Box32,
    centroids: Box32,
}

impl Span {
    const EMPTY: Span = Span {
        bounds: Box32::EMPTY,
        centroids: Box32::EMPTY,
    };

    /// The span of `items`, by one pass over them.
    pub(super) fn of(items: &[Item]) -> Span {
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
