//! Spatial access over HTTP: `/v1/spatial/{sphere,box,nearest,ray}`, each as a `GET`
//! with a query string and as a `POST` with a JSON body.
//!
//! One [`Spatial`] index is shared by every request ([`SpatialAccess`]). A query takes a
//! snapshot of the world and answers from the index when it is at (or past) the
//! snapshot's revision: on the async thread itself when the answer fits a small budget
//! (a few thousand features, a few hundred bodies), else on a blocking thread.
//! Otherwise the index is first brought up to the
//! snapshot under the write lock: built whole the first time; afterwards synced with the
//! bodies the change feed names since the index's revision, or, when the feed no longer
//! covers that gap, by comparing every body. Answers carry the index's revision in the
//! body and in `ETag`.
//!
//! When a sync leaves the index [worn](Spatial::worn) (bodies added, removed or moved far
//! enough to slow its hierarchy), the hierarchy is rebuilt on a thread of its own, from a
//! [`Fork`] of the index, while queries go on with the worn index (exact, only slower).
//! The fresh index catches up with the writes made meanwhile from the change feed, off
//! the lock, and takes the worn one's place under the write lock after the last few. Only
//! when the worn index has so many loose bodies that every query would crawl through
//! them is it rebuilt in place, under the lock. Builds are counted and timed in the
//! `winged_spatial_index_build*` metrics and logged.
//!
//! Malformed requests (bad JSON or query strings, unknown fields) are answered 400;
//! well-formed ones with values a query cannot take (NaN or infinite numbers, a negative
//! radius, an empty box, a zero direction, a tolerance that is not a positive length, a
//! centre, point or origin farther than [`QUERY_LIMIT`] from the origin on an axis)
//! 422 `invalid-query`, naming the field as the request spells it; an answer that would
//! hold more than `max_features` faces, edges and vertices 422 `too-many-features`.
//! Box corners, radii and distances beyond that limit are clamped to it: the world's
//! content lies well inside (see [`crate::model::range`]), so no answer changes.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, RwLock, RwLockWriteGuard};
use std::time::Instant;

use axum::extract::State;
use axum::http::StatusCode;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use tokio::sync::Semaphore;

use super::extract::{ApiJson, ApiQuery};
use super::{Answer, AppState, read_answer, snapshot};
use crate::model::range::{self, QUERY_LIMIT};
use crate::model::{BodyId, Serial, World};
use crate::server::changes::{Action, Field, Kind};
use crate::server::events::{Feed, Since};
use crate::server::metrics::{IndexBuild, Metrics};
use crate::server::problem::Problem;
use crate::spatial::{
    BoxQuery, DEFAULT_MAX_FEATURES, DEFAULT_TOLERANCE, Detail, Fork, QueryError, Spatial,
    SphereQuery,
};

/// The largest `max_features` a request may ask for; larger values are taken as this.
pub const MAX_FEATURES: usize = 1_000_000;

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
    /// Queries allowed to run at once.
    permits: Arc<Semaphore>,
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
    fn answer<T>(
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
    fn try_current<T>(&self, revision: u64, ask: impl FnOnce(&Spatial) -> T) -> Option<T> {
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

// ----- requests ----------------------------------------------------------------------

/// `POST /v1/spatial/sphere`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereReq {
    /// The centre, world coordinates.
    pub center: [f64; 3],
    /// The radius, meters.
    pub radius: f64,
    /// How much of each body to answer (default `features`).
    #[serde(default)]
    pub detail: Option<Detail>,
    /// The chord tolerance of portions, meters (default 1 mm).
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// The most faces, edges and vertices in the answer.
    #[serde(default)]
    pub max_features: Option<usize>,
}

/// `GET /v1/spatial/sphere?x=&y=&z=&r=&detail=&tolerance=&max_features=`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereParams {
    x: f64,
    y: f64,
    z: f64,
    r: f64,
    #[serde(default)]
    detail: Option<Detail>,
    #[serde(default)]
    tolerance: Option<f64>,
    #[serde(default)]
    max_features: Option<usize>,
}

/// `POST /v1/spatial/box`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxReq {
    /// The smallest corner, world coordinates.
    pub min: [f64; 3],
    /// The largest corner.
    pub max: [f64; 3],
    /// How much of each body to answer (default `features`).
    #[serde(default)]
    pub detail: Option<Detail>,
    /// The most faces, edges and vertices in the answer.
    #[serde(default)]
    pub max_features: Option<usize>,
}

/// `GET /v1/spatial/box?min_x=&min_y=&min_z=&max_x=&max_y=&max_z=&detail=&max_features=`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxParams {
    min_x: f64,
    min_y: f64,
    min_z: f64,
    max_x: f64,
    max_y: f64,
    max_z: f64,
    #[serde(default)]
    detail: Option<Detail>,
    #[serde(default)]
    max_features: Option<usize>,
}

/// `POST /v1/spatial/nearest`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NearestReq {
    /// The point, world coordinates.
    pub point: [f64; 3],
    /// The farthest a body may be, meters (default: no limit).
    #[serde(default)]
    pub max_distance: Option<f64>,
}

/// `GET /v1/spatial/nearest?x=&y=&z=&max_distance=`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NearestParams {
    x: f64,
    y: f64,
    z: f64,
    #[serde(default)]
    max_distance: Option<f64>,
}

/// `POST /v1/spatial/ray`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RayReq {
    /// Where the ray starts, world coordinates.
    pub origin: [f64; 3],
    /// Its direction (any length but zero).
    pub direction: [f64; 3],
    /// The farthest along the ray to look, meters (default: no limit).
    #[serde(default)]
    pub max_distance: Option<f64>,
}

/// `GET /v1/spatial/ray?x=&y=&z=&dx=&dy=&dz=&max_distance=`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RayParams {
    x: f64,
    y: f64,
    z: f64,
    dx: f64,
    dy: f64,
    dz: f64,
    #[serde(default)]
    max_distance: Option<f64>,
}

/// The names a request form gives its fields, for the problems that point at them.
struct Names {
    center: &'static str,
    radius: &'static str,
    min: [&'static str; 3],
    max: [&'static str; 3],
    direction: &'static str,
    zero_direction: &'static str,
}

const JSON_NAMES: Names = Names {
    center: "center",
    radius: "radius",
    min: ["min[0]", "min[1]", "min[2]"],
    max: ["max[0]", "max[1]", "max[2]"],
    direction: "direction",
    zero_direction: "direction must not be [0, 0, 0]",
};

const QUERY_NAMES: Names = Names {
    center: "x, y and z",
    radius: "r",
    min: ["min_x", "min_y", "min_z"],
    max: ["max_x", "max_y", "max_z"],
    direction: "dx, dy and dz",
    zero_direction: "dx, dy and dz must not all be zero",
};

/// 422 `invalid-query`.
fn invalid(detail: impl Into<String>) -> Problem {
    Problem::new(
        StatusCode::UNPROCESSABLE_ENTITY,
        "invalid-query",
        "Invalid spatial query",
        detail,
    )
}

/// The problem answering a query the index refused.
fn refused(e: QueryError) -> Problem {
    match e {
        QueryError::TooManyFeatures { .. } | QueryError::TooManyBodies { .. } => Problem::new(
            StatusCode::UNPROCESSABLE_ENTITY,
            "too-many-features",
            "Too many features",
            e.to_string(),
        ),
        QueryError::NotFinite { .. }
        | QueryError::NegativeRadius(_)
        | QueryError::EmptyBox
        | QueryError::ZeroDirection
        | QueryError::BadTolerance(_)
        | QueryError::NegativeDistance(_) => invalid(e.to_string()),
    }
}

/// A query's centre, point or origin: finite and within [`QUERY_LIMIT`] of the origin on
/// each axis, so that every distance to the world's content is a finite number.
fn point(v: [f64; 3], name: &str) -> Result<DVec3, Problem> {
    let p = DVec3::from_array(v);
    if !p.is_finite() {
        return Err(invalid(format!(
            "{name} must be finite (got [{}, {}, {}])",
            v[0], v[1], v[2]
        )));
    }
    if !range::is_within(p, QUERY_LIMIT) {
        return Err(invalid(format!(
            "{name} must lie within {QUERY_LIMIT:e} m of the origin on each axis (got [{}, {}, {}]); \
             the world's content lies within {:e} m",
            v[0],
            v[1],
            v[2],
            range::WORLD_EXTENT
        )));
    }
    Ok(p)
}

/// A length that reaches past everything from any query point: a radius or distance
/// beyond it is clamped to it, which changes no answer.
const REACH_ALL: f64 = 4.0 * QUERY_LIMIT;

fn max_distance(d: Option<f64>) -> Result<f64, Problem> {
    match d {
        None => Ok(f64::INFINITY),
        Some(d) if d.is_nan() || d < 0.0 => Err(invalid(format!(
            "max_distance must be zero or more meters (got {d}); leave it out for no limit"
        ))),
        Some(d) if d > REACH_ALL => Ok(f64::INFINITY),
        Some(d) => Ok(d),
    }
}

fn max_features(n: Option<usize>) -> usize {
    n.unwrap_or(DEFAULT_MAX_FEATURES).min(MAX_FEATURES)
}

/// Checks a sphere query, naming fields as `names` does.
#[allow(clippy::too_many_arguments)]
fn sphere_query(
    center: [f64; 3],
    radius: f64,
    detail: Option<Detail>,
    tolerance: Option<f64>,
    features: Option<usize>,
    names: &Names,
) -> Result<SphereQuery, Problem> {
    let center = point(center, names.center)?;
    if !radius.is_finite() || radius < 0.0 {
        return Err(invalid(format!(
            "{} must be a finite number of meters, zero or more (got {radius})",
            names.radius
        )));
    }
    let tolerance = tolerance.unwrap_or(DEFAULT_TOLERANCE);
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(invalid(format!(
            "tolerance must be a finite number of meters above zero (got {tolerance})"
        )));
    }
    Ok(SphereQuery {
        center,
        radius: radius.min(REACH_ALL),
        detail: detail.unwrap_or_default(),
        tolerance,
        max_features: max_features(features),
        max_bodies: usize::MAX,
    })
}

/// Checks a box query, naming fields as `names` does.
fn box_query(
    min: [f64; 3],
    max: [f64; 3],
    detail: Option<Detail>,
    features: Option<usize>,
    names: &Names,
) -> Result<BoxQuery, Problem> {
    for (v, n) in min.iter().zip(names.min).chain(max.iter().zip(names.max)) {
        if !v.is_finite() {
            return Err(invalid(format!("{n} must be a finite number (got {v})")));
        }
    }
    for k in 0..3 {
        if min[k] > max[k] {
            return Err(invalid(format!(
                "the box is empty: {} ({}) exceeds {} ({})",
                names.min[k], min[k], names.max[k], max[k]
            )));
        }
    }
    // Corners beyond the query limit are clamped to it: the world's content lies well
    // inside, so the answer is the same, and no extent of the box can overflow.
    let clamp = |v: [f64; 3]| {
        DVec3::from_array(v).clamp(DVec3::splat(-QUERY_LIMIT), DVec3::splat(QUERY_LIMIT))
    };
    Ok(BoxQuery {
        min: clamp(min),
        max: clamp(max),
        detail: detail.unwrap_or_default(),
        max_features: max_features(features),
        max_bodies: usize::MAX,
    })
}

/// A ray's direction scaled so that its largest component is ±1 (so that its length
/// cannot overflow), checked.
fn direction(v: [f64; 3], names: &Names) -> Result<DVec3, Problem> {
    let d = DVec3::from_array(v);
    if !d.is_finite() {
        return Err(invalid(format!(
            "{} must be finite (got [{}, {}, {}])",
            names.direction, v[0], v[1], v[2]
        )));
    }
    let m = d.abs().max_element();
    if m == 0.0 {
        return Err(invalid(format!(
            "{}: a ray needs a direction",
            names.zero_direction
        )));
    }
    Ok(d / m)
}

// ----- handlers ----------------------------------------------------------------------

/// `POST /v1/spatial/sphere`.
pub(super) async fn sphere_post(
    State(state): State<AppState>,
    ApiJson(r): ApiJson<SphereReq>,
) -> Answer {
    let q = sphere_query(
        r.center,
        r.radius,
        r.detail,
        r.tolerance,
        r.max_features,
        &JSON_NAMES,
    )?;
    run(&state, move |s, inline| s.sphere(&inline_sphere(q, inline))).await
}

/// `GET /v1/spatial/sphere`.
pub(super) async fn sphere_get(
    State(state): State<AppState>,
    ApiQuery(r): ApiQuery<SphereParams>,
) -> Answer {
    let q = sphere_query(
        [r.x, r.y, r.z],
        r.r,
        r.detail,
        r.tolerance,
        r.max_features,
        &QUERY_NAMES,
    )?;
    run(&state, move |s, inline| s.sphere(&inline_sphere(q, inline))).await
}

/// `POST /v1/spatial/box`.
pub(super) async fn box_post(State(state): State<AppState>, ApiJson(r): ApiJson<BoxReq>) -> Answer {
    let q = box_query(r.min, r.max, r.detail, r.max_features, &JSON_NAMES)?;
    run(&state, move |s, inline| s.aabb(&inline_box(q, inline))).await
}

/// `GET /v1/spatial/box`.
pub(super) async fn box_get(
    State(state): State<AppState>,
    ApiQuery(r): ApiQuery<BoxParams>,
) -> Answer {
    let q = box_query(
        [r.min_x, r.min_y, r.min_z],
        [r.max_x, r.max_y, r.max_z],
        r.detail,
        r.max_features,
        &QUERY_NAMES,
    )?;
    run(&state, move |s, inline| s.aabb(&inline_box(q, inline))).await
}

/// `POST /v1/spatial/nearest`.
pub(super) async fn nearest_post(
    State(state): State<AppState>,
    ApiJson(r): ApiJson<NearestReq>,
) -> Answer {
    let p = point(r.point, "point")?;
    let d = max_distance(r.max_distance)?;
    run(&state, move |s, _| s.nearest(p, d)).await
}

/// `GET /v1/spatial/nearest`.
pub(super) async fn nearest_get(
    State(state): State<AppState>,
    ApiQuery(r): ApiQuery<NearestParams>,
) -> Answer {
    let p = point([r.x, r.y, r.z], QUERY_NAMES.center)?;
    let d = max_distance(r.max_distance)?;
    run(&state, move |s, _| s.nearest(p, d)).await
}

/// `POST /v1/spatial/ray`.
pub(super) async fn ray_post(State(state): State<AppState>, ApiJson(r): ApiJson<RayReq>) -> Answer {
    let o = point(r.origin, "origin")?;
    let d = direction(r.direction, &JSON_NAMES)?;
    let m = max_distance(r.max_distance)?;
    run(&state, move |s, _| s.ray(o, d, m)).await
}

/// `GET /v1/spatial/ray`.
pub(super) async fn ray_get(
    State(state): State<AppState>,
    ApiQuery(r): ApiQuery<RayParams>,
) -> Answer {
    let o = point([r.x, r.y, r.z], QUERY_NAMES.center)?;
    let d = direction([r.dx, r.dy, r.dz], &QUERY_NAMES)?;
    let m = max_distance(r.max_distance)?;
    run(&state, move |s, _| s.ray(o, d, m)).await
}

/// An answer that says which revision it describes.
trait Revised {
    fn revision(&self) -> u64;
}

impl Revised for crate::spatial::SphereAnswer {
    fn revision(&self) -> u64 {
        self.revision
    }
}

impl Revised for crate::spatial::BoxAnswer {
    fn revision(&self) -> u64 {
        self.revision
    }
}

impl<T> Revised for crate::spatial::Found<T> {
    fn revision(&self) -> u64 {
        self.revision
    }
}

/// The most faces, edges and vertices of an answer computed on the async threads.
const INLINE_FEATURES: usize = 2_000;
/// The most bodies of an answer computed on the async threads.
const INLINE_BODIES: usize = 256;

/// `q`, held to the budget of the async threads when `inline`.
fn inline_sphere(mut q: SphereQuery, inline: bool) -> SphereQuery {
    if inline {
        q.max_features = q.max_features.min(INLINE_FEATURES);
        q.max_bodies = q.max_bodies.min(INLINE_BODIES);
    }
    q
}

/// `q`, held to the budget of the async threads when `inline`.
fn inline_box(mut q: BoxQuery, inline: bool) -> BoxQuery {
    if inline {
        q.max_features = q.max_features.min(INLINE_FEATURES);
        q.max_bodies = q.max_bodies.min(INLINE_BODIES);
    }
    q
}

/// Takes a snapshot and asks the index. A question the current index can answer within
/// the small budget ([`INLINE_FEATURES`], [`INLINE_BODIES`]) is answered at once, on the
/// async thread (a few microseconds, less than handing it to another thread); a larger
/// one, or one that needs the index brought up first, takes a turn and runs on a
/// blocking thread. `ask(index, inline)` must honour the budget when `inline`. Answers
/// carry the index's revision in `ETag`.
async fn run<T>(
    state: &AppState,
    ask: impl Fn(&Spatial, bool) -> Result<T, QueryError> + Send + 'static,
) -> Answer
where
    T: Serialize + Revised + Send + 'static,
{
    let world = snapshot(&state.handle).await?;
    let access = state.spatial.clone();
    if let Some(answer) = access.try_current(world.revision(), |s| ask(s, true)) {
        match answer {
            Ok(a) => return Ok(read_answer(a.revision(), a)),
            // Over the small budget: asked again below with the request's own limits.
            Err(QueryError::TooManyFeatures { .. } | QueryError::TooManyBodies { .. }) => {}
            Err(e) => return Err(refused(e)),
        }
    }
    let _turn = access
        .permits
        .clone()
        .acquire_owned()
        .await
        .map_err(|_| Problem::unavailable())?;
    let feed = state.feed.clone();
    let answer =
        tokio::task::spawn_blocking(move || access.answer(world, &feed, |s| ask(s, false)))
            .await
            .map_err(Problem::internal)?
            .map_err(refused)?;
    Ok(read_answer(answer.revision(), answer))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::server::changes::{Change, EntityChange};

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

    #[test]
    fn query_string_numbers_are_checked_by_name() {
        let p = sphere_query([f64::NAN, 0.0, 0.0], 1.0, None, None, None, &QUERY_NAMES)
            .expect_err("NaN refused");
        assert_eq!(p.status, StatusCode::UNPROCESSABLE_ENTITY);
        assert!(p.detail.contains("x, y and z"), "{}", p.detail);
        let p = sphere_query([0.0; 3], -1.0, None, None, None, &JSON_NAMES).expect_err("radius");
        assert!(p.detail.starts_with("radius"), "{}", p.detail);
        let p = sphere_query([0.0; 3], 1.0, None, Some(0.0), None, &JSON_NAMES).expect_err("tol");
        assert!(p.detail.starts_with("tolerance"), "{}", p.detail);
        let p = box_query([0.0, 2.0, 0.0], [1.0; 3], None, None, &QUERY_NAMES).expect_err("empty");
        assert!(
            p.detail.contains("min_y (2) exceeds max_y (1)"),
            "{}",
            p.detail
        );
        let p = direction([0.0; 3], &QUERY_NAMES).expect_err("zero");
        assert!(p.detail.starts_with("dx, dy and dz"), "{}", p.detail);
        assert_eq!(
            direction([1e308, 1e308, 0.0], &JSON_NAMES).ok(),
            Some(DVec3::new(1.0, 1.0, 0.0))
        );
        let p = point([0.0, 0.0, 1e155], "x, y and z").expect_err("beyond the query limit");
        assert!(p.detail.contains("within 1e12 m"), "{}", p.detail);
        let b = box_query([-1e308; 3], [1e308; 3], None, None, &JSON_NAMES).expect("clamped");
        assert_eq!(
            (b.min, b.max),
            (DVec3::splat(-QUERY_LIMIT), DVec3::splat(QUERY_LIMIT))
        );
        assert_eq!(max_distance(Some(1e300)).ok(), Some(f64::INFINITY));
        assert!(max_distance(Some(f64::NAN)).is_err());
        assert!(max_distance(Some(-1.0)).is_err());
        assert_eq!(max_features(Some(usize::MAX)), MAX_FEATURES);
        assert_eq!(
            refused(QueryError::TooManyFeatures { limit: 3 }).kind,
            "too-many-features"
        );
    }
}
