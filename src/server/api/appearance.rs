//! Appearance over HTTP: `GET /v1/cameras/{name}/image` and `POST /v1/appearance`.
//!
//! A request names a camera (or gives one inline), a mode and a format. The handler takes
//! a snapshot of the world, gets the [`Scene`] of its revision (built once per revision
//! and shared by every rendering of it), and draws on a blocking thread, outside the
//! world's owner, so renderings run in parallel with each other and with writes. At most
//! as many renderings as the machine has cores run at once; the others wait for a turn
//! (within the request timeout).
//!
//! Answers carry the world revision drawn in `ETag`, and per mode:
//! * `depth`: `X-Depth-Scale` (meters per unit) and `X-Depth-Background: 0`;
//! * `ids`: `X-Body-Ids`, the legend `value=id` pairs separated by commas (or, when it
//!   would be too long for a header, `X-Body-Ids-Omitted`; `format=json` always has it).

use std::sync::{Arc, Mutex};

use axum::extract::State;
use axum::http::StatusCode;
use axum::http::header::{CONTENT_TYPE, ETAG, HeaderName, HeaderValue};
use axum::response::IntoResponse;
use serde::{Deserialize, Serialize};
use tokio::sync::Semaphore;

use super::extract::{ApiJson, ApiPath, ApiQuery};
use super::precondition::etag;
use super::{Answer, AppState, snapshot};
use crate::camera::Camera;
use crate::model::World;
use crate::render::hidden::{self, Segment};
use crate::render::{self, Mode, Options, Picture, SHADED_BACKGROUND, Scene};
use crate::server::problem::Problem;
use crate::server::request::CameraReq;

/// The largest image drawn by default, in pixels (4096 × 4096).
pub const MAX_RENDER_PIXELS: u64 = 4096 * 4096;

/// The longest `X-Body-Ids` header written, in bytes.
const MAX_LEGEND_HEADER: usize = 4096;

/// What appearance requests share: the scene of the latest revision drawn and the turns.
pub struct Appearance {
    /// The scene built for the newest revision asked for.
    latest: Mutex<Option<Arc<Scene>>>,
    /// Held while a scene is built, so that one revision is built once.
    building: Mutex<()>,
    /// Renderings allowed at once.
    permits: Arc<Semaphore>,
    /// The largest image, in pixels.
    max_pixels: u64,
}

impl Appearance {
    /// Shared state for at most `max_pixels`-pixel images, with as many renderings at
    /// once as the machine has cores (each rendering itself runs on all of them).
    pub fn new(max_pixels: u64) -> Appearance {
        let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
        Appearance {
            latest: Mutex::new(None),
            building: Mutex::new(()),
            permits: Arc::new(Semaphore::new(cores)),
            max_pixels,
        }
    }

    /// The scene of `world`'s revision: the cached one, or a new one built now (and
    /// cached unless a newer one already is). Blocking: call off the async threads.
    pub(super) fn scene(&self, world: &World) -> Arc<Scene> {
        let cached = |this: &Appearance| {
            this.latest
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .clone()
                .filter(|s| s.revision == world.revision())
        };
        if let Some(s) = cached(self) {
            return s;
        }
        let _building = self.building.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(s) = cached(self) {
            return s;
        }
        let scene = Arc::new(Scene::build(world));
        let mut latest = self.latest.lock().unwrap_or_else(|p| p.into_inner());
        if latest.as_ref().is_none_or(|s| s.revision <= scene.revision) {
            *latest = Some(scene.clone());
        }
        scene
    }
}

/// An image format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// A PNG image (every mode).
    #[default]
    Png,
    /// JSON: the segments of `hidden`, the legend and pixel counts of `ids`.
    Json,
    /// SVG: the segments of `hidden`.
    Svg,
}

/// What to draw and how, as a request gives it: the query string of
/// `GET /v1/cameras/{name}/image` (whose path names the camera), or the JSON body of
/// `POST /v1/appearance` (which must name or give the camera).
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Drawing {
    /// The camera: in a `POST /v1/appearance` body only.
    #[serde(default)]
    pub camera: Option<CameraRef>,
    /// The mode (default `shaded`).
    #[serde(default)]
    pub mode: Mode,
    /// The format (default `png`).
    #[serde(default)]
    pub format: Format,
    /// Image width; the camera's intrinsics are scaled to it (default: the camera's).
    #[serde(default)]
    pub width: Option<u32>,
    /// Image height; with only a width, the camera's aspect ratio is kept.
    #[serde(default)]
    pub height: Option<u32>,
    /// Background colour `#rrggbb` (a query may leave out the `#`).
    #[serde(default)]
    pub background: Option<String>,
    /// Cast shadows in `shaded` (default true).
    #[serde(default)]
    pub shadows: Option<bool>,
    /// Near-plane distance, meters (default 0.01).
    #[serde(default)]
    pub near: Option<f64>,
    /// Meters per unit of a `depth` image (default 0.001).
    #[serde(default)]
    pub depth_scale: Option<f64>,
}

/// A stored camera's name, or a camera given inline.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum CameraRef {
    /// The name of a camera in the world.
    Named(String),
    /// A camera as `PUT /v1/cameras/{name}` takes it.
    Inline(Box<CameraReq>),
}

impl CameraRef {
    /// The camera named (404 when the world has none of that name) or given inline
    /// (422 `invalid-camera` when it is not a valid camera).
    pub fn resolve(&self, world: &World) -> Result<Camera, Problem> {
        match self {
            CameraRef::Named(name) => world
                .camera(name)
                .copied()
                .ok_or_else(|| Problem::not_found(format!("no camera is named {name:?}"))),
            CameraRef::Inline(req) => req.to_camera().map_err(|e| {
                Problem::new(
                    StatusCode::UNPROCESSABLE_ENTITY,
                    "invalid-camera",
                    "Invalid camera",
                    e.to_string(),
                )
            }),
        }
    }
}

/// A drawing checked and resolved against a camera.
struct Plan {
    camera: Camera,
    mode: Mode,
    format: Format,
    options: Options,
}

fn bad(detail: impl Into<String>) -> Problem {
    Problem::bad_request(detail)
}

impl Drawing {
    /// Checks the drawing and resolves it against `camera`: size, colours, numbers, and
    /// whether the format suits the mode.
    fn plan(&self, camera: Camera, max_pixels: u64) -> Result<Plan, Problem> {
        let format_ok = match self.format {
            Format::Png => true,
            Format::Json => matches!(self.mode, Mode::Hidden | Mode::Ids),
            Format::Svg => self.mode == Mode::Hidden,
        };
        if !format_ok {
            return Err(Problem::new(
                StatusCode::UNPROCESSABLE_ENTITY,
                "render-refused",
                "Cannot draw this",
                format!(
                    "format {:?} is not available for mode {}: json is for hidden and ids, \
                 svg for hidden, png for every mode",
                    self.format,
                    self.mode.name()
                ),
            ));
        }
        let camera = resize(camera, self.width, self.height)?;
        let k = camera.intrinsics;
        let pixels = k.width as u64 * k.height as u64;
        if pixels > max_pixels {
            return Err(Problem::new(
                StatusCode::UNPROCESSABLE_ENTITY,
                "render-too-large",
                "Image too large",
                format!(
                    "a {}×{} image has {pixels} pixels; this server draws at most {max_pixels}",
                    k.width, k.height
                ),
            ));
        }
        let mut options = Options::default();
        if self.mode == Mode::Shaded {
            options.background = SHADED_BACKGROUND;
        }
        if let Some(bg) = &self.background {
            let hex = if bg.starts_with('#') {
                bg.clone()
            } else {
                format!("#{bg}")
            };
            options.background = crate::model::Color::from_hex(&hex)
                .ok_or_else(|| bad(format!("background {bg:?} is not a colour #rrggbb")))?
                .0;
        }
        if let Some(s) = self.shadows {
            options.shadows = s;
        }
        if let Some(near) = self.near {
            if !near.is_finite() || near <= 0.0 {
                return Err(bad(format!(
                    "near {near} must be a positive number of meters"
                )));
            }
            options.near = near;
        }
        if let Some(scale) = self.depth_scale {
            if !scale.is_finite() || scale <= 0.0 {
                return Err(bad(format!(
                    "depth_scale {scale} must be a positive number of meters per unit"
                )));
            }
            options.depth_scale = scale;
        }
        Ok(Plan {
            camera,
            mode: self.mode,
            format: self.format,
            options,
        })
    }
}

/// `camera` with its intrinsics scaled to `width × height` (either may be left out: the
/// other follows the camera's aspect ratio).
fn resize(camera: Camera, width: Option<u32>, height: Option<u32>) -> Result<Camera, Problem> {
    let k = camera.intrinsics;
    let (w0, h0) = (k.width as f64, k.height as f64);
    let (w, h) = match (width, height) {
        (None, None) => return Ok(camera),
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (
            w,
            (h0 * w as f64 / w0).round().max(1.0).min(u32::MAX as f64) as u32,
        ),
        (None, Some(h)) => (
            (w0 * h as f64 / h0).round().max(1.0).min(u32::MAX as f64) as u32,
            h,
        ),
    };
    let (sx, sy) = (w as f64 / w0, h as f64 / h0);
    let intrinsics =
        crate::model::Intrinsics::new(w, h, k.fx * sx, k.fy * sy, k.cx * sx, k.cy * sy)
            .map_err(|e| bad(e.to_string()))?;
    Ok(Camera {
        pose: camera.pose,
        intrinsics,
    })
}

/// `GET /v1/cameras/{name}/image?mode=&format=&width=&height=&...`.
pub(super) async fn camera_image(
    State(state): State<AppState>,
    ApiPath(name): ApiPath<String>,
    ApiQuery(drawing): ApiQuery<Drawing>,
) -> Answer {
    if drawing.camera.is_some() {
        return Err(bad(
            "the camera is the one the path names; leave out camera=",
        ));
    }
    draw(&state, CameraRef::Named(name), drawing).await
}

/// `POST /v1/appearance`.
pub(super) async fn appearance(
    State(state): State<AppState>,
    ApiJson(mut drawing): ApiJson<Drawing>,
) -> Answer {
    let camera = drawing
        .camera
        .take()
        .ok_or_else(|| bad("give the camera: a stored camera's name, or one inline"))?;
    draw(&state, camera, drawing).await
}

/// Resolves the camera on a snapshot, then renders and encodes off the async threads.
async fn draw(state: &AppState, camera: CameraRef, drawing: Drawing) -> Answer {
    let world = snapshot(&state.handle).await?;
    let camera = camera.resolve(&world)?;
    let appearance = state.appearance.clone();
    let plan = drawing.plan(camera, appearance.max_pixels)?;
    let _turn = appearance
        .permits
        .clone()
        .acquire_owned()
        .await
        .map_err(|_| Problem::unavailable())?;
    let revision = world.revision();
    let started = std::time::Instant::now();
    let answer = tokio::task::spawn_blocking(move || {
        let scene = appearance.scene(&world);
        let picture =
            render::render(&scene, &plan.camera, plan.mode, &plan.options).map_err(|e| {
                Problem::new(
                    StatusCode::UNPROCESSABLE_ENTITY,
                    "render-refused",
                    "Cannot draw this",
                    e.to_string(),
                )
            })?;
        Ok::<_, Problem>(encode(&scene, picture, plan.format, &plan.options))
    })
    .await
    .map_err(Problem::internal)??;
    tracing::debug!(
        mode = plan.mode.name(),
        revision,
        elapsed_ms = started.elapsed().as_secs_f64() * 1e3,
        "rendered"
    );
    let mut response = (
        [(CONTENT_TYPE, HeaderValue::from_static(answer.content_type))],
        answer.body,
    )
        .into_response();
    let headers = response.headers_mut();
    headers.insert(ETAG, etag(revision));
    for (name, value) in answer.headers {
        if let Ok(v) = HeaderValue::from_str(&value) {
            headers.insert(HeaderName::from_static(name), v);
        }
    }
    Ok(response)
}

/// An encoded answer.
struct Encoded {
    content_type: &'static str,
    body: Vec<u8>,
    headers: Vec<(&'static str, String)>,
}

/// `hidden` as JSON.
#[derive(Serialize)]
struct HiddenJson<'a> {
    revision: u64,
    width: u32,
    height: u32,
    segments: &'a [Segment],
}

/// One body of the `ids` legend, as JSON.
#[derive(Serialize)]
struct LegendEntry {
    /// The pixel value.
    value: u16,
    /// The body's id.
    id: u64,
    /// Its name.
    name: Option<String>,
    /// Pixels it covers.
    pixels: u64,
    /// `[u_min, v_min, u_max, v_max]`: the pixel box it covers (max exclusive).
    bbox: [u32; 4],
}

/// `ids` as JSON.
#[derive(Serialize)]
struct IdsJson {
    revision: u64,
    width: u32,
    height: u32,
    bodies: Vec<LegendEntry>,
}

/// Encodes a picture in `format` (checked against the mode by [`Drawing::plan`]).
fn encode(scene: &Scene, picture: Picture, format: Format, options: &Options) -> Encoded {
    let png = |body: Vec<u8>, headers| Encoded {
        content_type: "image/png",
        body,
        headers,
    };
    match picture {
        Picture::Rgb(image) => {
            let body = image.to_png();
            image.recycle();
            png(body, Vec::new())
        }
        Picture::Depth {
            image,
            meters_per_unit,
        } => png(
            image.to_png(),
            vec![
                ("x-depth-scale", format!("{meters_per_unit}")),
                ("x-depth-background", "0".to_owned()),
            ],
        ),
        Picture::Lines {
            segments,
            width,
            height,
        } => match format {
            Format::Json => Encoded {
                content_type: "application/json",
                body: serde_json::to_vec(&HiddenJson {
                    revision: scene.revision,
                    width,
                    height,
                    segments: &segments,
                })
                .unwrap_or_default(),
                headers: Vec::new(),
            },
            Format::Svg => Encoded {
                content_type: "image/svg+xml",
                body: hidden::to_svg(&segments, width, height).into_bytes(),
                headers: Vec::new(),
            },
            Format::Png => png(
                hidden::draw(&segments, width, height, options.background, options.ink).to_png(),
                Vec::new(),
            ),
        },
        Picture::Ids { image, legend } => {
            if format == Format::Json {
                let bodies = legend_entries(scene, &image, &legend);
                return Encoded {
                    content_type: "application/json",
                    body: serde_json::to_vec(&IdsJson {
                        revision: scene.revision,
                        width: image.width,
                        height: image.height,
                        bodies,
                    })
                    .unwrap_or_default(),
                    headers: Vec::new(),
                };
            }
            let text = legend
                .iter()
                .enumerate()
                .map(|(i, id)| format!("{}={}", i + 1, id.get()))
                .collect::<Vec<_>>()
                .join(",");
            let header = if text.len() <= MAX_LEGEND_HEADER {
                ("x-body-ids", text)
            } else {
                (
                    "x-body-ids-omitted",
                    format!(
                        "{} bodies: ask with format=json for the legend",
                        legend.len()
                    ),
                )
            };
            png(image.to_png(), vec![header])
        }
    }
}

/// Per legend entry: pixel count and box.
fn legend_entries(
    scene: &Scene,
    image: &crate::render::Gray16,
    legend: &[crate::model::BodyId],
) -> Vec<LegendEntry> {
    let mut entries: Vec<LegendEntry> = legend
        .iter()
        .enumerate()
        .map(|(i, id)| LegendEntry {
            value: (i + 1) as u16,
            id: id.get(),
            name: scene
                .bodies
                .iter()
                .find(|b| b.id == *id)
                .and_then(|b| b.name.clone()),
            pixels: 0,
            bbox: [u32::MAX, u32::MAX, 0, 0],
        })
        .collect();
    let w = image.width.max(1) as usize;
    for (i, &v) in image.data.iter().enumerate() {
        if v == 0 {
            continue;
        }
        let Some(e) = entries.get_mut(v as usize - 1) else {
            continue;
        };
        let (x, y) = ((i % w) as u32, (i / w) as u32);
        e.pixels += 1;
        e.bbox = [
            e.bbox[0].min(x),
            e.bbox[1].min(y),
            e.bbox[2].max(x + 1),
            e.bbox[3].max(y + 1),
        ];
    }
    entries
}
