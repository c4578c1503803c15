//! Recognition over HTTP: `POST /v1/recognition`, a picture (and optionally a depth
//! picture) and the camera that took it in; the modeled bodies it shows, where they
//! really are, and the regions nothing modeled explains out
//! ([`recognize`](crate::vision::recognize::recognize)).
//!
//! Two forms:
//! * JSON: `{"camera": <name or inline camera>, "image": <base64 PNG>, "depth": <base64
//!   16-bit PNG>, "depth_scale": 0.001, "refine_camera": false, "search":
//!   {"translation_m": 0.1, "rotation_deg": 10}, "unexplained_mask": false, "update":
//!   false}` (only `camera` and `image` required; `"search": null` does not look for
//!   moved bodies);
//! * the raw PNG as the body (`Content-Type: image/png`) with `?camera=NAME` and the
//!   flags `refine_camera`, `unexplained_mask` and `update` in the query (the flags in
//!   the query hold for the JSON form too; its `camera` names the raw form's camera only).
//!
//! Recognition reads a snapshot of the world on a blocking thread, at most one per core
//! at a time (the camera solution's turns). With `update` (the write role), the moved
//! bodies' corrected poses are applied in one write, if the world is still at the
//! revision recognized against (412 otherwise: recognize again).
//!
//! Errors (`application/problem+json`), none of which changes the world: 400 for JSON
//! that does not parse, a PNG or base64 that is broken, a depth PNG that is not 16-bit
//! grey, a raw body without `?camera`; 404 for an unknown camera name; 413 for pictures
//! beyond the decoder's limits; 415 for a body that is neither JSON nor PNG; 422
//! `invalid-camera` (NaN or out of range), `invalid-image` (not the camera's size),
//! `invalid-depth` (not the camera's size, or a bad `depth_scale`), `invalid-parameter`
//! (search bounds), and the camera solution's answers when `refine_camera` fails.

use std::time::Instant;

use axum::Json;
use axum::extract::{Extension, Request, State};
use axum::http::StatusCode;
use axum::http::header::{CONTENT_TYPE, ETAG};
use axum::response::IntoResponse;
use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as BASE64;
use serde::{Deserialize, Serialize};

use super::appearance::CameraRef;
use super::body::{Bodies, from_json, is_json};
use super::camera_solution::{refuse_before_decoding, solve_problem};
use super::extract::ApiQuery;
use super::precondition::etag;
use super::{Answer, AppState, snapshot};
use crate::edit::{Edit, Place};
use crate::model::camera::Camera;
use crate::model::{BodyId, Pose, World};
use crate::server::actor::Applied;
use crate::server::auth::Role;
use crate::server::limits::{ImageLimits, decode_depth_png, decode_png};
use crate::server::problem::Problem;
use crate::server::request::{IntrinsicsDto, PoseDto};
use crate::vision::image::Luma;
use crate::vision::recognize::{
    BodyReport, DepthImage, RecognizeError, RecognizeOptions, SearchBounds, recognize,
};
use crate::vision::solve::align::{EdgePyramid, align_camera};

/// The depth scale when none is given: millimetres, as most RGB-D cameras give them.
const DEFAULT_DEPTH_SCALE: f64 = 0.001;

/// `POST /v1/recognition` as JSON.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecognitionReq {
    /// The camera that took the picture: a stored camera's name or one inline.
    pub camera: CameraRef,
    /// The picture, a base64 PNG (grey or colour, 8 or 16 bits).
    pub image: String,
    /// A depth picture, a base64 16-bit grey PNG of the picture's size (0 = no reading).
    #[serde(default)]
    pub depth: Option<String>,
    /// Meters per unit of `depth` (default 0.001).
    #[serde(default)]
    pub depth_scale: Option<f64>,
    /// Align the camera with the picture first (its pose only roughly known).
    #[serde(default)]
    pub refine_camera: bool,
    /// How far to look for bodies that moved; `null` does not look.
    #[serde(default = "default_search")]
    pub search: Option<SearchReq>,
    /// Answer the unexplained regions as a PNG mask too.
    #[serde(default)]
    pub unexplained_mask: bool,
    /// Apply the moved bodies' corrected poses (the write role).
    #[serde(default)]
    pub update: bool,
}

fn default_search() -> Option<SearchReq> {
    Some(SearchReq::default())
}

/// Search bounds as given.
#[derive(Clone, Copy, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SearchReq {
    /// Meters (default 0.1).
    #[serde(default)]
    pub translation_m: Option<f64>,
    /// Degrees (default 10).
    #[serde(default)]
    pub rotation_deg: Option<f64>,
}

/// The query of the raw-PNG form.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecognitionQuery {
    /// A stored camera's name (the raw form needs it).
    #[serde(default)]
    pub camera: Option<String>,
    /// Align the camera with the picture first.
    #[serde(default)]
    pub refine_camera: bool,
    /// Answer the unexplained regions as a PNG mask too.
    #[serde(default)]
    pub unexplained_mask: bool,
    /// Apply the moved bodies' corrected poses (the write role).
    #[serde(default)]
    pub update: bool,
}

/// The camera as used.
#[derive(Debug, Serialize)]
struct CameraUsed {
    pose: PoseDto,
    intrinsics: IntrinsicsDto,
    /// Whether it was aligned with the picture first.
    refined: bool,
}

/// The evidence for one body.
#[derive(Debug, Serialize)]
struct EvidenceDto {
    /// The fraction of its predicted visible edge length that image edges support.
    edge_support: f64,
    /// Points sampled along its visible edges.
    edge_points: usize,
    /// With depth: the fraction of its predicted pixels whose reading agrees.
    #[serde(skip_serializing_if = "Option::is_none")]
    depth_agreement: Option<f64>,
}

/// One body in view.
#[derive(Debug, Serialize)]
struct BodyDto {
    id: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    status: &'static str,
    score: f64,
    visible_fraction: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    bbox: Option<[f64; 4]>,
    /// Its world pose: where it was found (corrected, for a moved body).
    pose: PoseDto,
    evidence: EvidenceDto,
}

/// One unexplained region.
#[derive(Debug, Serialize)]
struct RegionDto {
    /// Outer boundary, pixels.
    outline: Vec<[f64; 2]>,
    /// Holes, pixels.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    holes: Vec<Vec<[f64; 2]>>,
    /// Pixels².
    area: f64,
    bbox: [f64; 4],
}

/// The answer.
#[derive(Debug, Serialize)]
struct RecognitionAnswer {
    /// The revision recognized against.
    revision: u64,
    camera: CameraUsed,
    bodies: Vec<BodyDto>,
    unexplained: Vec<RegionDto>,
    /// The unexplained regions as a base64 8-bit grey PNG (255 inside), when asked.
    #[serde(skip_serializing_if = "Option::is_none")]
    unexplained_mask: Option<String>,
    /// The revision the update made, when `update` applied corrected poses.
    #[serde(skip_serializing_if = "Option::is_none")]
    updated_revision: Option<u64>,
    elapsed_ms: f64,
}

/// A request, whichever form it came in.
struct Asked {
    camera: CameraRef,
    image: Vec<u8>,
    /// A base64 header to check before decoding, for the JSON form.
    image_base64: Option<String>,
    depth: Option<String>,
    depth_scale: f64,
    refine_camera: bool,
    search: Option<SearchBounds>,
    unexplained_mask: bool,
    update: bool,
}

fn unprocessable(kind: &'static str, title: &'static str, detail: impl Into<String>) -> Problem {
    Problem::new(StatusCode::UNPROCESSABLE_ENTITY, kind, title, detail)
}

fn bad_image(detail: impl Into<String>) -> Problem {
    Problem::new(
        StatusCode::BAD_REQUEST,
        "invalid-image",
        "Invalid image",
        detail,
    )
}

impl SearchReq {
    fn bounds(&self) -> Result<SearchBounds, Problem> {
        let d = SearchBounds::default();
        let bounds = SearchBounds {
            translation_m: self.translation_m.unwrap_or(d.translation_m),
            rotation_deg: self.rotation_deg.unwrap_or(d.rotation_deg),
        };
        if !(bounds.translation_m.is_finite()
            && bounds.translation_m > 0.0
            && bounds.translation_m <= 10.0)
        {
            return Err(unprocessable(
                "invalid-parameter",
                "Invalid parameter",
                format!(
                    "search.translation_m must lie in (0, 10] meters, not {}",
                    bounds.translation_m
                ),
            ));
        }
        if !(bounds.rotation_deg > 0.0 && bounds.rotation_deg <= 180.0) {
            return Err(unprocessable(
                "invalid-parameter",
                "Invalid parameter",
                format!(
                    "search.rotation_deg must lie in (0, 180] degrees, not {}",
                    bounds.rotation_deg
                ),
            ));
        }
        Ok(bounds)
    }
}

/// The request read from its body (within the server's body limits): JSON, or a raw PNG
/// with the query.
async fn asked(query: RecognitionQuery, req: Request) -> Result<Asked, Problem> {
    let content_type = req
        .headers()
        .get(CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_ascii_lowercase();
    if content_type.starts_with("image/png") {
        // The body is read before anything is refused, so that a client that writes it
        // whole before reading gets the answer.
        let image = Bodies::of(&req)?.parse(req, |b| Ok(b.to_vec())).await?;
        let Some(name) = query.camera else {
            return Err(Problem::bad_request(
                "a raw PNG needs the camera that took it: ?camera=NAME",
            ));
        };
        return Ok(Asked {
            camera: CameraRef::Named(name),
            image,
            image_base64: None,
            depth: None,
            depth_scale: DEFAULT_DEPTH_SCALE,
            refine_camera: query.refine_camera,
            search: Some(SearchBounds::default()),
            unexplained_mask: query.unexplained_mask,
            update: query.update,
        });
    }
    if !is_json(req.headers()) {
        return Err(Problem::new(
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            "unsupported-media-type",
            "Unsupported media type",
            "send JSON (application/json) or a PNG (image/png) with ?camera=NAME",
        )
        .unread());
    }
    let req: RecognitionReq = Bodies::of(&req)?.parse(req, from_json).await?;
    let search = req.search.map(|s| s.bounds()).transpose()?;
    let depth_scale = req.depth_scale.unwrap_or(DEFAULT_DEPTH_SCALE);
    if !(depth_scale.is_finite() && depth_scale > 0.0) {
        return Err(unprocessable(
            "invalid-depth",
            "Invalid depth picture",
            format!("depth_scale must be a positive number of meters per unit, not {depth_scale}"),
        ));
    }
    Ok(Asked {
        camera: req.camera,
        image: Vec::new(),
        image_base64: Some(req.image),
        depth: req.depth,
        depth_scale,
        // The query's flags hold for the JSON form too; its camera is the raw form's.
        refine_camera: req.refine_camera || query.refine_camera,
        search,
        unexplained_mask: req.unexplained_mask || query.unexplained_mask,
        update: req.update || query.update,
    })
}

/// The problem answer of a refused recognition.
fn recognize_problem(e: RecognizeError) -> Problem {
    let detail = e.to_string();
    match e {
        RecognizeError::ImageSize { .. } => unprocessable("invalid-image", "Invalid image", detail),
        RecognizeError::DepthSize { .. } => {
            unprocessable("invalid-depth", "Invalid depth picture", detail)
        }
        RecognizeError::Camera(_) => unprocessable("invalid-camera", "Invalid camera", detail),
        RecognizeError::Option { .. } => {
            unprocessable("invalid-parameter", "Invalid parameter", detail)
        }
    }
}

/// What the blocking work gives back.
struct Outcome {
    camera: Camera,
    refined: bool,
    reports: Vec<BodyReport>,
    regions: Vec<crate::vision::image::Region>,
    mask: Option<Vec<u8>>,
}

/// Decodes the pictures and recognizes, on the calling (blocking) thread.
fn run(
    scene: &crate::render::Scene,
    start: Camera,
    png: &[u8],
    depth_png: Option<&[u8]>,
    asked: &AskedOptions,
) -> Result<Outcome, Problem> {
    let limits = ImageLimits::default();
    let decoded = decode_png(png, &limits).map_err(Problem::from)?;
    let k = start.intrinsics;
    if (decoded.width, decoded.height) != (k.width, k.height) {
        return Err(recognize_problem(RecognizeError::ImageSize {
            image_width: decoded.width,
            image_height: decoded.height,
            camera_width: k.width,
            camera_height: k.height,
        }));
    }
    let luma = Luma::from_samples(
        decoded.width,
        decoded.height,
        decoded.channels,
        &decoded.pixels,
    )
    .map_err(|e| solve_problem(e.into()))?;
    let depth = match depth_png {
        Some(bytes) => {
            let d = decode_depth_png(bytes, &limits).map_err(Problem::from)?;
            Some(
                DepthImage::from_units(d.width, d.height, &d.units, asked.depth_scale).map_err(
                    |e| unprocessable("invalid-depth", "Invalid depth picture", e.to_string()),
                )?,
            )
        }
        None => None,
    };
    let options = RecognizeOptions {
        search: asked.search,
        ..RecognizeOptions::default()
    };
    let pyramid = EdgePyramid::of(&luma, &options.refine).map_err(solve_problem)?;
    let camera = if asked.refine_camera {
        align_camera(scene, &start, &pyramid, &options.refine)
            .map_err(solve_problem)?
            .camera
    } else {
        start
    };
    let found = recognize(scene, &camera, &luma, &pyramid, depth.as_ref(), &options)
        .map_err(recognize_problem)?;
    let mask = asked.unexplained_mask.then(|| {
        let m = &found.unexplained_mask;
        mask_png(m.width(), m.height(), m.bits())
    });
    Ok(Outcome {
        camera,
        refined: asked.refine_camera,
        reports: found.bodies,
        regions: found.unexplained,
        mask,
    })
}

/// An 8-bit grey PNG of `bits`: 255 inside, 0 outside.
fn mask_png(width: u32, height: u32, bits: &[bool]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    let samples: Vec<u8> = bits.iter().map(|&b| if b { 255 } else { 0 }).collect();
    let written = encoder
        .write_header()
        .and_then(|mut w| w.write_image_data(&samples));
    if written.is_err() {
        out.clear();
    }
    out
}

/// The options of the blocking work.
struct AskedOptions {
    depth_scale: f64,
    refine_camera: bool,
    search: Option<SearchBounds>,
    unexplained_mask: bool,
}

/// `POST /v1/recognition`.
pub(super) async fn recognition(
    State(state): State<AppState>,
    role: Option<Extension<Role>>,
    ApiQuery(query): ApiQuery<RecognitionQuery>,
    req: Request,
) -> Answer {
    let started = Instant::now();
    let asked = asked(query, req).await?;
    if asked.update {
        let role = role.map_or(Role::Admin, |Extension(r)| r);
        if role < Role::Write {
            return Err(Problem::new(
                StatusCode::FORBIDDEN,
                "forbidden",
                "Forbidden",
                format!(
                    "update needs the {} role; the token holds {role}",
                    Role::Write
                ),
            ));
        }
    }
    let world = snapshot(&state.handle).await?;
    let start = asked.camera.resolve(&world)?;
    let limits = ImageLimits::default();
    let png = match &asked.image_base64 {
        Some(text) => {
            let text = text.trim();
            refuse_before_decoding(text, &start, &limits)?;
            BASE64
                .decode(text)
                .map_err(|e| bad_image(format!("image: not base64 ({e})")))?
        }
        None => asked.image,
    };
    let depth_png = asked
        .depth
        .as_deref()
        .map(|text| {
            BASE64.decode(text.trim()).map_err(|e| {
                Problem::new(
                    StatusCode::BAD_REQUEST,
                    "invalid-depth",
                    "Invalid depth picture",
                    format!("depth: not base64 ({e})"),
                )
            })
        })
        .transpose()?;
    let options = AskedOptions {
        depth_scale: asked.depth_scale,
        refine_camera: asked.refine_camera,
        search: asked.search,
        unexplained_mask: asked.unexplained_mask,
    };
    let _turn = state
        .solves
        .clone()
        .acquire_owned()
        .await
        .map_err(|_| Problem::unavailable())?;
    let appearance = state.appearance.clone();
    let snapshot_world = world.clone();
    let outcome = tokio::task::spawn_blocking(move || {
        let scene = appearance.scene(&snapshot_world);
        run(&scene, start, &png, depth_png.as_deref(), &options)
    })
    .await
    .map_err(Problem::internal)??;
    drop(_turn);

    let bodies: Vec<BodyDto> = outcome
        .reports
        .iter()
        .filter_map(|r| body_dto(&world, r))
        .collect();
    let mut updated_revision = None;
    if asked.update {
        let places = corrected_places(&world, &outcome.reports);
        if !places.is_empty() {
            let Applied { revision, .. } = state
                .handle
                .apply_if(Edit::PlaceBodies { places }, Some(world.revision()))
                .await?;
            updated_revision = Some(revision);
        }
    }
    let k = outcome.camera.intrinsics;
    let elapsed_ms = started.elapsed().as_secs_f64() * 1e3;
    tracing::info!(
        bodies = bodies.len(),
        moved = outcome
            .reports
            .iter()
            .filter(|r| r.motion.is_some())
            .count(),
        unexplained = outcome.regions.len(),
        refined = outcome.refined,
        elapsed_ms,
        "recognized"
    );
    let answer = RecognitionAnswer {
        revision: world.revision(),
        camera: CameraUsed {
            pose: outcome.camera.pose.into(),
            intrinsics: IntrinsicsDto {
                width: k.width,
                height: k.height,
                fx: k.fx,
                fy: k.fy,
                cx: k.cx,
                cy: k.cy,
            },
            refined: outcome.refined,
        },
        bodies,
        unexplained: outcome
            .regions
            .into_iter()
            .map(|r| RegionDto {
                outline: r.outer,
                holes: r.holes,
                area: r.area,
                bbox: r.bbox,
            })
            .collect(),
        unexplained_mask: outcome.mask.map(|png| BASE64.encode(png)),
        updated_revision,
        elapsed_ms,
    };
    let revision = updated_revision.unwrap_or(world.revision());
    Ok(([(ETAG, etag(revision))], Json(answer)).into_response())
}

/// The world pose a report puts its body at: the model's, or for a moved body the
/// model's carried by its motion.
fn found_pose(world: &World, r: &BodyReport) -> Option<Pose> {
    let pose = world.world_pose(r.id)?;
    Some(match &r.motion {
        Some(m) => m.compose(&pose),
        None => pose,
    })
}

fn body_dto(world: &World, r: &BodyReport) -> Option<BodyDto> {
    let pose = found_pose(world, r)?;
    Some(BodyDto {
        id: r.id.get(),
        name: world.node(r.id).and_then(|n| n.name.clone()),
        status: r.status.name(),
        score: r.score,
        visible_fraction: r.visible_fraction,
        bbox: r.bbox,
        pose: pose.into(),
        evidence: EvidenceDto {
            edge_support: r.edge_support,
            edge_points: r.edge_points,
            depth_agreement: r.depth_agreement,
        },
    })
}

/// The moved bodies' new poses relative to their suparts.
fn corrected_places(world: &World, reports: &[BodyReport]) -> Vec<Place> {
    reports
        .iter()
        .filter(|r| r.motion.is_some())
        .filter_map(|r| {
            let found = found_pose(world, r)?;
            let supart: BodyId = world.supart(r.id)?;
            let under = world.world_pose(supart)?;
            Some(Place {
                body: r.id.get(),
                pose: under.inverse().compose(&found),
            })
        })
        .collect()
}
