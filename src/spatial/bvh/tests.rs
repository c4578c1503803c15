use glam::DVec3;

use super::Bvh;
use super::build::{Item, PARALLEL_MIN, Span, split};
use super::node::{Nodes, PAD};
use super::walk::Frontier;
use crate::spatial::aabb::Aabb;

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
