//! Prometheus metrics: HTTP traffic, the actor's queue, the journal, snapshots and the size
//! of the world, exposed in the OpenMetrics text format.
//!
//! # Wiring
//!
//! ```no_run
//! use std::sync::Arc;
//! use axum::{Router, middleware::from_fn_with_state, routing::get};
//! use winged::server::metrics::{self, Metrics};
//!
//! # async fn h() {}
//! let m = Arc::new(Metrics::new());
//! let app: Router = Router::new()
//!     .route("/v1/bodies/{id}", get(h))
//!     .merge(metrics::routes(m.clone())) // GET /metrics
//!     // `layer`, not `route_layer`, so unmatched requests are counted too.
//!     .layer(from_fn_with_state(m.clone(), metrics::track));
//! ```
//!
//! The actor and the journal report through [`Metrics::set_queue_depth`],
//! [`Metrics::observe_commit`], [`Metrics::set_world`] and friends on a shared
//! `Arc<Metrics>`.

use std::sync::Arc;
use std::time::{Duration, Instant};

use axum::Router;
use axum::extract::{MatchedPath, Request, State};
use axum::http::{HeaderValue, Method, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use prometheus_client::encoding::EncodeLabelSet;
use prometheus_client::encoding::text::encode;
use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::{
    Histogram, exponential_buckets, exponential_buckets_range,
};
use prometheus_client::registry::{Registry, Unit};

/// The Content-Type of [`Metrics::render`]'s output.
pub const CONTENT_TYPE: &str = "application/openmetrics-text; version=1.0.0; charset=utf-8";

/// The route label of requests that matched no route.
pub const UNMATCHED: &str = "unmatched";

/// Labels of the request counter.
#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct RequestLabels {
    route: String,
    method: &'static str,
    status: u16,
}

type HistogramFamily = Family<RequestLabels, Histogram, fn() -> Histogram>;

/// How the spatial index came to be built.
#[derive(Clone, Copy, Debug, Hash, PartialEq, Eq)]
pub enum IndexBuild {
    /// A whole build, shapes and all: by the first query, or by the next query after a
    /// panic dropped the index.
    First,
    /// A rebuild of a worn index under its lock (queries wait for it).
    InPlace,
    /// A rebuild on a thread of its own that took the worn index's place (queries went
    /// on with the worn index meanwhile).
    Background,
    /// A rebuild on a thread of its own that was dropped: the index had been rebuilt in
    /// place meanwhile.
    Dropped,
}

impl IndexBuild {
    /// The label value.
    fn label(self) -> &'static str {
        match self {
            IndexBuild::First => "first",
            IndexBuild::InPlace => "in_place",
            IndexBuild::Background => "background",
            IndexBuild::Dropped => "dropped",
        }
    }
}

/// Labels of the spatial index build counter.
#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct IndexBuildLabels {
    how: &'static str,
}

fn request_duration_histogram() -> Histogram {
    // 100 µs .. 30 s, 20 buckets (a factor of about 1.94 apart).
    Histogram::new(exponential_buckets_range(0.000_1, 30.0, 20))
}

/// Every metric the server exports, registered in one registry.
///
/// Shared as `Arc<Metrics>`; every method takes `&self` and is safe to call from any thread.
pub struct Metrics {
    registry: Registry,
    requests: Family<RequestLabels, Counter>,
    request_duration: HistogramFamily,
    queue_depth: Gauge,
    edits_planning: Gauge,
    commit_duration: Histogram,
    batch_entries: Histogram,
    overload_rejections: Counter,
    connections_open: Gauge,
    connections_refused: Counter,
    world_revision: Gauge,
    world_bodies: Gauge,
    world_faces: Gauge,
    world_edges: Gauge,
    world_vertices: Gauge,
    snapshot_duration: Histogram,
    index_builds: Family<IndexBuildLabels, Counter>,
    index_build_duration: Histogram,
}

impl std::fmt::Debug for Metrics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Metrics").finish_non_exhaustive()
    }
}

impl Default for Metrics {
    fn default() -> Self {
        Metrics::new()
    }
}

/// A count as a gauge value, saturating at `i64::MAX`.
fn gauge_value<T: TryInto<i64>>(n: T) -> i64 {
    n.try_into().unwrap_or(i64::MAX)
}

impl Metrics {
    /// All families registered, every value zero.
    pub fn new() -> Metrics {
        let mut registry = Registry::default();

        let requests = Family::<RequestLabels, Counter>::default();
        registry.register(
            "winged_http_requests",
            "HTTP requests answered, by route template, method and status",
            requests.clone(),
        );
        let request_duration: HistogramFamily =
            Family::new_with_constructor(request_duration_histogram);
        registry.register_with_unit(
            "winged_http_request_duration",
            "Time from receiving an HTTP request to sending its response head, by route template, method and status",
            Unit::Seconds,
            request_duration.clone(),
        );
        let queue_depth = Gauge::default();
        registry.register(
            "winged_actor_queue_depth",
            "Edits waiting for the world's owner",
            queue_depth.clone(),
        );
        let edits_planning = Gauge::default();
        registry.register(
            "winged_edits_planning",
            "Large edits being planned (their bodies built) beside the world's owner",
            edits_planning.clone(),
        );
        // 10 µs .. 10 s.
        let commit_duration = Histogram::new(exponential_buckets_range(0.000_01, 10.0, 19));
        registry.register_with_unit(
            "winged_journal_commit_duration",
            "Time to make one batch of journal entries durable",
            Unit::Seconds,
            commit_duration.clone(),
        );
        // 1 .. 8192 entries.
        let batch_entries = Histogram::new(exponential_buckets(1.0, 2.0, 14));
        registry.register(
            "winged_journal_batch_entries",
            "Journal entries committed together in one batch",
            batch_entries.clone(),
        );
        let overload_rejections = Counter::default();
        registry.register(
            "winged_overload_rejections",
            "Requests refused because the world's owner was overloaded",
            overload_rejections.clone(),
        );
        let connections_open = Gauge::default();
        registry.register(
            "winged_http_connections_open",
            "HTTP connections open",
            connections_open.clone(),
        );
        let connections_refused = Counter::default();
        registry.register(
            "winged_http_connections_refused",
            "HTTP connections answered 503 and closed because every place under the connection cap was busy",
            connections_refused.clone(),
        );
        let world = |registry: &mut Registry, name: &str, help: &str| {
            let g = Gauge::default();
            registry.register(name, help, g.clone());
            g
        };
        let world_revision = world(
            &mut registry,
            "winged_world_revision",
            "Revision of the world",
        );
        let world_bodies = world(&mut registry, "winged_world_bodies", "Bodies in the world");
        let world_faces = world(
            &mut registry,
            "winged_world_faces",
            "Faces of all bodies in the world",
        );
        let world_edges = world(
            &mut registry,
            "winged_world_edges",
            "Edges of all bodies in the world",
        );
        let world_vertices = world(
            &mut registry,
            "winged_world_vertices",
            "Vertices of all bodies in the world",
        );
        // 1 ms .. 300 s.
        let snapshot_duration = Histogram::new(exponential_buckets_range(0.001, 300.0, 19));
        registry.register_with_unit(
            "winged_snapshot_duration",
            "Time to write one snapshot of the world",
            Unit::Seconds,
            snapshot_duration.clone(),
        );

        let index_builds = Family::<IndexBuildLabels, Counter>::default();
        registry.register(
            "winged_spatial_index_builds",
            "Builds of the spatial index's hierarchy, by how: first, in_place (queries waited), background (queries went on), dropped (a background build overtaken)",
            index_builds.clone(),
        );
        // 100 µs .. 100 s.
        let index_build_duration = Histogram::new(exponential_buckets_range(0.000_1, 100.0, 19));
        registry.register_with_unit(
            "winged_spatial_index_build_duration",
            "Time to build the spatial index's hierarchy (a background build's catching up not included)",
            Unit::Seconds,
            index_build_duration.clone(),
        );

        Metrics {
            registry,
            requests,
            request_duration,
            queue_depth,
            edits_planning,
            commit_duration,
            batch_entries,
            overload_rejections,
            connections_open,
            connections_refused,
            world_revision,
            world_bodies,
            world_faces,
            world_edges,
            world_vertices,
            snapshot_duration,
            index_builds,
            index_build_duration,
        }
    }

    /// Records one build of the spatial index's hierarchy, made `how`, that took
    /// `elapsed` (a dropped build is counted and not timed: its time was counted when it
    /// was built).
    pub fn observe_index_build(&self, how: IndexBuild, elapsed: Duration) {
        self.index_builds
            .get_or_create(&IndexBuildLabels { how: how.label() })
            .inc();
        if how != IndexBuild::Dropped {
            self.index_build_duration.observe(elapsed.as_secs_f64());
        }
    }

    /// Records one journal commit that took `elapsed` and made `entries` entries durable.
    pub fn observe_commit(&self, elapsed: Duration, entries: usize) {
        self.commit_duration.observe(elapsed.as_secs_f64());
        self.batch_entries.observe(entries as f64);
    }

    /// Sets the number of edits waiting for the world's owner.
    pub fn set_queue_depth(&self, depth: i64) {
        self.queue_depth.set(depth);
    }

    /// Counts one request refused for overload.
    pub fn reject_overload(&self) {
        self.overload_rejections.inc();
    }

    /// Sets the number of open HTTP connections.
    pub fn set_open_connections(&self, open: usize) {
        self.connections_open.set(gauge_value(open));
    }

    /// Counts one HTTP connection refused at the connection cap.
    pub fn refuse_connection(&self) {
        self.connections_refused.inc();
    }

    /// Sets the world gauges. Values beyond `i64::MAX` are shown as `i64::MAX`.
    pub fn set_world(
        &self,
        revision: u64,
        bodies: usize,
        faces: usize,
        edges: usize,
        vertices: usize,
    ) {
        self.world_revision.set(gauge_value(revision));
        self.world_bodies.set(gauge_value(bodies));
        self.world_faces.set(gauge_value(faces));
        self.world_edges.set(gauge_value(edges));
        self.world_vertices.set(gauge_value(vertices));
    }

    /// Records one snapshot that took `elapsed`.
    pub fn observe_snapshot(&self, elapsed: Duration) {
        self.snapshot_duration.observe(elapsed.as_secs_f64());
    }

    /// Records one answered HTTP request.
    ///
    /// Precondition: `route` is a route template or [`UNMATCHED`], never a raw path, so the
    /// number of label values stays bounded.
    pub fn observe_request(&self, route: &str, method: &Method, status: u16, elapsed: Duration) {
        let method = method_label(method);
        self.requests
            .get_or_create(&RequestLabels {
                route: route.to_owned(),
                method,
                status,
            })
            .inc();
        self.request_duration
            .get_or_create(&RequestLabels {
                route: route.to_owned(),
                method,
                status,
            })
            .observe(elapsed.as_secs_f64());
    }

    /// The OpenMetrics text exposition of every metric, ending in `# EOF`; serve it with
    /// Content-Type [`CONTENT_TYPE`]. The labelled HTTP families appear once the first
    /// request was observed.
    pub fn render(&self) -> String {
        let mut out = String::new();
        // Writing into a String cannot fail; an encoder error would leave a partial text.
        if encode(&mut out, &self.registry).is_err() {
            tracing::error!("encoding metrics failed");
        }
        out
    }
}

/// The method as a label value: the standard methods by name, anything else as `OTHER`, so
/// clients cannot grow the label set.
fn method_label(method: &Method) -> &'static str {
    match method.as_str() {
        "GET" => "GET",
        "HEAD" => "HEAD",
        "POST" => "POST",
        "PUT" => "PUT",
        "PATCH" => "PATCH",
        "DELETE" => "DELETE",
        "OPTIONS" => "OPTIONS",
        "CONNECT" => "CONNECT",
        "TRACE" => "TRACE",
        _ => "OTHER",
    }
}

/// Middleware counting and timing every request by matched route template (e.g.
/// `/v1/bodies/{id}`; [`UNMATCHED`] when no route matched), method and status.
///
/// Install with `Router::layer(axum::middleware::from_fn_with_state(metrics, track))` so that
/// the matched path is known and fallback answers are counted. The duration is measured up to
/// the response head, not to the end of a streamed body.
pub async fn track(State(m): State<Arc<Metrics>>, req: Request, next: Next) -> Response {
    let start = Instant::now();
    let route = req
        .extensions()
        .get::<MatchedPath>()
        .map(|p| p.as_str().to_owned());
    let method = req.method().clone();
    let res = next.run(req).await;
    m.observe_request(
        route.as_deref().unwrap_or(UNMATCHED),
        &method,
        res.status().as_u16(),
        start.elapsed(),
    );
    res
}

/// Handler answering [`Metrics::render`] with Content-Type [`CONTENT_TYPE`].
pub async fn metrics_handler(State(m): State<Arc<Metrics>>) -> Response {
    let mut res = m.render().into_response();
    res.headers_mut()
        .insert(header::CONTENT_TYPE, HeaderValue::from_static(CONTENT_TYPE));
    res
}

/// A router serving `GET /metrics` from `metrics`, ready to `merge` into a router of any
/// state.
pub fn routes<S: Clone + Send + Sync + 'static>(metrics: Arc<Metrics>) -> Router<S> {
    Router::new()
        .route("/metrics", get(metrics_handler))
        .with_state(metrics)
}

impl super::actor::Observer for Metrics {
    fn committed(&self, elapsed: Duration, entries: usize) {
        self.observe_commit(elapsed, entries);
    }
    fn overloaded(&self) {
        self.reject_overload();
    }
    fn snapshotted(&self, elapsed: Duration, _bytes: u64) {
        self.observe_snapshot(elapsed);
    }
    fn planning(&self, change: i64) {
        self.edits_planning.inc_by(change);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use axum::http::StatusCode;
    use axum::middleware::from_fn_with_state;

    /// The value of the sample line starting with `prefix` (name and labels).
    fn sample(text: &str, prefix: &str) -> Option<f64> {
        text.lines()
            .find_map(|l| l.strip_prefix(prefix))
            .and_then(|v| v.trim().parse().ok())
    }

    #[test]
    fn render_lists_every_family() {
        let m = Metrics::new();
        // Labelled families are listed once they have a child.
        assert!(!m.render().contains("winged_http_requests"));
        m.observe_request("/v1/world", &Method::GET, 200, Duration::from_micros(50));
        m.observe_commit(Duration::from_millis(3), 5);
        m.set_queue_depth(7);
        m.reject_overload();
        m.reject_overload();
        m.set_open_connections(3);
        m.refuse_connection();
        m.set_world(42, 2, 12, 24, 16);
        m.observe_snapshot(Duration::from_millis(250));
        m.observe_index_build(IndexBuild::First, Duration::from_millis(90));
        m.observe_index_build(IndexBuild::Background, Duration::from_millis(40));
        m.observe_index_build(IndexBuild::Background, Duration::from_millis(50));
        m.observe_index_build(IndexBuild::Dropped, Duration::ZERO);
        let text = m.render();
        for family in [
            "# TYPE winged_http_requests counter",
            "# TYPE winged_http_request_duration_seconds histogram",
            "# TYPE winged_actor_queue_depth gauge",
            "# TYPE winged_journal_commit_duration_seconds histogram",
            "# TYPE winged_journal_batch_entries histogram",
            "# TYPE winged_overload_rejections counter",
            "# TYPE winged_http_connections_open gauge",
            "# TYPE winged_http_connections_refused counter",
            "# TYPE winged_world_revision gauge",
            "# TYPE winged_world_bodies gauge",
            "# TYPE winged_world_faces gauge",
            "# TYPE winged_world_edges gauge",
            "# TYPE winged_world_vertices gauge",
            "# TYPE winged_snapshot_duration_seconds histogram",
            "# TYPE winged_spatial_index_builds counter",
            "# TYPE winged_spatial_index_build_duration_seconds histogram",
        ] {
            assert!(text.contains(family), "{family} missing from\n{text}");
        }
        assert!(text.ends_with("# EOF\n"));
        assert_eq!(sample(&text, "winged_actor_queue_depth "), Some(7.0));
        assert_eq!(
            sample(&text, "winged_overload_rejections_total "),
            Some(2.0)
        );
        assert_eq!(sample(&text, "winged_http_connections_open "), Some(3.0));
        assert_eq!(
            sample(&text, "winged_http_connections_refused_total "),
            Some(1.0)
        );
        assert_eq!(sample(&text, "winged_world_revision "), Some(42.0));
        assert_eq!(sample(&text, "winged_world_vertices "), Some(16.0));
        assert_eq!(
            sample(&text, "winged_journal_batch_entries_sum "),
            Some(5.0)
        );
        assert_eq!(
            sample(&text, "winged_journal_commit_duration_seconds_count "),
            Some(1.0)
        );
        assert_eq!(
            sample(
                &text,
                "winged_snapshot_duration_seconds_bucket{le=\"0.001\"} "
            ),
            Some(0.0)
        );
        assert_eq!(
            sample(
                &text,
                "winged_snapshot_duration_seconds_bucket{le=\"+Inf\"} "
            ),
            Some(1.0)
        );
        assert_eq!(
            sample(
                &text,
                "winged_spatial_index_builds_total{how=\"background\"} "
            ),
            Some(2.0)
        );
        assert_eq!(
            sample(&text, "winged_spatial_index_builds_total{how=\"dropped\"} "),
            Some(1.0)
        );
        // The dropped build is not timed again.
        assert_eq!(
            sample(&text, "winged_spatial_index_build_duration_seconds_count "),
            Some(3.0)
        );
        m.set_world(u64::MAX, 0, 0, 0, 0);
        assert_eq!(
            sample(&m.render(), "winged_world_revision "),
            Some(i64::MAX as f64)
        );
    }

    #[test]
    fn odd_methods_share_one_label() {
        let m = Method::from_bytes(b"BREW").unwrap();
        assert_eq!(method_label(&m), "OTHER");
        assert_eq!(method_label(&Method::PATCH), "PATCH");
    }

    #[test]
    fn requests_are_counted_by_route_template() {
        let m = Arc::new(Metrics::new());
        let app: Router = Router::new()
            .route("/v1/bodies/{id}", get(|| async { "body" }))
            .route(
                "/v1/fail",
                get(|| async { (StatusCode::UNPROCESSABLE_ENTITY, "no") }),
            )
            .merge(routes(m.clone()))
            .layer(from_fn_with_state(m.clone(), track));

        let server =
            crate::server::background::Background::router("127.0.0.1:0".parse().unwrap(), app)
                .unwrap();
        let base = server.base();
        let agent: ureq::Agent = ureq::Agent::config_builder()
            .http_status_as_error(false)
            .build()
            .into();
        let status = |path: &str| agent.get(format!("{base}{path}")).call().unwrap().status();
        for id in 1..=3 {
            assert_eq!(status(&format!("/v1/bodies/{id}")), 200);
        }
        assert_eq!(status("/v1/fail"), 422);
        assert_eq!(status("/no/such/path/123"), 404);
        assert_eq!(status("/no/such/path/456"), 404);
        let mut res = agent.get(format!("{base}/metrics")).call().unwrap();
        let content_type = res.headers().get("content-type").cloned();
        let text = res.body_mut().read_to_string().unwrap();
        drop(agent);
        server.stop().unwrap();

        assert_eq!(
            content_type.as_ref().and_then(|v| v.to_str().ok()),
            Some(CONTENT_TYPE)
        );
        let count =
            |labels: &str| sample(&text, &format!("winged_http_requests_total{{{labels}}} "));
        assert_eq!(
            count(r#"route="/v1/bodies/{id}",method="GET",status="200""#),
            Some(3.0),
            "{text}"
        );
        assert_eq!(
            count(r#"route="/v1/fail",method="GET",status="422""#),
            Some(1.0)
        );
        assert_eq!(
            count(r#"route="unmatched",method="GET",status="404""#),
            Some(2.0)
        );
        assert_eq!(
            sample(
                &text,
                r#"winged_http_request_duration_seconds_count{route="/v1/bodies/{id}",method="GET",status="200"} "#
            ),
            Some(3.0)
        );
        assert!(!text.contains("/v1/bodies/1"), "a raw path became a label");
        assert!(!text.contains("/no/such"), "a raw path became a label");
        // The scrape itself is counted only after its body was rendered.
        assert_eq!(count(r#"route="/metrics",method="GET",status="200""#), None);
        assert_eq!(
            sample(
                &m.render(),
                "winged_http_requests_total{route=\"/metrics\",method=\"GET\",status=\"200\"} "
            ),
            Some(1.0)
        );
    }
}
