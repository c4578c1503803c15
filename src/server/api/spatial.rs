//! Spatial access over HTTP: `/v1/spatial/{sphere,box,nearest,ray}`, each as a `GET`
//! with a query string and as a `POST` with a JSON body (the query string converted into
//! the body's type, so one handler serves both), answered from the shared index
//! ([`SpatialAccess`](crate::server::index::SpatialAccess)): on the async thread itself
//! when the answer fits a small budget (a few thousand features, a few hundred bodies),
//! else on a blocking thread. Answers carry the index's revision in the body and in
//! `ETag`.
//!
//! Malformed requests (bad JSON or query strings, unknown fields) are answered 400;
//! well-formed ones with values a query cannot take (NaN or infinite numbers, a negative
//! radius, an empty box, a zero direction, a tolerance that is not a positive length, a
//! centre, point or origin farther than [`QUERY_LIMIT`] from the origin on an axis)
//! 422 `invalid-query`, naming the field as the request spells it; an answer that would
//! hold more than `max_features` faces, edges and vertices 422 `too-many-features`.
//! Box corners, radii and distances beyond that limit are clamped to it: the world's
//! content lies well inside (see [`crate::model::range`]), so no answer changes.

use axum::extract::{FromRequest, FromRequestParts, Request, State};
use axum::http::{Method, StatusCode};
use glam::DVec3;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::extract::{ApiJson, ApiQuery};
use super::{Answer, AppState, read_answer, snapshot};
use crate::model::range::{self, QUERY_LIMIT};
use crate::server::problem::Problem;
use crate::spatial::{
    BoxQuery, DEFAULT_MAX_FEATURES, DEFAULT_TOLERANCE, Detail, QueryError, Spatial, SphereQuery,
};

/// The largest `max_features` a request may ask for; larger values are taken as this.
pub const MAX_FEATURES: usize = 1_000_000;

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
    /// How the request spelled its fields, for the problems that point at them.
    #[serde(skip, default = "json_names")]
    names: &'static Names,
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
    /// How the request spelled its fields, for the problems that point at them.
    #[serde(skip, default = "json_names")]
    names: &'static Names,
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
    /// How the request spelled its fields, for the problems that point at them.
    #[serde(skip, default = "json_names")]
    names: &'static Names,
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
    /// How the request spelled its fields, for the problems that point at them.
    #[serde(skip, default = "json_names")]
    names: &'static Names,
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
#[derive(Debug)]
struct Names {
    center: &'static str,
    point: &'static str,
    origin: &'static str,
    radius: &'static str,
    min: [&'static str; 3],
    max: [&'static str; 3],
    direction: &'static str,
    zero_direction: &'static str,
}

const JSON_NAMES: Names = Names {
    center: "center",
    point: "point",
    origin: "origin",
    radius: "radius",
    min: ["min[0]", "min[1]", "min[2]"],
    max: ["max[0]", "max[1]", "max[2]"],
    direction: "direction",
    zero_direction: "direction must not be [0, 0, 0]",
};

const QUERY_NAMES: Names = Names {
    center: "x, y and z",
    point: "x, y and z",
    origin: "x, y and z",
    radius: "r",
    min: ["min_x", "min_y", "min_z"],
    max: ["max_x", "max_y", "max_z"],
    direction: "dx, dy and dz",
    zero_direction: "dx, dy and dz must not all be zero",
};

fn json_names() -> &'static Names {
    &JSON_NAMES
}

impl From<SphereParams> for SphereReq {
    fn from(p: SphereParams) -> Self {
        SphereReq {
            center: [p.x, p.y, p.z],
            radius: p.r,
            detail: p.detail,
            tolerance: p.tolerance,
            max_features: p.max_features,
            names: &QUERY_NAMES,
        }
    }
}

impl From<BoxParams> for BoxReq {
    fn from(p: BoxParams) -> Self {
        BoxReq {
            min: [p.min_x, p.min_y, p.min_z],
            max: [p.max_x, p.max_y, p.max_z],
            detail: p.detail,
            max_features: p.max_features,
            names: &QUERY_NAMES,
        }
    }
}

impl From<NearestParams> for NearestReq {
    fn from(p: NearestParams) -> Self {
        NearestReq {
            point: [p.x, p.y, p.z],
            max_distance: p.max_distance,
            names: &QUERY_NAMES,
        }
    }
}

impl From<RayParams> for RayReq {
    fn from(p: RayParams) -> Self {
        RayReq {
            origin: [p.x, p.y, p.z],
            direction: [p.dx, p.dy, p.dz],
            max_distance: p.max_distance,
            names: &QUERY_NAMES,
        }
    }
}

/// A query as its `POST` route's JSON body gives it, with the query string of its `GET`
/// twin converted into the same type.
trait Twin: DeserializeOwned + Send + 'static {
    /// The `GET` form.
    type Params: DeserializeOwned + Send + 'static + Into<Self>;
}

impl Twin for SphereReq {
    type Params = SphereParams;
}
impl Twin for BoxReq {
    type Params = BoxParams;
}
impl Twin for NearestReq {
    type Params = NearestParams;
}
impl Twin for RayReq {
    type Params = RayParams;
}

/// The query of a spatial route, read from a `GET`'s query string ([`ApiQuery`]) or a
/// `POST`'s JSON body ([`ApiJson`]), refused as those refuse.
pub(super) struct Asked<T>(T);

impl<S: Send + Sync, T: Twin> FromRequest<S> for Asked<T> {
    type Rejection = Problem;

    async fn from_request(req: Request, state: &S) -> Result<Self, Problem> {
        if req.method() == Method::GET {
            let (mut parts, _) = req.into_parts();
            let ApiQuery(params) =
                ApiQuery::<T::Params>::from_request_parts(&mut parts, state).await?;
            Ok(Asked(params.into()))
        } else {
            let ApiJson(query) = ApiJson::<T>::from_request(req, state).await?;
            Ok(Asked(query))
        }
    }
}

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

/// `GET` and `POST /v1/spatial/sphere`.
pub(super) async fn sphere(State(state): State<AppState>, Asked(r): Asked<SphereReq>) -> Answer {
    let q = sphere_query(
        r.center,
        r.radius,
        r.detail,
        r.tolerance,
        r.max_features,
        r.names,
    )?;
    run(&state, move |s, inline| s.sphere(&inline_sphere(q, inline))).await
}

/// `GET` and `POST /v1/spatial/box`.
pub(super) async fn aabb(State(state): State<AppState>, Asked(r): Asked<BoxReq>) -> Answer {
    let q = box_query(r.min, r.max, r.detail, r.max_features, r.names)?;
    run(&state, move |s, inline| s.aabb(&inline_box(q, inline))).await
}

/// `GET` and `POST /v1/spatial/nearest`.
pub(super) async fn nearest(State(state): State<AppState>, Asked(r): Asked<NearestReq>) -> Answer {
    let p = point(r.point, r.names.point)?;
    let d = max_distance(r.max_distance)?;
    run(&state, move |s, _| s.nearest(p, d)).await
}

/// `GET` and `POST /v1/spatial/ray`.
pub(super) async fn ray(State(state): State<AppState>, Asked(r): Asked<RayReq>) -> Answer {
    let o = point(r.origin, r.names.origin)?;
    let d = direction(r.direction, r.names)?;
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
