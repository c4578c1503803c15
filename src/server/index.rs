//! The spatial index as a service of the server: one [`Spatial`] index shared by every
//! spatial query ([`SpatialAccess`]), kept up with the world.
//!
//! A query takes a snapshot of the world and is answered from the index when the index
//! is at (or past) the snapshot's revision. Otherwise the index is first brought up to
//! the snapshot under the write lock: built whole the first time; afterwards synced with
//! the bodies the change feed names since the index's revision, or, when the feed no
//! longer covers that gap, by comparing every body.
//!
//! When a sync leaves the index [worn](Spatial::worn) (bodies added, removed or moved far
//! enough to slow its hierarchy), the hierarchy is rebuilt on a thread of its own, from a
//! [`Fork`] of the index, while queries go on with the worn index (exact, only slower).
//! The fresh index catches up with the writes made meanwhile from the change feed, off
//! the lock, and takes the worn one's place under the write lock after the last few. Only
//! when the worn index has so many loose bodies that every query would crawl through
//! them is it rebuilt in place, under the lock. Builds are counted and timed in the
//! `winged_spatial_index_build*` metrics and logged.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, RwLock, RwLockWriteGuard};
use std::time::Instant;

use tokio::sync::Semaphore;

use crate::model::{BodyId, Serial, World};
use crate::server::changes::{Action, Field, Kind};
use crate::server::events::{Feed, Since};
use crate::server::metrics::{IndexBuild, Metrics};
use crate::spatial::{Fork, Spatial};

/// The most changes read from the feed to bring the index up; a longer gap is closed by
/// comparing every body instead.
const FEED_GAP_MAX: u64 = 65_536;

/// Loose bodies (tested one by one by every query) past which a worn index is rebuilt
/// in place rather than left answering until a rebuild off the lock is ready.
const LOOSE_WAIT_MAX: usize = 4096;

/// Rebuilds one rebuild thread makes in a row, each when the writes its last one caught
/// up with left that one worn.
const REBUILD_ROUNDS: usize = 3;

/// Rounds of catching up off the lock a fresh index makes before it takes the lock for
/// the last writes.
const CATCH_UP_ROUNDS: usize = 4;

/// What spatial queries share: the index, the turns, and the rebuild under way.
pub struct SpatialAccess {
    /// The index, built by the first query.
    index: RwLock<Option<Spatial>>,
    /// Queries allowed to run at once (off the async threads).
    pub(crate) permits: Arc<Semaphore>,
    /// Whether a rebuild is running off the lock.
    rebuilding: AtomicBool,
    /// Where builds are counted and timed.
    metrics: Arc<Metrics>,
}

impl SpatialAccess {
    /// No index yet (the first query builds it); as many queries at once as the machine
    /// has cores; builds reported to `metrics`.
    pub fn new(metrics: Arc<Metrics>) -> SpatialAccess {
        let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
        SpatialAccess {
            index: RwLock::new(None),
            permits: Arc::new(Semaphore::new(cores)),
            rebuilding: AtomicBool::new(false),
            metrics,
        }
    }

    /// Answers `ask` from an index at `world`'s revision or later, bringing the index up
    /// first if it is behind (and starting a rebuild if that leaves it worn). Blocking:
    /// call off the async threads.
    pub(crate) fn answer<T>(
        self: &Arc<Self>,
        world: Arc<World>,
        feed: &Arc<Feed>,
        ask: impl FnOnce(&Spatial) -> T,
    ) -> T {
        let target = world.revision();
        if let Ok(g) = self.index.read()
            && let Some(s) = g.as_ref()
            && s.revision() >= target
        {
            return ask(s);
        }
        let mut g = self.write();
        // The snapshot the index leaves behind, freed once the lock is released: it may
        // be the last reference to a world of many bodies.
        let mut retired = None;
        let index = match g.take() {
            None => self.build(world),
            Some(mut s) => {
                if s.revision() < target {
                    retired = Some(s.world().clone());
                    bring_up(&mut s, world, feed);
                    if s.worn() {
                        self.renew(&mut s, feed);
                    }
                }
                s
            }
        };
        // Answered under the write lock: the index cannot be dropped between the update
        // and the question, and the readers queued behind it are released right after.
        let answer = ask(g.insert(index));
        drop(g);
        drop(retired);
        answer
    }

    /// The index of `world`, built whole (the first query's), logged and counted.
    fn build(&self, world: Arc<World>) -> Spatial {
        let started = Instant::now();
        let s = Spatial::build(world);
        let elapsed = started.elapsed();
        self.metrics.observe_index_build(IndexBuild::First, elapsed);
        tracing::info!(
            bodies = s.len(),
            revision = s.revision(),
            elapsed_ms = elapsed.as_secs_f64() * 1e3,
            heap_mb = s.heap_bytes() as f64 / (1024.0 * 1024.0),
            "spatial index built"
        );
        s
    }

    /// Has the worn index `s` rebuilt: on a thread of its own while `s` goes on answering
    /// (unless such a rebuild is already running), or here, in place, when `s` is too
    /// worn to wait ([`LOOSE_WAIT_MAX`]) or no thread can be started.
    ///
    /// Precondition: the caller holds the write lock and puts `s` back in the index.
    fn renew(self: &Arc<Self>, s: &mut Spatial, feed: &Arc<Feed>) {
        if s.loose() <= LOOSE_WAIT_MAX {
            if self.rebuilding.swap(true, Ordering::AcqRel) {
                return;
            }
            let fork = s.fork();
            let (access, feed) = (Arc::clone(self), Arc::clone(feed));
            let spawned = std::thread::Builder::new()
                .name("spatial-rebuild".into())
                .spawn(move || access.rebuild_away(fork, &feed));
            match spawned {
                Ok(_) => return,
                Err(e) => {
                    self.rebuilding.store(false, Ordering::Release);
                    tracing::warn!(error = %e, "no thread for the spatial index's rebuild; rebuilt in place");
                }
            }
        }
        let started = Instant::now();
        s.rebuild();
        let elapsed = started.elapsed();
        self.metrics
            .observe_index_build(IndexBuild::InPlace, elapsed);
        tracing::info!(
            bodies = s.len(),
            revision = s.revision(),
            generation = s.generation(),
            elapsed_ms = elapsed.as_secs_f64() * 1e3,
            "spatial index rebuilt in place"
        );
    }

    /// Builds a fresh index from `fork` and puts it in the index's place (see
    /// [`SpatialAccess::adopt`]); again when the writes it caught up with left it worn
    /// too, up to [`REBUILD_ROUNDS`] times (after that, the next write's sync starts a
    /// rebuild). Runs on the rebuild's own thread; clears `rebuilding` when done, or if
    /// it panics.
    fn rebuild_away(&self, fork: Fork, feed: &Feed) {
        struct Running<'a>(&'a AtomicBool);
        impl Drop for Running<'_> {
            fn drop(&mut self) {
                self.0.store(false, Ordering::Release);
            }
        }
        let _running = Running(&self.rebuilding);
        let mut next = Some(fork);
        for _ in 0..REBUILD_ROUNDS {
            let Some(fork) = next.take() else { break };
            let (from, origin) = (fork.revision(), fork.generation());
            let started = Instant::now();
            let fresh = fork.build();
            let built = started.elapsed();
            let caught_up = Instant::now();
            let (how, worn) = self.adopt(fresh, origin, feed);
            self.metrics.observe_index_build(how, built);
            tracing::info!(
                from,
                generation = origin + 1,
                adopted = how == IndexBuild::Background,
                build_ms = built.as_secs_f64() * 1e3,
                catch_up_ms = caught_up.elapsed().as_secs_f64() * 1e3,
                "spatial index rebuilt off the lock"
            );
            next = worn;
        }
    }

    /// Puts `fresh`, built from a fork of the index of generation `origin`, in the
    /// index's place, once brought up to the index's revision: off the lock while the
    /// index moves on (a few rounds), then under the write lock for the writes since.
    /// Drops it instead when the index is no longer of generation `origin` (rebuilt in
    /// place meanwhile, or dropped after a panic). Answers which it was, and a fork of
    /// the adopted index when catching up left it worn.
    fn adopt(&self, mut fresh: Spatial, origin: u64, feed: &Feed) -> (IndexBuild, Option<Fork>) {
        for _ in 0..CATCH_UP_ROUNDS {
            let Some(world) = self.world_of_generation(origin) else {
                return (IndexBuild::Dropped, None);
            };
            if world.revision() <= fresh.revision() {
                break;
            }
            bring_up(&mut fresh, world, feed);
        }
        let mut g = self.write();
        let Some(current) = g.as_mut().filter(|s| s.generation() == origin) else {
            return (IndexBuild::Dropped, None);
        };
        if current.revision() > fresh.revision() {
            bring_up(&mut fresh, current.world().clone(), feed);
        }
        let worn = fresh.worn().then(|| fresh.fork());
        // The worn index is freed once the lock is released.
        let old = std::mem::replace(current, fresh);
        drop(g);
        drop(old);
        (IndexBuild::Background, worn)
    }

    /// The world of the index when it is of generation `generation`.
    fn world_of_generation(&self, generation: u64) -> Option<Arc<World>> {
        let g = self.index.read().ok()?;
        let s = g.as_ref().filter(|s| s.generation() == generation)?;
        Some(s.world().clone())
    }

    /// `ask` of the index when it is at `revision` or past it and its read lock is free
    /// now (never waits: a sync holding the write lock sends the question elsewhere).
    pub(crate) fn try_current<T>(
        &self,
        revision: u64,
        ask: impl FnOnce(&Spatial) -> T,
    ) -> Option<T> {
        let g = self.index.try_read().ok()?;
        let s = g.as_ref().filter(|s| s.revision() >= revision)?;
        Some(ask(s))
    }

    /// The write lock; a poisoned index (a panic while it was being changed) is dropped,
    /// to be built anew.
    fn write(&self) -> RwLockWriteGuard<'_, Option<Spatial>> {
        match self.index.write() {
            Ok(g) => g,
            Err(poisoned) => {
                let mut g = poisoned.into_inner();
                *g = None;
                self.index.clear_poison();
                tracing::warn!("the spatial index was poisoned by a panic; it is built anew");
                g
            }
        }
    }
}

/// Brings `s` to `world`: with the bodies the feed names since `s`'s revision, or by
/// comparing every body when the feed does not cover the gap.
fn bring_up(s: &mut Spatial, world: Arc<World>, feed: &Feed) {
    let (from, to) = (s.revision(), world.revision());
    let started = Instant::now();
    let touched = touched_between(feed, from, to);
    let listed = touched.as_ref().map(Vec::len);
    let stats = s.update(world, touched.as_deref());
    tracing::debug!(
        from,
        to,
        listed,
        shaped = stats.shaped,
        moved = stats.moved,
        added = stats.added,
        removed = stats.removed,
        elapsed_ms = started.elapsed().as_secs_f64() * 1e3,
        "spatial index synced"
    );
}

/// The bodies changed by the writes after revision `from` up to `to`, as the feed tells;
/// `None` when the feed no longer holds every one of those writes (it was asked too late,
/// or the gap is longer than [`FEED_GAP_MAX`]).
///
/// A body whose only changes are its list of sub-parts or its colour is left out: its
/// shape, pose and name are as they were, and each part added to or taken from it is
/// named on its own. (Every creation updates its supart's parts; following those would
/// revisit the whole world under the world body.)
fn touched_between(feed: &Feed, from: u64, to: u64) -> Option<Vec<BodyId>> {
    let gap = to.checked_sub(from)?;
    if gap > FEED_GAP_MAX {
        return None;
    }
    let limit = usize::try_from(gap).ok()?;
    let Since::Changes { changes, .. } = feed.since(from, limit) else {
        return None;
    };
    // The feed's changes are consecutive from `from + 1`: they cover the gap when the
    // last one reaches `to` (with `more` or not: what follows is past the snapshot).
    if changes.last().is_none_or(|c| c.revision < to) {
        return None;
    }
    let mut ids: Vec<BodyId> = changes
        .iter()
        .filter(|c| c.revision <= to)
        .flat_map(|c| c.changes.iter())
        .filter(|e| e.kind == Kind::Body)
        .filter(|e| {
            !(e.action == Action::Updated
                && !e.fields.is_empty()
                && e.fields
                    .iter()
                    .all(|f| matches!(f, Field::Parts | Field::Color)))
        })
        .filter_map(|e| e.id)
        .map(|id| BodyId(Serial(id)))
        .collect();
    ids.sort_unstable();
    ids.dedup();
    Some(ids)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::server::changes::{Change, EntityChange};
    use crate::spatial::{BoxQuery, Detail};
    use glam::DVec3;

    fn body(action: Action, id: u64, fields: &[Field]) -> EntityChange {
        EntityChange::body(action, id, fields)
    }

    fn change(revision: u64, changes: Vec<EntityChange>) -> Change {
        Change {
            revision,
            edit: "test".into(),
            changes,
        }
    }

    #[test]
    fn the_feed_names_the_bodies_that_moved_or_changed_shape() {
        let feed = Feed::new(
            10,
            5,
            vec![
                change(3, vec![body(Action::Added, 7, &[])]),
                change(
                    4,
                    vec![
                        body(Action::Added, 8, &[]),
                        body(Action::Updated, 1, &[Field::Parts]),
                    ],
                ),
                change(
                    5,
                    vec![
                        body(Action::Updated, 7, &[Field::Pose]),
                        body(Action::Updated, 8, &[Field::Color]),
                        body(Action::Updated, 6, &[Field::Name, Field::Color]),
                        body(Action::Removed, 9, &[]),
                    ],
                ),
            ],
        );
        let ids = |v: Option<Vec<BodyId>>| v.map(|v| v.iter().map(|b| b.get()).collect::<Vec<_>>());
        assert_eq!(ids(touched_between(&feed, 2, 5)), Some(vec![6, 7, 8, 9]));
        // A colour alone is not a change to the index; a name is.
        assert_eq!(ids(touched_between(&feed, 4, 5)), Some(vec![6, 7, 9]));
        // Older than the history: the feed cannot tell.
        assert_eq!(ids(touched_between(&feed, 1, 5)), None);
        // Only up to the snapshot's revision.
        assert_eq!(ids(touched_between(&feed, 2, 3)), Some(vec![7]));
        // A snapshot ahead of the feed: not covered.
        assert_eq!(ids(touched_between(&feed, 4, 6)), None);
    }

    /// A 2 × 2 × 2 box added to `w` at `(x, y, 0)`.
    fn add_box(w: &mut World, x: f64, y: f64) -> BodyId {
        let root = w.root();
        w.insert_with(
            None,
            root,
            crate::model::Pose::from_translation(DVec3::new(x, y, 0.0)),
            |s| crate::model::solids::mkcube(s, 2.0, 2.0, 2.0),
        )
        .expect("a box")
    }

    /// The ids of the bodies whose boxes meet the box `min..max`, as `access` answers
    /// at `world`'s revision.
    fn found(access: &Arc<SpatialAccess>, world: &World, min: DVec3, max: DVec3) -> Vec<u64> {
        let q = BoxQuery {
            detail: Detail::Bodies,
            ..BoxQuery::new(min, max)
        };
        let feed = Feed::new(1, 0, Vec::new());
        let answer = access.answer(Arc::new(world.clone()), &feed, |s| s.aabb(&q));
        answer
            .expect("a query")
            .bodies
            .iter()
            .map(|h| h.id)
            .collect()
    }

    #[test]
    fn a_fresh_index_catches_up_with_the_writes_made_while_it_was_built() {
        let mut w = World::new();
        let first = add_box(&mut w, 0.0, 0.0);
        let metrics = Arc::new(Metrics::new());
        let access = Arc::new(SpatialAccess::new(metrics.clone()));
        let everywhere = (DVec3::splat(-100.0), DVec3::splat(500.0));
        assert_eq!(
            found(&access, &w, everywhere.0, everywhere.1),
            vec![first.get()]
        );
        // Taken as running, so that the queries below leave the rebuild to this test.
        access.rebuilding.store(true, Ordering::Release);
        let row: Vec<BodyId> = (1..=70)
            .map(|k| add_box(&mut w, 4.0 * f64::from(k), 0.0))
            .collect();
        let all = found(&access, &w, everywhere.0, everywhere.1);
        assert_eq!(all.len(), 71);
        let (fork, worn_loose) = {
            let g = access.index.read().expect("the index");
            let s = g.as_ref().expect("built");
            assert!(s.worn(), "70 loose bodies wear the index");
            (s.fork(), s.loose())
        };
        assert_eq!(worn_loose, 70);
        // Writes after the fork: a move, a removal and an addition, each answered.
        w.set_pose(
            row[0],
            crate::model::Pose::from_translation(DVec3::new(4.0, 3.0, 0.0)),
        )
        .expect("posed");
        w.kill(row[1]).expect("killed");
        let late = add_box(&mut w, 0.0, -5.0);
        let before = found(&access, &w, everywhere.0, everywhere.1);
        assert_eq!(before.len(), 71);
        assert!(before.contains(&late.get()) && !before.contains(&row[1].get()));

        let (how, again) = access.adopt(fork.build(), 0, &Feed::new(1, 0, Vec::new()));
        assert_eq!(how, IndexBuild::Background);
        assert!(again.is_none(), "the fresh index is not worn");
        {
            let g = access.index.read().expect("the index");
            let s = g.as_ref().expect("adopted");
            assert_eq!((s.generation(), s.revision()), (1, w.revision()));
            assert_eq!(s.loose(), 1, "only the body added after the fork is loose");
        }
        assert_eq!(found(&access, &w, everywhere.0, everywhere.1), before);
        let up = found(
            &access,
            &w,
            DVec3::new(3.0, 2.5, -2.0),
            DVec3::new(5.0, 3.5, 2.0),
        );
        assert_eq!(up, vec![row[0].get()]);

        // A fork of an index since rebuilt in place is dropped, and the index left as it
        // was.
        let stale = access
            .index
            .read()
            .expect("the index")
            .as_ref()
            .expect("built")
            .fork();
        access.write().as_mut().expect("built").rebuild();
        let (how, again) = access.adopt(stale.build(), 1, &Feed::new(1, 0, Vec::new()));
        assert_eq!((how, again.is_none()), (IndexBuild::Dropped, true));
        let g = access.index.read().expect("the index");
        assert_eq!(g.as_ref().map(Spatial::generation), Some(2));
    }
}
