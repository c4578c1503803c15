//! The world-level index: one entry per body (its shape, its world pose and the world
//! bounds of its shape) under a hierarchy of those bounds.
//!
//! Kept in step with the world by [`Spatial::sync`]: a body that moved (or whose
//! supart moved) gets new bounds and its leaf is refitted, which costs a walk up one
//! path of the hierarchy; a body whose geometry changed gets a new shape; a new body
//! waits in a short list of loose entries; a removed body's entry is emptied. The
//! hierarchy is built anew when those add up (many loose or dead entries, or refits
//! that have doubled its surface area): [`Spatial::worn`].
//!
//! That rebuild can be done in place ([`Spatial::sync`]) or elsewhere while the worn
//! index goes on answering: [`Spatial::update`] brings the index up without rebuilding,
//! [`Spatial::fork`] copies its bodies out, [`Fork::build`] makes the fresh index from
//! them (on any thread, holding no lock), and `update` brings that one up to the worn
//! index's revision before it takes its place. A worn index answers as exactly as a fresh
//! one; only more slowly.

use std::collections::HashMap;
use std::sync::Arc;

use glam::DVec3;
use imbl::OrdMap;
use rayon::prelude::*;

use super::aabb::Aabb;
use super::bvh::Bvh;
use super::hits::{Hits, Order};
use super::hull::{HullRef, Hulls};
use super::query::{
    BoxAnswer, BoxQuery, Detail, Found, Nearest, QueryError, RayHit, SphereAnswer, SphereQuery,
    validate_point, validate_ray,
};
use super::reach::{self, Features, cull_radius2};
use super::shape::BodyShape;
use crate::model::{BodyId, BodyNode, Pose, World};

/// Loose entries (not yet under the hierarchy) tolerated before a rebuild.
const LOOSE_MAX: usize = 64;
/// Numbers held by released hull records tolerated before a rebuild (besides half of
/// all).
const HULL_GARBAGE_MIN: usize = 1 << 16;
/// Bodies a query at `features` detail reads ahead at a time (see
/// [`Spatial::read_ahead`]): enough for their misses to overlap, few enough (about 64 KB
/// for boxes) to stay in cache until they are tested.
const READ_AHEAD_BODIES: usize = 64;
/// Ancestors of a moved body's leaf read ahead of its refit (see [`Bvh::touch_path`]):
/// a little more than a move changes (2.7 above the leaf, on average, for the moves of
/// `spatial-peers profile-moves`).
const REFIT_PATH_AHEAD: usize = 4;
/// The most primitives a hierarchy leaf holds.
const LEAF_BOXES: usize = super::bvh::LEAF_LIMIT;

/// One body in the index.
///
/// Laid out for the queries: the fields a query reads of every candidate it tests through
/// its entry (bounds, record) fill the first cache line, those a hit reads (id, name)
/// begin the second. A move reads and writes the entry (with the record and one path of
/// the hierarchy), never the shape: what it needs of the shape is copied here.
#[repr(C, align(64))]
struct Entry {
    /// World bounds of the shape (empty for a removed body).
    bounds: Aabb,
    /// The body's record among the index's [`Hulls`], when it is small and convex.
    hull: Option<HullRef>,
    id: BodyId,
    /// The body's name, kept here so that answers need not look it up in the world.
    name: Option<Box<str>>,
    shape: Arc<BodyShape>,
    pose: Pose,
    /// The shape's bounds in the body's frame.
    local: Aabb,
    /// The address of the body the shape was built from (`Arc::as_ptr`), to tell an
    /// unchanged body without reading the shape. The shape holds that body, so the
    /// address is not reused while the entry lives.
    body: usize,
    /// The hierarchy leaf holding the entry, or `u32::MAX` while it is loose.
    leaf: u32,
}

// The layout the queries rely on: bounds and record in the first line, the id at the
// start of the second; and the whole entry in four lines.
const _: () = assert!(
    std::mem::offset_of!(Entry, hull) + std::mem::size_of::<Option<HullRef>>() <= 64
        && std::mem::offset_of!(Entry, id) == 64
        && std::mem::size_of::<Entry>() == 256
);

/// What a sphere query at `bodies` detail reads of an entry whose record settles it:
/// kept densely beside the entries (same index), so that such a query reads the record
/// and not the entry.
#[derive(Clone, Copy, Debug)]
struct Quick {
    /// The entry's record, when it has one (and is not removed).
    hull: Option<HullRef>,
    id: BodyId,
    /// Whether the body has a name (read from the entry for a hit).
    named: bool,
}

impl Quick {
    fn of(e: &Entry) -> Quick {
        Quick {
            hull: e.hull.filter(|_| !e.bounds.is_empty()),
            id: e.id,
            named: e.name.is_some(),
        }
    }
}

/// How much work a [`Spatial::sync`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SyncStats {
    /// Bodies whose shape was built.
    pub shaped: usize,
    /// Bodies that moved.
    pub moved: usize,
    /// Bodies added.
    pub added: usize,
    /// Bodies removed.
    pub removed: usize,
    /// Whether the hierarchy was rebuilt.
    pub rebuilt: bool,
}

/// What a fresh index is built from, taken from a live one at no cost
/// ([`Spatial::fork`]) and built away from it ([`Fork::build`]): the index's world and its
/// bodies' shapes, shared, so that no shape is built again.
pub struct Fork {
    world: Arc<World>,
    shapes: OrdMap<BodyId, Arc<BodyShape>>,
    generation: u64,
}

impl Fork {
    /// The revision the fork describes (that of the index it was taken from).
    pub fn revision(&self) -> u64 {
        self.world.revision()
    }

    /// The [generation](Spatial::generation) of the index it was taken from.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// The fresh index of the fork's world, one generation past the index it was taken
    /// from. A body's shape is the index's when it was built from the very same body
    /// (always, for a fork of an index at its own world), else built here.
    pub fn build(self) -> Spatial {
        Spatial::build_reusing(self.world, &self.shapes, self.generation + 1)
    }
}

/// The spatial index of one world revision.
pub struct Spatial {
    world: Arc<World>,
    entries: Vec<Entry>,
    /// [`Quick::of`] each entry, same index.
    quick: Vec<Quick>,
    by_id: HashMap<BodyId, u32>,
    /// The hierarchy over the entries' bounds. Its order is the identity: leaf position
    /// `k` holds entry `k` (`build_hierarchy` lays the entries out so).
    bvh: Bvh,
    /// Parent of each hierarchy node.
    parents: Vec<u32>,
    /// Entries not under the hierarchy yet.
    loose: Vec<u32>,
    /// The records of the small convex bodies, in leaf order as of the last build.
    hulls: Hulls,
    /// Entries emptied by removals.
    dead: usize,
    /// Surface area gained by refits since the last build, and the area then.
    growth: f64,
    built_area: f64,
    /// Hierarchies built: 0 for the first, one more for each rebuild.
    generation: u64,
    /// Each live body's shape (as in its entry), shared with the forks taken.
    shapes: OrdMap<BodyId, Arc<BodyShape>>,
}

impl Spatial {
    /// The index of `world`, shapes built in parallel.
    pub fn build(world: Arc<World>) -> Spatial {
        Spatial::build_reusing(world, &OrdMap::new(), 0)
    }

    /// The index of `world`, hierarchy generation `generation`, with each body's shape
    /// taken from `shapes` when it was built from the very same body, else built (in
    /// parallel).
    fn build_reusing(
        world: Arc<World>,
        shapes: &OrdMap<BodyId, Arc<BodyShape>>,
        generation: u64,
    ) -> Spatial {
        // Each body's node is read once, here: its pose and name come from it, not from
        // looking the body up again.
        let bodies: Vec<(BodyId, &BodyNode)> = world
            .bodies()
            .filter(|(_, n)| n.body.vertex_count() > 0)
            .collect();
        let built: Vec<(Arc<BodyShape>, bool)> = bodies
            .par_iter()
            .map(|(id, n)| match shapes.get(id) {
                Some(s) if Arc::ptr_eq(s.body(), &n.body) => (s.clone(), true),
                _ => (Arc::new(BodyShape::build(n.body.clone())), false),
            })
            .collect();
        // The map is taken whole when it holds exactly the shapes used (a fork's always
        // does), else made anew.
        let whole = shapes.len() == built.len() && built.iter().all(|(_, reused)| *reused);
        let mut s = Spatial {
            world: world.clone(),
            entries: Vec::with_capacity(bodies.len()),
            quick: Vec::new(),
            by_id: HashMap::new(),
            bvh: Bvh::default(),
            parents: Vec::new(),
            loose: Vec::new(),
            hulls: Hulls::default(),
            dead: 0,
            growth: 0.0,
            built_area: 0.0,
            generation,
            shapes: if whole { shapes.clone() } else { OrdMap::new() },
        };
        for ((id, n), (shape, _)) in bodies.into_iter().zip(built) {
            if !whole {
                s.shapes.insert(id, shape.clone());
            }
            let pose = world.world_pose_of(id, n);
            s.entries.push(entry(id, n.name.as_deref(), shape, pose));
        }
        s.build_hierarchy();
        s
    }

    /// The world revision the index describes.
    pub fn revision(&self) -> u64 {
        self.world.revision()
    }

    /// The world the index describes.
    pub fn world(&self) -> &Arc<World> {
        &self.world
    }

    /// Bodies indexed.
    pub fn len(&self) -> usize {
        self.by_id.len()
    }

    /// Whether no body is indexed.
    pub fn is_empty(&self) -> bool {
        self.by_id.is_empty()
    }

    /// Heap bytes held by the index, shapes included (the bodies themselves are the
    /// world's; of the map of shapes, its entries are counted, not its nodes' overhead).
    pub fn heap_bytes(&self) -> usize {
        let shapes: usize = self
            .entries
            .iter()
            .filter(|e| !e.bounds.is_empty())
            .map(|e| e.shape.heap_bytes())
            .sum();
        shapes
            + self.entries.capacity() * std::mem::size_of::<Entry>()
            + self.quick.capacity() * std::mem::size_of::<Quick>()
            + self.by_id.capacity() * 16
            + self.bvh.heap_bytes()
            + self.hulls.heap_bytes()
            + self.parents.capacity() * 4
            + self.shapes.len() * std::mem::size_of::<(BodyId, Arc<BodyShape>)>()
    }

    /// How many times the hierarchy was built: 0 for an index made by [`Spatial::build`],
    /// one more for each rebuild in place, and one more than its origin's for an index made
    /// by [`Fork::build`]. A fork remembers its origin's generation, so that whoever
    /// builds it can tell whether the origin was rebuilt in the meantime.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Loose entries: bodies added since the hierarchy was built, which every query
    /// tests one by one.
    pub fn loose(&self) -> usize {
        self.loose.len()
    }

    /// Whether the hierarchy has worn enough to be built anew: many loose or removed
    /// entries, refits that have doubled its surface area, or many released records.
    pub fn worn(&self) -> bool {
        self.loose.len() > LOOSE_MAX
            || self.dead > LOOSE_MAX.max(self.entries.len() / 4)
            || self.growth > self.built_area.max(f64::MIN_POSITIVE)
            || self.hulls.garbage() > HULL_GARBAGE_MIN.max(self.hulls.size() / 2)
    }

    /// What a fresh index of the index's world is built from, away from this one
    /// ([`Fork::build`]): the world and the shapes, shared (constant time, no copy).
    pub fn fork(&self) -> Fork {
        Fork {
            world: self.world.clone(),
            shapes: self.shapes.clone(),
            generation: self.generation,
        }
    }

    /// Builds the hierarchy anew in place, over the live entries, and moves to the next
    /// generation. The answers are unchanged; a worn index answers faster after it.
    pub fn rebuild(&mut self) {
        self.build_hierarchy();
        self.generation += 1;
    }

    /// Brings the index to `world`, and builds the hierarchy anew in place when it has
    /// [`worn`](Spatial::worn). `touched` is as for [`Spatial::update`].
    pub fn sync(&mut self, world: Arc<World>, touched: Option<&[BodyId]>) -> SyncStats {
        let mut stats = self.update(world, touched);
        if self.worn() {
            self.rebuild();
            stats.rebuilt = true;
        }
        stats
    }

    /// Brings the index to `world` without rebuilding the hierarchy (the answers are
    /// exact either way; a [`worn`](Spatial::worn) one is slower). `touched` lists the
    /// bodies changed since the index's revision (the parts of one whose world pose
    /// changed, or which has no entry, are followed); `None` compares every body.
    ///
    /// Precondition: with `touched`, every body added, removed, moved, re-parented,
    /// renamed or edited since the index's revision is listed (or is a part of one
    /// listed).
    pub fn update(&mut self, world: Arc<World>, touched: Option<&[BodyId]>) -> SyncStats {
        let mut stats = SyncStats::default();
        match touched {
            Some(ids) => {
                let mut stack: Vec<BodyId> = ids.to_vec();
                while let Some(id) = stack.pop() {
                    if let Some(parts) = self.refresh(&world, id, &mut stats) {
                        stack.extend(parts.iter().copied());
                    }
                }
            }
            None => {
                let ids: Vec<BodyId> = world.bodies().map(|(id, _)| id).collect();
                for id in ids {
                    self.refresh(&world, id, &mut stats);
                }
                let gone: Vec<BodyId> = self
                    .by_id
                    .keys()
                    .copied()
                    .filter(|id| world.node(*id).is_none())
                    .collect();
                for id in gone {
                    self.refresh(&world, id, &mut stats);
                }
            }
        }
        self.world = world;
        stats
    }

    /// Brings body `id`'s entry in line with `world`. Answers the body's parts when they
    /// may have moved with it: not when it has an entry whose world pose is unchanged,
    /// nor when it is not in `world`. The body's node is looked up in the world once; a
    /// body that is the one its entry was made from is not read (it has geometry, or it
    /// would have no entry).
    fn refresh<'w>(
        &mut self,
        world: &'w World,
        id: BodyId,
        stats: &mut SyncStats,
    ) -> Option<&'w imbl::Vector<BodyId>> {
        let found = world.node(id);
        let parts = found.map(|n| &n.parts);
        let at = self.by_id.get(&id).copied();
        // Whether the body is the very one the entry was made from.
        let kept = found
            .zip(at)
            .is_some_and(|(n, i)| self.entries[i as usize].body == Arc::as_ptr(&n.body) as usize);
        let node = found.filter(|n| kept || n.body.vertex_count() > 0);
        match (node, at) {
            (None, None) => parts,
            (None, Some(i)) => {
                self.by_id.remove(&id);
                self.shapes.remove(&id);
                let e = &mut self.entries[i as usize];
                e.bounds = Aabb::EMPTY;
                if let Some(h) = e.hull.take() {
                    self.hulls.release(h);
                }
                self.quick[i as usize] = Quick::of(e);
                self.refit(i);
                self.dead += 1;
                stats.removed += 1;
                parts
            }
            (Some(n), None) => {
                let pose = world.world_pose_of(id, n);
                let shape = Arc::new(BodyShape::build(n.body.clone()));
                self.shapes.insert(id, shape.clone());
                let i = self.entries.len() as u32;
                let mut e = entry(id, n.name.as_deref(), shape, pose);
                e.hull = self.hulls.add(&e.shape, &e.pose);
                self.quick.push(Quick::of(&e));
                self.entries.push(e);
                self.by_id.insert(id, i);
                self.loose.push(i);
                stats.added += 1;
                stats.shaped += 1;
                parts
            }
            (Some(n), Some(i)) => {
                let pose = world.world_pose_of(id, n);
                let e = &mut self.entries[i as usize];
                let renamed = e.name.as_deref() != n.name.as_deref();
                if renamed {
                    e.name = n.name.as_deref().map(Box::from);
                }
                let reshaped = !kept;
                if reshaped {
                    let shape = Arc::new(BodyShape::build(n.body.clone()));
                    self.shapes.insert(id, shape.clone());
                    e.set_shape(shape);
                    stats.shaped += 1;
                }
                let moved = e.pose != pose;
                if reshaped || moved {
                    let hull = e.hull;
                    e.place(pose);
                    // A moved body keeps its record, or its lack of one (its shape is not
                    // read); a reshaped one gets a new record.
                    e.hull = match hull {
                        Some(h) if !reshaped => {
                            self.hulls.pose(h, &e.shape, &e.pose);
                            Some(h)
                        }
                        None if !reshaped => None,
                        _ => {
                            if let Some(h) = hull {
                                self.hulls.release(h);
                            }
                            self.hulls.add(&e.shape, &e.pose)
                        }
                    };
                    if !reshaped {
                        stats.moved += 1;
                    }
                    self.refit(i);
                }
                // A move leaves what a query reads first (record, id, name) as it was.
                if renamed || reshaped {
                    self.quick[i as usize] = Quick::of(&self.entries[i as usize]);
                }
                parts.filter(|_| moved)
            }
        }
    }

    /// The name of the body in entry `i`, if it has one.
    fn name_of(&self, i: u32) -> Option<&str> {
        self.entries[i as usize].name.as_deref()
    }

    /// Refits the hierarchy after entry `i`'s bounds changed.
    fn refit(&mut self, i: u32) {
        let leaf = self.entries[i as usize].leaf;
        if leaf == u32::MAX {
            return;
        }
        // The path up is read first, its misses overlapping those of the leaf's boxes.
        let path = self.bvh.touch_path(&self.parents, leaf, REFIT_PATH_AHEAD);
        std::hint::black_box(path);
        // The leaf's boxes are copied out: `refit` mutates the nodes. Leaf position k
        // holds entry k (see `build_hierarchy`).
        let n = *self.bvh.node(leaf as usize);
        let first = n.first as usize;
        let mut boxes = [Aabb::EMPTY; LEAF_BOXES];
        for (slot, e) in boxes
            .iter_mut()
            .zip(&self.entries[first..first + n.count as usize])
        {
            *slot = e.bounds;
        }
        self.growth += self.bvh.refit(&self.parents, leaf, |k| boxes[k - first]);
    }

    /// Builds the hierarchy anew over the live entries (dropping removed ones), and lays
    /// the entries out in its leaf order, so that bodies near each other in space are
    /// near each other in memory.
    fn build_hierarchy(&mut self) {
        self.entries.retain(|e| !e.bounds.is_empty());
        let boxes: Vec<Aabb> = self.entries.iter().map(|e| e.bounds).collect();
        self.bvh = Bvh::build(&boxes);
        let mut slots: Vec<Option<Entry>> = std::mem::take(&mut self.entries)
            .into_iter()
            .map(Some)
            .collect();
        self.entries = self
            .bvh
            .order()
            .iter()
            .filter_map(|&i| slots[i as usize].take())
            .collect();
        self.bvh.identity_order();
        self.hulls = Hulls::default();
        for e in &mut self.entries {
            e.hull = self.hulls.add(&e.shape, &e.pose);
        }
        self.hulls.shrink_to_fit();
        self.quick = self.entries.iter().map(Quick::of).collect();
        self.by_id = self
            .entries
            .iter()
            .enumerate()
            .map(|(i, e)| (e.id, i as u32))
            .collect();
        self.parents = self.bvh.parents();
        for (e, leaf) in self.entries.iter_mut().zip(self.bvh.leaf_of_positions()) {
            e.leaf = leaf;
        }
        self.loose.clear();
        self.dead = 0;
        self.growth = 0.0;
        self.built_area = self.bvh.total_half_area();
    }

    /// The bodies reaching into a ball, with what of them is inside it.
    pub fn sphere(&self, q: &SphereQuery) -> Result<SphereAnswer, QueryError> {
        q.validate()?;
        let r2 = cull_radius2(q.radius);
        // The candidates are gathered first and what their tests read is read ahead in
        // loops of independent reads (their records at `bodies` detail, their shapes
        // above it), so that the cache misses of a query overlap instead of following
        // one another through the tests. Leaf position k holds entry k (see
        // `build_hierarchy`).
        let mut candidates: Vec<u32> = Vec::with_capacity(256);
        self.bvh.within(q.center, r2, |k| candidates.push(k as u32));
        candidates.extend_from_slice(&self.loose);
        let features = q.detail != Detail::Bodies;
        if features {
            // Only the bodies whose bounds reach the ball are tested: their shapes are
            // read ahead, a batch at a time (see `read_ahead`).
            candidates
                .retain(|&i| self.entries[i as usize].bounds.distance_squared(q.center) <= r2);
        } else {
            let touched = candidates
                .iter()
                .filter_map(|&i| self.quick[i as usize].hull)
                .map(|h| self.hulls.touch(h))
                .sum::<f64>();
            std::hint::black_box(touched);
        }
        // Most candidates are hits: room for them all, made once.
        let mut hits = Hits::new(features, q.max_features, q.max_bodies, candidates.len());
        // Whether the query goes on after body `i`: not once the budget has run out.
        let test = |i: u32| -> bool {
            let i = i as usize;
            // A record settles most small convex bodies at `bodies` detail. It meets the
            // ball only when the body is nearer than the radius, so the bounds (looser)
            // need no test first.
            let quick = &self.quick[i];
            if let Some(decided) = quick
                .hull
                .filter(|_| q.detail == Detail::Bodies)
                .and_then(|h| self.hulls.ball(h, q.center, q.radius))
            {
                if let Some((distance, inside)) = decided {
                    let named = quick.named.then_some(i as u32);
                    hits.push_body(quick.id, named, Some(distance), inside);
                }
                return !hits.full;
            }
            let e = &self.entries[i];
            // At `features` detail the candidates kept are within the ball's reach.
            if !features && e.bounds.distance_squared(q.center) > r2 {
                return true;
            }
            let mut f = Features::default();
            let c = e.pose.inverse().transform_point(q.center);
            if let Some((distance, inside)) = reach::ball(
                &e.shape,
                &e.pose,
                c,
                q.radius,
                q.detail,
                q.tolerance,
                &mut f,
            ) {
                let named = e.name.is_some().then_some(i as u32);
                hits.push(e.id, named, Some(distance), inside, f);
            }
            !hits.full
        };
        self.test_in_batches(&candidates, features, test);
        let tolerance = hits.tolerance;
        let bodies = hits.finish(Order::Distance, |i| self.name_of(i))?;
        Ok(SphereAnswer {
            revision: self.revision(),
            center: q.center,
            radius: q.radius,
            detail: q.detail,
            tolerance: (q.detail == Detail::Portions).then(|| q.tolerance.max(tolerance)),
            bodies,
        })
    }

    /// Calls `test` on each of `candidates` (entry indices) in order until it answers
    /// false (the query's budget has run out), [`READ_AHEAD_BODIES`] at a time; with
    /// `read`, each batch is [read ahead](Spatial::read_ahead) before it is tested.
    fn test_in_batches(&self, candidates: &[u32], read: bool, mut test: impl FnMut(u32) -> bool) {
        for batch in candidates.chunks(READ_AHEAD_BODIES) {
            if read {
                self.read_ahead(batch);
            }
            if !batch.iter().all(|&i| test(i)) {
                return;
            }
        }
    }

    /// Reads ahead what the tests of the bodies `candidates` (entry indices) will read of
    /// them: their entries' poses and their shapes' headers first, then every record of
    /// each small shape ([`BodyShape::touch_all`]). Each pass is a loop of reads
    /// independent of one another, so that the cache misses of many bodies overlap
    /// instead of following one another through the tests, where each shape's records
    /// are found through its header and each header through an entry. Queries read
    /// ahead [`READ_AHEAD_BODIES`] at a time, so that one refused for its budget reads
    /// little past the body where it stopped.
    fn read_ahead(&self, candidates: &[u32]) {
        let headers = candidates.iter().fold(0, |acc, &i| {
            let e = &self.entries[i as usize];
            let pose = e.pose.rotation.w.to_bits() ^ e.pose.position.x.to_bits();
            acc ^ pose ^ e.shape.touch_header()
        });
        let records = candidates.iter().fold(0, |acc, &i| {
            acc ^ self.entries[i as usize].shape.touch_all()
        });
        std::hint::black_box(headers ^ records);
    }

    /// The bodies reaching into a closed axis-aligned box, with what of them is inside.
    pub fn aabb(&self, q: &BoxQuery) -> Result<BoxAnswer, QueryError> {
        q.validate()?;
        let region = Aabb::new(q.min, q.max);
        // Leaf position k holds entry k (see `build_hierarchy`). The bodies whose
        // bounds meet the box are gathered first; at `features` detail and above, their
        // shapes are read ahead.
        let mut candidates: Vec<u32> = Vec::with_capacity(256);
        self.bvh
            .overlapping(q.min, q.max, |k| candidates.push(k as u32));
        candidates.extend_from_slice(&self.loose);
        candidates.retain(|&i| self.entries[i as usize].bounds.overlaps(&region));
        let features = q.detail != Detail::Bodies;
        let mut hits = Hits::new(features, q.max_features, q.max_bodies, candidates.len());
        // Whether the query goes on after body `i`: not once the budget has run out.
        let test = |i: u32| -> bool {
            let e = &self.entries[i as usize];
            let mut f = Features::default();
            if let Some(inside) = reach::aabb(
                &e.shape,
                &e.pose,
                &e.pose.inverse(),
                q.min,
                q.max,
                q.detail,
                &mut f,
            ) {
                let named = e.name.is_some().then_some(i);
                hits.push(e.id, named, None, inside, f);
            }
            !hits.full
        };
        self.test_in_batches(&candidates, features, test);
        let bodies = hits.finish(Order::Id, |i| self.name_of(i))?;
        Ok(BoxAnswer {
            revision: self.revision(),
            min: q.min,
            max: q.max,
            detail: q.detail,
            bodies,
        })
    }

    /// The body whose solid is nearest `point` (ties to the smaller id), within
    /// `max_distance` (`f64::INFINITY` for no limit).
    pub fn nearest(&self, point: DVec3, max_distance: f64) -> Result<Found<Nearest>, QueryError> {
        validate_point(point, max_distance)?;
        let mut best: Option<Nearest> = None;
        let bound = max_distance * max_distance;
        let mut consider = |e: &Entry, best2: f64| -> f64 {
            // A removed body's entry stays in its leaf (with empty bounds, at an infinite
            // distance) until the next rebuild; with no limit, that is not beyond `best2`.
            if e.bounds.is_empty() || e.bounds.distance_squared(point) > best2 {
                return best2;
            }
            let c = e.pose.inverse().transform_point(point);
            let inside = e.shape.contains(c);
            let limit = if inside { f64::INFINITY } else { best2 };
            let Some((k, cl)) = e.shape.nearest_face(c, limit) else {
                return best2;
            };
            let d2 = if inside { 0.0 } else { cl.d2 };
            let better = match &best {
                None => d2 <= best2,
                Some(b) => d2 < best2 || (d2 == best2 && e.id.get() < b.id),
            };
            if !better {
                return best2;
            }
            best = Some(Nearest {
                id: e.id.get(),
                name: e.name.as_deref().map(str::to_owned),
                distance: d2.sqrt(),
                inside,
                surface_distance: cl.d2.sqrt(),
                point: e.pose.transform_point(cl.point),
                face: e.shape.faces[k].serial,
            });
            d2
        };
        let order = self.bvh.order();
        let mut b2 = self.bvh.nearest(point, bound, |k, b2| {
            consider(&self.entries[order[k] as usize], b2)
        });
        for &i in &self.loose {
            b2 = consider(&self.entries[i as usize], b2);
        }
        let _ = b2;
        Ok(Found {
            revision: self.revision(),
            hit: best,
        })
    }

    /// The first face the ray from `origin` along `direction` meets within
    /// `max_distance` (`f64::INFINITY` for no limit); a hit at the origin counts.
    pub fn ray(
        &self,
        origin: DVec3,
        direction: DVec3,
        max_distance: f64,
    ) -> Result<Found<RayHit>, QueryError> {
        let d = validate_ray(origin, direction, max_distance)?;
        let mut best: Option<(f64, u32, usize)> = None;
        let mut consider = |i: u32, t_best: f64| -> f64 {
            let e = &self.entries[i as usize];
            if e.bounds.ray_entry(origin, d).is_none_or(|t| t > t_best) {
                return t_best;
            }
            let inverse = e.pose.inverse();
            let o = inverse.transform_point(origin);
            let db = inverse.transform_vector(d);
            let mut t_best = t_best;
            e.shape
                .bvh
                .ray(o, db, t_best, |k, tb| match e.shape.ray_face(k, o, db) {
                    Some((t, _)) if t < tb || (t == tb && best.is_none()) => {
                        best = Some((t, i, k));
                        t_best = t;
                        t
                    }
                    _ => tb,
                });
            t_best
        };
        let order = self.bvh.order();
        let mut t = self
            .bvh
            .ray(origin, d, max_distance, |k, t| consider(order[k], t));
        for &i in &self.loose {
            t = consider(i, t);
        }
        let _ = t;
        let hit = best.map(|(t, i, k)| {
            let e = &self.entries[i as usize];
            let f = &e.shape.faces[k];
            let normal = e.pose.transform_vector(f.normal);
            RayHit {
                id: e.id.get(),
                name: e.name.as_deref().map(str::to_owned),
                face: f.serial,
                point: origin + d * t,
                distance: t,
                normal,
                entering: normal.dot(d) < 0.0,
            }
        });
        Ok(Found {
            revision: self.revision(),
            hit,
        })
    }
}

fn entry(id: BodyId, name: Option<&str>, shape: Arc<BodyShape>, pose: Pose) -> Entry {
    let mut e = Entry {
        id,
        name: name.map(Box::from),
        local: Aabb::EMPTY,
        body: 0,
        shape: shape.clone(),
        pose: Pose::IDENTITY,
        bounds: Aabb::EMPTY,
        hull: None,
        leaf: u32::MAX,
    };
    e.set_shape(shape);
    e.place(pose);
    e
}

impl Entry {
    /// Gives the entry a new shape (its world bounds are the caller's to redo, by
    /// [`Entry::place`]).
    fn set_shape(&mut self, shape: Arc<BodyShape>) {
        self.local = shape.bounds;
        self.body = Arc::as_ptr(shape.body()) as usize;
        self.shape = shape;
    }

    /// Puts the entry's shape at world pose `pose`: the pose and the world bounds (the
    /// record, if any, is the caller's to rewrite).
    fn place(&mut self, pose: Pose) {
        self.bounds = self.local.transformed(&pose);
        self.pose = pose;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::solids;

    /// Two 2 × 2 × 2 boxes, at the origin and at (5, 0, 0).
    fn two_boxes() -> (World, BodyId, BodyId) {
        let mut w = World::new();
        let root = w.root();
        let at = |w: &mut World, x: f64| {
            w.insert_with(
                None,
                root,
                Pose::from_translation(DVec3::new(x, 0.0, 0.0)),
                |s| solids::mkcube(s, 2.0, 2.0, 2.0),
            )
            .expect("a box")
        };
        let a = at(&mut w, 0.0);
        let b = at(&mut w, 5.0);
        (w, a, b)
    }

    #[test]
    fn a_removed_body_is_neither_nearest_nor_hit_before_the_rebuild() {
        let (mut w, a, b) = two_boxes();
        let mut s = Spatial::build(Arc::new(w.clone()));
        w.kill(a).expect("killed");
        let stats = s.sync(Arc::new(w), Some(&[a]));
        assert_eq!((stats.removed, stats.rebuilt), (1, false));
        let n = s.nearest(DVec3::ZERO, f64::INFINITY).expect("a query");
        assert_eq!(n.hit.map(|h| h.id), Some(b.get()));
        // A skew ray through where the removed box was.
        let d = DVec3::new(1.0, 0.01, 0.02);
        let r = s.ray(DVec3::new(-5.0, 0.0, 0.0), d, f64::INFINITY);
        assert_eq!(r.expect("a query").hit.map(|h| h.id), Some(b.get()));
        // A ball reaching into where it was and into the other box, at every detail.
        for detail in [Detail::Bodies, Detail::Features] {
            let q = SphereQuery::new(DVec3::new(2.5, 0.0, 0.0), 2.0).with_detail(detail);
            let hits = s.sphere(&q).expect("a query").bodies;
            let ids: Vec<u64> = hits.iter().map(|h| h.id).collect();
            assert_eq!(ids, vec![b.get()], "{detail:?}");
        }
    }

    #[test]
    fn a_name_given_or_taken_after_the_build_is_answered_at_bodies_detail() {
        let (mut w, a, _) = two_boxes();
        let mut s = Spatial::build(Arc::new(w.clone()));
        let q = SphereQuery::new(DVec3::ZERO, 0.5).with_detail(Detail::Bodies);
        let name = |s: &Spatial| s.sphere(&q).expect("a query").bodies[0].name.clone();
        assert_eq!(name(&s), None);
        for given in [Some("crate"), None] {
            w.rename(a, given).expect("renamed");
            // Moved too: a move alone leaves what a query reads first as it was.
            w.set_pose(a, Pose::from_translation(DVec3::new(0.0, 0.1, 0.0)))
                .expect("posed");
            s.sync(Arc::new(w.clone()), Some(&[a]));
            assert_eq!(name(&s).as_deref(), given);
        }
    }

    #[test]
    fn a_centre_on_an_edge_or_at_a_vertex_is_inside() {
        let (w, a, _) = two_boxes();
        let s = Spatial::build(Arc::new(w));
        for c in [
            DVec3::ONE,
            DVec3::new(1.0, 1.0, 0.3),
            DVec3::new(1.0, 0.2, 0.3),
        ] {
            let q = SphereQuery::new(c, 0.5).with_detail(Detail::Bodies);
            let hit = &s.sphere(&q).expect("a query").bodies[0];
            assert_eq!(hit.id, a.get());
            assert!(hit.inside, "{c}");
            assert_eq!(hit.distance, Some(0.0), "{c}");
            let n = s.nearest(c, f64::INFINITY).expect("a query").hit;
            assert!(n.is_some_and(|n| n.inside && n.distance == 0.0), "{c}");
        }
    }
}
