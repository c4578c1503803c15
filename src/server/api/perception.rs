//! Perception over HTTP: `POST /v1/perception`, views from solved cameras in; new
//! provisional bodies carved from their silhouettes, or a provisional body carved further,
//! out ([`crate::vision::perceive`]).
//!
//! ```json
//! {"views": [{"camera": "left", "mask": "<base64 PNG>"},
//!            {"camera": {...inline...}, "image": "<base64 PNG>", "depth": "<base64 PNG>"}],
//!  "name": "cup", "body": null, "near": 0.05, "far": 20, "tolerance_px": 1,
//!  "min_area_px": 16}
//! ```
//!
//! Each view gives a camera (a stored camera's name or one inline) and either a `mask`
//! (non-zero pixels are the new object) or an `image` (and optionally a `depth` picture
//! with `depth_scale`) whose unexplained regions, found by recognition, are the mask.
//! Pixels a modeled body covers next to the silhouette join it, so that a view does not
//! carve away what a known body hides. Without `body`, the views' visual hull becomes
//! new provisional bodies, one per connected piece, named `name`, `name-2`, ...; with
//! `body`, that provisional body is carved further (a piece carved off becomes a body of
//! its own; a body carved to nothing is removed). One write, journaled as the geometry
//! made. Carving runs beside the world's owner, on a snapshot, at most one per core.
//!
//! Errors (`application/problem+json`; the world is unchanged): 400 for JSON that does
//! not parse, a PNG or base64 that is broken, a view with neither or both of `mask`
//! and `image`; 404 for an unknown camera name or `body`; 413 for pictures beyond the
//! decoder's limits; 422 `invalid-camera`, `invalid-mask` (not the camera's size),
//! `empty-mask` (no region of `min_area_px`), `invalid-parameter` (`near` ≥ `far`, a
//! tolerance or area out of range, no views), `not-provisional` (a `body` perception did
//! not make), `cones-apart` (views whose cones do not meet, named in the detail and in
//! `views`).

use std::time::Instant;

use axum::Json;
use axum::extract::{Request, State};
use axum::http::StatusCode;
use axum::http::header::ETAG;
use axum::response::IntoResponse;
use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as BASE64;
use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::appearance::CameraRef;
use super::body::Bodies;
use super::camera_solution::solve_problem;
use super::precondition::{FIELD, IfMatch, etag, read_write};
use super::{Answer, AppState, snapshot};
use crate::edit::command::{FaceList, PerceivedPiece};
use crate::edit::{Edit, Outcome};
use crate::model::camera::Camera;
use crate::model::perceived::Maker;
use crate::model::{BodyId, Serial, World};
use crate::server::actor::{Applied, WriteError};
use crate::server::limits::{ImageLimits, decode_depth_png, decode_png};
use crate::server::problem::Problem;
use crate::vision::image::{Luma, Mask};
use crate::vision::perceive::silhouette::SIMPLIFY_PX;
use crate::vision::perceive::{
    Depths, MaskView, Mesh, PerceiveOptions, Tally, ViewsError, carve_body, new_bodies, sights,
};
use crate::vision::recognize::{DepthImage, RecognizeOptions, recognize};
use crate::vision::solve::align::EdgePyramid;

/// The most views one request may give.
pub const MAX_VIEWS: usize = 256;

/// `POST /v1/perception`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PerceptionReq {
    /// The views.
    pub views: Vec<ViewReq>,
    /// The new bodies' name (several pieces: `name`, `name-2`, ...).
    #[serde(default)]
    pub name: Option<String>,
    /// A provisional body to carve further.
    #[serde(default)]
    pub body: Option<u64>,
    /// Nearest depth of the cones, meters (default 0.05).
    #[serde(default)]
    pub near: Option<f64>,
    /// Farthest depth of the cones, meters (default 20).
    #[serde(default)]
    pub far: Option<f64>,
    /// Pixels by which silhouettes are widened (default 1).
    #[serde(default)]
    pub tolerance_px: Option<f64>,
    /// Regions of fewer pixels are left out (default 16).
    #[serde(default)]
    pub min_area_px: Option<f64>,
}

/// One view as given.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewReq {
    /// The solved camera: a stored camera's name or one inline.
    pub camera: CameraRef,
    /// The new object's mask, a base64 PNG of the camera's size (non-zero inside).
    #[serde(default)]
    pub mask: Option<String>,
    /// A picture whose unexplained regions are the mask, a base64 PNG.
    #[serde(default)]
    pub image: Option<String>,
    /// With `image`: a depth picture, a base64 16-bit grey PNG.
    #[serde(default)]
    pub depth: Option<String>,
    /// Meters per unit of `depth` (default 0.001).
    #[serde(default)]
    pub depth_scale: Option<f64>,
}

/// One body in the answer.
#[derive(Debug, Serialize)]
struct BodyDto {
    id: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    volume: f64,
    faces: usize,
    /// Views that carved it, over every request.
    views: u32,
}

/// The answer.
#[derive(Debug, Serialize)]
struct PerceptionAnswer {
    inserted: Vec<BodyDto>,
    carved: Vec<BodyDto>,
    removed: Vec<u64>,
    revision: u64,
    /// Carvings made in the image, by the general boolean where that was unsure, and
    /// pieces a view could not carve (kept whole).
    carvings: CarvingsDto,
    elapsed_ms: f64,
}

#[derive(Debug, Serialize)]
struct CarvingsDto {
    image: usize,
    boolean: usize,
    uncarved: usize,
}

fn unprocessable(kind: &'static str, title: &'static str, detail: impl Into<String>) -> Problem {
    Problem::new(StatusCode::UNPROCESSABLE_ENTITY, kind, title, detail)
}

fn invalid_parameter(detail: impl Into<String>) -> Problem {
    unprocessable("invalid-parameter", "Invalid parameter", detail)
}

fn bad_png(what: &str, view: usize, e: impl std::fmt::Display) -> Problem {
    Problem::bad_request(format!("view {view}: {what}: {e}"))
}

impl PerceptionReq {
    /// The options, checked.
    fn options(&self) -> Result<PerceiveOptions, Problem> {
        let d = PerceiveOptions::default();
        let near = self.near.unwrap_or(d.depths.near);
        let far = self.far.unwrap_or(d.depths.far);
        if !(near.is_finite() && far.is_finite() && near > 0.0 && near < far && far <= 1e6) {
            return Err(invalid_parameter(format!(
                "near and far must be finite with 0 < near < far ≤ 1e6 meters, not {near} and {far}"
            )));
        }
        let tolerance_px = self.tolerance_px.unwrap_or(d.tolerance_px);
        if !(0.0..=16.0).contains(&tolerance_px) {
            return Err(invalid_parameter(format!(
                "tolerance_px must lie in [0, 16] pixels, not {tolerance_px}"
            )));
        }
        let min_area_px = self.min_area_px.unwrap_or(d.min_area_px);
        if !(min_area_px.is_finite() && min_area_px >= 0.0) {
            return Err(invalid_parameter(format!(
                "min_area_px must be a number of pixels ≥ 0, not {min_area_px}"
            )));
        }
        if self.views.is_empty() || self.views.len() > MAX_VIEWS {
            return Err(invalid_parameter(format!(
                "give between 1 and {MAX_VIEWS} views, not {}",
                self.views.len()
            )));
        }
        Ok(PerceiveOptions {
            depths: Depths { near, far },
            tolerance_px,
            min_area_px,
        })
    }
}

/// A view's silhouette source, decoded.
enum Source {
    Mask(Mask),
    Image {
        luma: Luma,
        depth: Option<DepthImage>,
    },
}

/// Decodes view `i`'s mask or picture (on a blocking thread), checked against its camera.
fn decode_view(i: usize, v: &ViewReq, camera: &Camera) -> Result<Source, Problem> {
    let limits = ImageLimits::default();
    let k = camera.intrinsics;
    let size_problem = |w: u32, h: u32, what: &str| {
        unprocessable(
            "invalid-mask",
            "Invalid mask",
            format!(
                "view {i}: the {what} is {w} × {h} pixels but the camera's picture is {} × {}",
                k.width, k.height
            ),
        )
    };
    let b64 = |text: &str, what: &str| {
        BASE64
            .decode(text.trim())
            .map_err(|e| bad_png(what, i, format!("not base64 ({e})")))
    };
    match (&v.mask, &v.image) {
        (Some(mask), None) => {
            let d = decode_png(&b64(mask, "mask")?, &limits).map_err(Problem::from)?;
            if (d.width, d.height) != (k.width, k.height) {
                return Err(size_problem(d.width, d.height, "mask"));
            }
            // Colour channels decide; an alpha channel does not.
            let colour = match d.channels {
                2 => 1,
                4 => 3,
                c => c,
            } as usize;
            let bits = d
                .pixels
                .chunks_exact(d.channels as usize)
                .map(|p| p[..colour].iter().any(|&c| c != 0))
                .collect();
            let mask =
                Mask::from_bits(d.width, d.height, bits).map_err(|e| bad_png("mask", i, e))?;
            Ok(Source::Mask(mask))
        }
        (None, Some(image)) => {
            let d = decode_png(&b64(image, "image")?, &limits).map_err(Problem::from)?;
            if (d.width, d.height) != (k.width, k.height) {
                return Err(size_problem(d.width, d.height, "image"));
            }
            let luma = Luma::from_samples(d.width, d.height, d.channels, &d.pixels)
                .map_err(|e| solve_problem(e.into()))?;
            let depth = match &v.depth {
                Some(text) => {
                    let d =
                        decode_depth_png(&b64(text, "depth")?, &limits).map_err(Problem::from)?;
                    let scale = v.depth_scale.unwrap_or(0.001);
                    Some(
                        DepthImage::from_units(d.width, d.height, &d.units, scale).map_err(
                            |e| {
                                unprocessable(
                                    "invalid-depth",
                                    "Invalid depth picture",
                                    e.to_string(),
                                )
                            },
                        )?,
                    )
                }
                None => None,
            };
            Ok(Source::Image { luma, depth })
        }
        _ => Err(Problem::bad_request(format!(
            "view {i}: give either a mask or an image, not {}",
            if v.mask.is_some() { "both" } else { "neither" }
        ))),
    }
}

/// The problem answer of views that could not be carved.
fn views_problem(e: ViewsError) -> Problem {
    let detail = e.to_string();
    match e {
        ViewsError::MaskSize { .. } => unprocessable("invalid-mask", "Invalid mask", detail),
        ViewsError::EmptyMask { .. } => unprocessable("empty-mask", "Empty mask", detail),
        ViewsError::ConesApart { .. } => {
            unprocessable("cones-apart", "The views' cones do not meet", detail)
        }
        ViewsError::Perceive(_) => unprocessable("carving-failed", "Carving failed", detail),
    }
}

/// What the blocking work gives back.
struct Carved {
    /// Pieces in world coordinates; with `body`, the first replaces it.
    pieces: Vec<Mesh>,
    tally: Tally,
}

/// Decodes, finds silhouettes and carves, on the calling (blocking) thread.
fn run(
    world: &World,
    scene: &crate::render::Scene,
    req: &PerceptionReq,
    cameras: &[Camera],
    options: &PerceiveOptions,
    existing: Option<(BodyId, u32)>,
) -> Result<Carved, Problem> {
    let mut views = Vec::with_capacity(req.views.len());
    for (i, (v, camera)) in req.views.iter().zip(cameras).enumerate() {
        let mask = match decode_view(i, v, camera)? {
            Source::Mask(m) => m,
            Source::Image { luma, depth } => {
                let options = RecognizeOptions::default();
                let pyramid = EdgePyramid::of(&luma, &options.refine).map_err(solve_problem)?;
                let found = recognize(scene, camera, &luma, &pyramid, depth.as_ref(), &options)
                    .map_err(|e| unprocessable("invalid-image", "Invalid image", e.to_string()))?;
                found.unexplained_mask
            }
        };
        views.push(MaskView {
            camera: *camera,
            mask,
        });
    }
    let first = existing.map_or(0, |(_, views)| views);
    let start = match existing {
        None => None,
        Some((b, _)) => {
            let node = world
                .node(b)
                .ok_or_else(|| Problem::not_found(format!("body {b}")))?;
            let pose = world.world_pose(b).unwrap_or(node.pose);
            let record = node.perceived.clone().unwrap_or_default();
            Some(Mesh::of_body(
                &node.body,
                |p| pose.transform_point(p),
                |s| record.maker(s).unwrap_or(Maker::Unrecorded),
            ))
        }
    };
    let mut tally = Tally::default();
    let carve = |hull: Option<&[Mesh]>, tally: &mut Tally| -> Result<Vec<Mesh>, Problem> {
        let sights = sights(&views, Some(scene), hull, options, first).map_err(views_problem)?;
        match &start {
            None => new_bodies(&sights, options.depths, tally).map_err(views_problem),
            Some(mesh) => carve_body(mesh.clone(), &sights, options.depths, tally)
                .map_err(|e| views_problem(e.into())),
        }
    };
    // Every covering body next to a silhouette first; then only those in front of what
    // that carving left (see `vision::perceive::occlusion`).
    let first_pass = carve(None, &mut tally)?;
    let pieces = if first_pass.is_empty() {
        first_pass
    } else {
        carve(Some(&first_pass), &mut tally)?
    };
    Ok(Carved { pieces, tally })
}

/// `POST /v1/perception`.
pub(super) async fn perception(State(state): State<AppState>, req: Request) -> Answer {
    let started = Instant::now();
    // Refused before the body is read: the connection cannot be reused.
    let IfMatch(header) = IfMatch::from_headers(req.headers()).map_err(Problem::unread)?;
    let (req, field): (PerceptionReq, _) = Bodies::of(&req)?.parse(req, read_write).await?;
    let precondition = match (header, field) {
        (Some(h), Some(f)) if h != f => {
            return Err(Problem::bad_request(format!(
                "If-Match names revision {h} but {FIELD} is {f}"
            )));
        }
        (h, f) => h.or(f),
    };
    let options = req.options()?;
    let world = snapshot(&state.handle).await?;
    // The views are carved against this snapshot: a precondition names it or fails now.
    if let Some(expected) = precondition
        && expected != world.revision()
    {
        return Err(WriteError::Conflict {
            expected,
            actual: world.revision(),
        }
        .into());
    }
    let cameras = req
        .views
        .iter()
        .map(|v| v.camera.resolve(&world))
        .collect::<Result<Vec<_>, _>>()?;
    let existing = match req.body {
        Some(id) => {
            let b = BodyId(Serial(id));
            if world.node(b).is_none() || b == world.root() {
                return Err(Problem::not_found(format!("body {id} does not exist")));
            }
            let Some(record) = world.perceived(b) else {
                return Err(unprocessable(
                    "not-provisional",
                    "Body not provisional",
                    format!(
                        "body {id} is not provisional: only bodies perception made can be carved by views"
                    ),
                ));
            };
            Some((b, record.views))
        }
        None => None,
    };
    let _turn = state
        .solves
        .clone()
        .acquire_owned()
        .await
        .map_err(|_| Problem::unavailable())?;
    let appearance = state.appearance.clone();
    let snapshot_world = world.clone();
    let views_given = req.views.len() as u32;
    let name = req.name.clone();
    let carved = tokio::task::spawn_blocking(move || {
        let scene = appearance.scene(&snapshot_world);
        // The body being carved hides nothing from its own views.
        let scene = match existing {
            Some((b, _)) => scene.without_bodies(|i| scene.bodies[i].id == b),
            None => (*scene).clone(),
        };
        run(&snapshot_world, &scene, &req, &cameras, &options, existing)
    })
    .await
    .map_err(Problem::internal)??;
    drop(_turn);

    let views_after = existing.map_or(0, |(_, v)| v) + views_given;
    let earlier_outline = existing
        .and_then(|(b, _)| world.perceived(b))
        .map_or(0.0, |p| p.outline_px);
    let outline_px = (options.tolerance_px + SIMPLIFY_PX).max(earlier_outline);
    let (edit, carving) = edit_of(
        &world,
        &carved.pieces,
        existing,
        name.as_deref(),
        views_after,
        outline_px,
    )?;
    let Applied {
        revision, outcome, ..
    } = state
        .handle
        .apply_if(edit.clone(), precondition.or(carving))
        .await?;
    let carved_name = existing.and_then(|(b, _)| world.node(b).and_then(|n| n.name.clone()));
    let answer = answer_of(&edit, &outcome, revision, &carved, carved_name, started);
    tracing::info!(
        inserted = answer.inserted.len(),
        carved = answer.carved.len(),
        removed = answer.removed.len(),
        views = views_given,
        boolean = carved.tally.boolean,
        uncarved = carved.tally.uncarved,
        elapsed_ms = answer.elapsed_ms,
        "perceived"
    );
    let status = if answer.inserted.is_empty() {
        StatusCode::OK
    } else {
        StatusCode::CREATED
    };
    Ok((status, [(ETAG, etag(revision))], Json(answer)).into_response())
}

/// The write that places the pieces, and the revision it must apply to (carving a body
/// needs it unchanged since the snapshot).
fn edit_of(
    world: &World,
    pieces: &[Mesh],
    existing: Option<(BodyId, u32)>,
    name: Option<&str>,
    views: u32,
    outline_px: f64,
) -> Result<(Edit, Option<u64>), Problem> {
    let piece =
        |mesh: &Mesh, body: Option<u64>, name: Option<String>, place: &dyn Fn(DVec3) -> DVec3| {
            let mut faces = FaceList::new();
            for f in &mesh.faces {
                faces.push(f);
            }
            PerceivedPiece {
                body,
                name,
                views,
                outline_px,
                positions: mesh.positions.iter().map(|&p| place(p)).collect(),
                faces,
                makers: mesh.makers.clone(),
            }
        };
    let same = |p: DVec3| p;
    let mut out = Vec::with_capacity(pieces.len());
    let mut removed = Vec::new();
    let mut expected = None;
    let mut rest = pieces;
    let mut base = name.map(str::to_owned);
    if let Some((b, _)) = existing {
        expected = Some(world.revision());
        let pose = world
            .world_pose(b)
            .ok_or_else(|| Problem::not_found(format!("body {b} does not exist")))?;
        let to_body = |p: DVec3| pose.inverse().transform_point(p);
        match pieces.split_first() {
            Some((first, others)) => {
                out.push(piece(first, Some(b.get()), None, &to_body));
                rest = others;
            }
            None => removed.push(b.get()),
        }
        if base.is_none() {
            base = world.node(b).and_then(|n| n.name.clone());
        }
    }
    let numbered = !out.is_empty() || rest.len() > 1;
    for (i, mesh) in rest.iter().enumerate() {
        let n = i + 1 + usize::from(!out.is_empty());
        let name = base.as_ref().map(|b| {
            if numbered && n > 1 {
                format!("{b}-{n}")
            } else {
                b.clone()
            }
        });
        out.push(piece(mesh, None, name, &same));
    }
    Ok((
        Edit::Perception {
            pieces: out,
            removed,
        },
        expected,
    ))
}

fn answer_of(
    edit: &Edit,
    outcome: &Outcome,
    revision: u64,
    carved: &Carved,
    carved_name: Option<String>,
    started: Instant,
) -> PerceptionAnswer {
    let mut answer = PerceptionAnswer {
        inserted: Vec::new(),
        carved: Vec::new(),
        removed: outcome.killed.clone(),
        revision,
        carvings: CarvingsDto {
            image: carved.tally.exact_image,
            boolean: carved.tally.boolean,
            uncarved: carved.tally.uncarved,
        },
        elapsed_ms: 0.0,
    };
    if let (Edit::Perception { pieces, .. }, Some(placed)) = (edit, &outcome.pieces) {
        for (piece, p) in pieces.iter().zip(placed) {
            let dto = BodyDto {
                id: p.id,
                name: piece
                    .name
                    .clone()
                    .or_else(|| piece.body.is_some().then(|| carved_name.clone()).flatten()),
                volume: p.volume,
                faces: p.faces,
                views: piece.views,
            };
            if piece.body.is_some() {
                answer.carved.push(dto);
            } else {
                answer.inserted.push(dto);
            }
        }
    }
    answer.elapsed_ms = started.elapsed().as_secs_f64() * 1e3;
    answer
}
