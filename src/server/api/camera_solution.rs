//! Camera solution over HTTP: `POST /v1/camera-solution`, in two forms.
//!
//! **From correspondences.** A request gives 2D–3D correspondences, each a pixel and either a model vertex (by id:
//! its world locus is read from the model at the request's snapshot) or a world point,
//! and the camera's intrinsics (inline, or a stored camera's). The solve
//! ([`solve_pnp`]: LO-RANSAC around P3P, SQPnP on the consensus, robust
//! Levenberg–Marquardt) runs on a blocking thread, at most one per core at a time.
//!
//! Pixels are in the API's convention (the camera module's): `u` from the left edge, `v`
//! from the top, pixel `(i, j)` covering `[i, i+1) × [j, j+1)`, so a vertex seen by
//! [`Camera::project`] at `(u, v)` is given as `[u, v]`. OpenCV puts integer coordinates
//! at pixel centres; its `(u − ½, v − ½)` with its principal point `(cx − ½, cy − ½)`
//! (the `camera_matrix` answered) describe the same rays, so the answered `rvec`/`tvec`
//! are OpenCV's extrinsics as they are.
//!
//! With `solve_focal`, the focal length is solved too ([`solve_pnp_focal`]): the
//! intrinsics then give the image size, principal point and pixel aspect only, and a
//! view that cannot determine the focal length is refused.
//!
//! **From an image and a rough camera.** A request gives a picture (`image`, base64
//! PNG) and the camera it was taken with as far as it is known (`initial`: a stored
//! camera's name or one inline, as `PUT /v1/cameras/{name}` takes it); the model's visible
//! edges are aligned with the picture's edges ([`align_to_image`]) and the corrected
//! camera answered. The picture must have the initial camera's size (its PNG header is
//! compared with the camera before anything is decoded).
//!
//! The answer is the camera (pose and intrinsics, as `GET /v1/cameras/{name}` gives one),
//! OpenCV's `rvec`, `tvec` and camera matrix, the RMS reprojection error of the inliers
//! in pixels, the inlier indices (into `correspondences`), and iteration counts. With
//! `store_as`, the camera is also stored under that name, as `PUT /v1/cameras/{name}`
//! would (one write, a new revision). From an image, `edges` says how many points of the
//! model's visible edges were matched and what fraction lies on the picture's edges, and
//! `rms_px` is their distance to those edges.
//!
//! Solving needs the `read` role; `store_as` needs `write`.
//!
//! Errors (`application/problem+json`), none of which changes the world:
//! * 400: malformed JSON, unknown fields, a correspondence with neither or both of
//!   `vertex` and `point`, a `store_as` that is no valid camera name;
//! * 403: `store_as` with a token that may only read;
//! * 404: `intrinsics` names no stored camera;
//! * 422 `unknown-vertex`: a `vertex` is not a live vertex of the model (every such id is
//!   named);
//! * 422 `too-few-correspondences`, `too-many-correspondences`;
//! * 422 `invalid-intrinsics`, `invalid-parameter`, `invalid-correspondences` (numbers
//!   out of range or not finite);
//! * 422 `degenerate-correspondences`: the points cannot fix a camera (all on one line,
//!   coincident);
//! * 422 `no-consensus`: no camera agrees with enough correspondences;
//! * 422 `did-not-converge`, `no-pose-in-front`: the solve found no camera it can vouch
//!   for; no camera is ever answered that the solver does not stand behind;
//! * from an image: 400 `invalid-image` (not base64, not a PNG, broken), 413 for an
//!   image beyond the decoder's limits, 422 `invalid-image` (not the camera's size),
//!   `invalid-camera`, `no-image-edges` (a blank picture), `model-not-in-view` (too
//!   little of the model's edges visible from the initial camera), `image-does-not-match`
//!   (after alignment too little of the model lies on the picture's edges: the picture
//!   does not show the model from near the initial camera).

use std::sync::Arc;
use std::time::Instant;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as BASE64;
use tokio::sync::OwnedSemaphorePermit;

use axum::Json;
use axum::extract::{Extension, State};
use axum::http::StatusCode;
use axum::http::header::ETAG;
use axum::response::IntoResponse;
use glam::{DMat3, DVec2, DVec3};
use serde::{Deserialize, Serialize};

use super::appearance::CameraRef;
use super::extract::ApiJson;
use super::precondition::etag;
use super::{Answer, AppState, snapshot};
use crate::edit::Edit;
use crate::edit::command::CameraSpec;
use crate::model::camera::{Camera, Intrinsics};
use crate::model::{Serial, World};
use crate::server::actor::Applied;
use crate::server::auth::Role;
use crate::server::limits::{
    ImageError, ImageLimits, Measure, PNG_HEADER_BYTES, decode_png, png_size,
};
use crate::server::problem::Problem;
use crate::server::request::{IntrinsicsDto, PoseDto};
use crate::vision::image::Luma;
use crate::vision::solve::align::{AlignOptions, align_to_image};
use crate::vision::solve::{
    PixelIntrinsics, PnpOptions, PnpSolution, SolveError, rotation_vector, solve_pnp,
    solve_pnp_focal,
};

/// The most correspondences one request may give.
pub const MAX_CORRESPONDENCES: usize = 20_000;

/// The most RANSAC iterations a request may ask for.
pub const MAX_RANSAC_ITERATIONS: usize = 1_000_000;

/// Unknown vertex ids named in one problem answer at most.
const MAX_NAMED_IDS: usize = 20;

/// `POST /v1/camera-solution`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolveReq {
    /// From correspondences: the camera's intrinsics, or the name of a stored camera
    /// whose intrinsics to use.
    #[serde(default)]
    pub intrinsics: Option<IntrinsicsRef>,
    /// From correspondences: pixels and the world points seen there.
    #[serde(default)]
    pub correspondences: Option<Vec<CorrespondenceDto>>,
    /// From an image: the picture, a base64 PNG.
    #[serde(default)]
    pub image: Option<String>,
    /// From an image: the camera as far as it is known.
    #[serde(default)]
    pub initial: Option<CameraRef>,
    /// Store the solved camera under this name.
    #[serde(default)]
    pub store_as: Option<String>,
    /// Reprojection error in pixels up to which a correspondence counts as an inlier
    /// (default 8).
    #[serde(default)]
    pub threshold_px: Option<f64>,
    /// RANSAC's confidence that it has drawn an all-inlier sample when it stops
    /// (default 0.999).
    #[serde(default)]
    pub confidence: Option<f64>,
    /// The most RANSAC iterations (default 10,000).
    #[serde(default)]
    pub max_iterations: Option<usize>,
    /// The fewest inliers the camera may rest on (default 6, at least 4).
    #[serde(default)]
    pub min_inliers: Option<usize>,
    /// RANSAC's seed: the same request gives the same camera (default 0).
    #[serde(default)]
    pub seed: Option<u64>,
    /// Solve the focal length too: the intrinsics' principal point and pixel aspect
    /// (`fy/fx`) are kept, their focal lengths are not used.
    #[serde(default)]
    pub solve_focal: bool,
}

/// Intrinsics given inline, or taken from a stored camera.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum IntrinsicsRef {
    /// A stored camera's name.
    Named(String),
    /// Intrinsics in pixels.
    Inline(IntrinsicsDto),
}

/// One correspondence: a pixel and exactly one of a vertex id and a world point.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CorrespondenceDto {
    /// Where the point is seen, `[u, v]` pixels.
    pub pixel: [f64; 2],
    /// A vertex of the model: its world locus is the point.
    #[serde(default)]
    pub vertex: Option<u64>,
    /// The point, `[x, y, z]` meters in the world.
    #[serde(default)]
    pub point: Option<[f64; 3]>,
}

/// A solved camera as answered.
#[derive(Debug, Serialize)]
struct SolvedCamera {
    /// Pose in the world (the camera looks along its −k axis).
    pose: PoseDto,
    /// Intrinsics.
    intrinsics: IntrinsicsDto,
    /// The direction it looks along.
    view_direction: [f64; 3],
}

/// The extrinsics and camera matrix in OpenCV's convention.
#[derive(Debug, Serialize)]
struct OpenCv {
    /// Rotation vector (axis × angle, radians), world to camera.
    rvec: [f64; 3],
    /// Translation, world to camera.
    tvec: [f64; 3],
    /// The 3×3 camera matrix K, by rows (principal point in OpenCV's pixel-centre
    /// convention).
    camera_matrix: [[f64; 3]; 3],
}

/// A solved focal length.
#[derive(Debug, Serialize)]
struct Focal {
    /// Horizontal focal length, pixels.
    fx: f64,
    /// Vertical focal length, pixels.
    fy: f64,
    /// The estimated standard deviation of `fx`, pixels.
    fx_std: f64,
}

/// Iteration counts.
#[derive(Debug, Serialize)]
struct Iterations {
    /// RANSAC samples drawn (from correspondences).
    #[serde(skip_serializing_if = "Option::is_none")]
    ransac: Option<usize>,
    /// Levenberg–Marquardt iterations.
    refine: usize,
}

/// How well the model's edges lie on the picture's (from an image).
#[derive(Debug, Serialize)]
struct EdgeFit {
    /// Points sampled on the model's visible edges at the answered camera.
    samples: usize,
    /// The fraction of them within 2 pixels of a picture edge of their direction.
    inlier_fraction: f64,
}

/// The answer of `POST /v1/camera-solution`.
#[derive(Debug, Serialize)]
struct Solved {
    camera: SolvedCamera,
    opencv: OpenCv,
    /// RMS reprojection error over the inliers, pixels.
    rms_px: f64,
    /// Indices of the inlier correspondences, ascending.
    #[serde(skip_serializing_if = "Option::is_none")]
    inliers: Option<Vec<usize>>,
    /// Number of correspondences given.
    #[serde(skip_serializing_if = "Option::is_none")]
    correspondences: Option<usize>,
    iterations: Iterations,
    /// Whether RANSAC stopped at its confidence rather than its iteration limit.
    #[serde(skip_serializing_if = "Option::is_none")]
    confident: Option<bool>,
    /// From an image: how the model's edges lie on the picture's.
    #[serde(skip_serializing_if = "Option::is_none")]
    edges: Option<EdgeFit>,
    /// The focal length, when it was solved.
    #[serde(skip_serializing_if = "Option::is_none")]
    focal: Option<Focal>,
    /// The name the camera was stored under.
    #[serde(skip_serializing_if = "Option::is_none")]
    stored_as: Option<String>,
    /// The world's revision: the one the vertices were read at, or the one the store
    /// made.
    revision: u64,
}

fn unprocessable(kind: &'static str, title: &'static str, detail: impl Into<String>) -> Problem {
    Problem::new(StatusCode::UNPROCESSABLE_ENTITY, kind, title, detail)
}

/// The problem answer of a solve that failed.
pub(super) fn solve_problem(e: SolveError) -> Problem {
    let detail = e.to_string();
    match e {
        SolveError::TooFewPoints { .. } => {
            unprocessable("too-few-correspondences", "Too few correspondences", detail)
        }
        SolveError::Degenerate(_) => unprocessable(
            "degenerate-correspondences",
            "The correspondences cannot fix a camera",
            detail,
        ),
        SolveError::NonFinite { .. } | SolveError::LengthMismatch { .. } => {
            unprocessable("invalid-correspondences", "Invalid correspondences", detail)
        }
        SolveError::BadParameter { .. } | SolveError::NotARotation { .. } => {
            unprocessable("invalid-parameter", "Invalid parameter", detail)
        }
        SolveError::NoConsensus { .. } => unprocessable(
            "no-consensus",
            "No camera agrees with enough correspondences",
            detail,
        ),
        SolveError::NoPoseInFront => unprocessable(
            "no-pose-in-front",
            "No camera sees the points in front of it",
            detail,
        ),
        SolveError::DidNotConverge { .. } => {
            unprocessable("did-not-converge", "The solve did not converge", detail)
        }
        SolveError::ImageChannels { .. }
        | SolveError::ImageSamples { .. }
        | SolveError::ImageSizeMismatch { .. } => {
            unprocessable("invalid-image", "Invalid image", detail)
        }
        SolveError::BadCamera(_) => unprocessable("invalid-camera", "Invalid camera", detail),
        SolveError::NoImageEdges => {
            unprocessable("no-image-edges", "The image shows no edges", detail)
        }
        SolveError::NoEdgesVisible { .. } => unprocessable(
            "model-not-in-view",
            "Too little of the model is in view",
            detail,
        ),
        SolveError::TooFewInliers { .. } => unprocessable(
            "image-does-not-match",
            "The image does not show the model from near the camera",
            detail,
        ),
    }
}

impl SolveReq {
    /// The solver's options, checked.
    fn options(&self) -> Result<PnpOptions, Problem> {
        let mut o = PnpOptions::default();
        let bad = |what: &str, why: &str| {
            Err(unprocessable(
                "invalid-parameter",
                "Invalid parameter",
                format!("{what} {why}"),
            ))
        };
        if let Some(t) = self.threshold_px {
            if !(t.is_finite() && t > 0.0) {
                return bad("threshold_px", "must be a positive number of pixels");
            }
            o.threshold_px = t;
        }
        if let Some(c) = self.confidence {
            if !(c > 0.0 && c < 1.0) {
                return bad("confidence", "must lie strictly between 0 and 1");
            }
            o.confidence = c;
        }
        if let Some(n) = self.max_iterations {
            if n == 0 || n > MAX_RANSAC_ITERATIONS {
                return bad(
                    "max_iterations",
                    &format!("must lie between 1 and {MAX_RANSAC_ITERATIONS}"),
                );
            }
            o.max_iterations = n;
        }
        if let Some(n) = self.min_inliers {
            if n < crate::vision::solve::MIN_CONSENSUS {
                return bad(
                    "min_inliers",
                    &format!("must be at least {}", crate::vision::solve::MIN_CONSENSUS),
                );
            }
            o.min_inliers = n;
        }
        if let Some(s) = self.seed {
            o.seed = s;
        }
        Ok(o)
    }

    /// The intrinsics, from the request or the world's camera.
    fn intrinsics(given: &IntrinsicsRef, world: &World) -> Result<Intrinsics, Problem> {
        match given {
            IntrinsicsRef::Named(name) => world
                .camera(name)
                .map(|c| c.intrinsics)
                .ok_or_else(|| Problem::not_found(format!("no camera is named {name:?}"))),
            IntrinsicsRef::Inline(i) => Intrinsics::new(i.width, i.height, i.fx, i.fy, i.cx, i.cy)
                .map_err(|e| {
                    unprocessable("invalid-intrinsics", "Invalid intrinsics", e.to_string())
                }),
        }
    }

    /// The world points and pixels, vertices read from `world`. Refused when a
    /// correspondence has neither or both of `vertex` and `point` (400), or names a vertex
    /// the model does not have (422, every such id named).
    fn pairs(
        correspondences: &[CorrespondenceDto],
        world: &World,
    ) -> Result<(Vec<DVec3>, Vec<DVec2>), Problem> {
        let n = correspondences.len();
        if n > MAX_CORRESPONDENCES {
            return Err(unprocessable(
                "too-many-correspondences",
                "Too many correspondences",
                format!("{n} correspondences; at most {MAX_CORRESPONDENCES} are taken"),
            ));
        }
        let mut ids = Vec::new();
        for (i, c) in correspondences.iter().enumerate() {
            match (c.vertex, c.point) {
                (Some(v), None) => ids.push(Serial(v)),
                (None, Some(_)) => {}
                _ => {
                    return Err(Problem::bad_request(format!(
                        "correspondences[{i}]: give exactly one of \"vertex\" and \"point\""
                    )));
                }
            }
        }
        let found = world.find_vertices(&ids);
        let missing: Vec<u64> = ids
            .iter()
            .zip(&found)
            .filter(|(_, f)| f.is_none())
            .map(|(s, _)| s.get())
            .collect();
        if !missing.is_empty() {
            let shown: Vec<String> = missing
                .iter()
                .take(MAX_NAMED_IDS)
                .map(u64::to_string)
                .collect();
            let more = if missing.len() > MAX_NAMED_IDS {
                format!(" and {} more", missing.len() - MAX_NAMED_IDS)
            } else {
                String::new()
            };
            return Err(unprocessable(
                "unknown-vertex",
                "Unknown vertex",
                format!("no live vertex has the id {}{more}", shown.join(", ")),
            ));
        }
        let mut loci = found.into_iter().flatten().map(|(_, _, p)| p);
        let mut points = Vec::with_capacity(n);
        let mut pixels = Vec::with_capacity(n);
        for c in correspondences {
            let p = match c.point {
                Some(p) => DVec3::from_array(p),
                None => loci.next().ok_or_else(|| {
                    Problem::internal("a vertex was found but its locus went missing")
                })?,
            };
            points.push(p);
            pixels.push(DVec2::from_array(c.pixel));
        }
        Ok((points, pixels))
    }
}

/// OpenCV's camera matrix of `k`, by rows.
fn camera_matrix(k: &Intrinsics) -> [[f64; 3]; 3] {
    let m: DMat3 = k.opencv_matrix();
    let r = m.transpose();
    [
        r.x_axis.to_array(),
        r.y_axis.to_array(),
        r.z_axis.to_array(),
    ]
}

/// What a request asks for, checked for exactly one of the two forms.
enum Form<'a> {
    /// Correspondences with intrinsics.
    Correspondences(&'a IntrinsicsRef, &'a [CorrespondenceDto]),
    /// A picture and the rough camera that took it.
    Image(&'a str, &'a CameraRef),
}

impl SolveReq {
    /// The form asked for: 400 unless the request holds exactly one form whole, and only
    /// the options that form takes.
    fn form(&self) -> Result<Form<'_>, Problem> {
        match (
            &self.intrinsics,
            &self.correspondences,
            &self.image,
            &self.initial,
        ) {
            (Some(k), Some(c), None, None) => Ok(Form::Correspondences(k, c)),
            (None, None, Some(image), Some(initial)) => {
                let ransac = [
                    ("threshold_px", self.threshold_px.is_some()),
                    ("confidence", self.confidence.is_some()),
                    ("max_iterations", self.max_iterations.is_some()),
                    ("min_inliers", self.min_inliers.is_some()),
                    ("seed", self.seed.is_some()),
                    ("solve_focal", self.solve_focal),
                ];
                match ransac.iter().find(|(_, given)| *given) {
                    Some((name, _)) => Err(Problem::bad_request(format!(
                        "{name} is an option of solving from correspondences, not from an image"
                    ))),
                    None => Ok(Form::Image(image, initial)),
                }
            }
            _ => Err(Problem::bad_request(
                "give either \"intrinsics\" and \"correspondences\", or \"image\" and \"initial\"",
            )),
        }
    }
}

/// A solved camera and how it was found, before it is answered.
struct Outcome {
    camera: Camera,
    rms_px: f64,
    inliers: Option<Vec<usize>>,
    correspondences: Option<usize>,
    iterations: Iterations,
    confident: Option<bool>,
    focal: Option<Focal>,
    edges: Option<EdgeFit>,
}

/// `POST /v1/camera-solution`.
pub(super) async fn camera_solution(
    State(state): State<AppState>,
    role: Option<Extension<Role>>,
    ApiJson(req): ApiJson<SolveReq>,
) -> Answer {
    let form = req.form()?;
    if let Some(name) = &req.store_as {
        // Solving only reads the world; storing the camera writes it.
        let role = role.map_or(Role::Admin, |Extension(r)| r);
        if role < Role::Write {
            return Err(Problem::new(
                StatusCode::FORBIDDEN,
                "forbidden",
                "Forbidden",
                format!(
                    "store_as needs the {} role; the token holds {role}",
                    Role::Write
                ),
            ));
        }
        crate::model::parts::validate_name(name).map_err(|reason| {
            crate::server::problem::invalid_name(format!("store_as {name:?}: {reason}"))
        })?;
    }
    let world = snapshot(&state.handle).await?;
    let outcome = match form {
        Form::Correspondences(k, list) => {
            from_correspondences(&state, &req, &world, k, list).await?
        }
        Form::Image(image, initial) => from_image(&state, world.clone(), image, initial).await?,
    };
    let camera = outcome.camera;
    let intrinsics = camera.intrinsics;
    let dto = IntrinsicsDto {
        width: intrinsics.width,
        height: intrinsics.height,
        fx: intrinsics.fx,
        fy: intrinsics.fy,
        cx: intrinsics.cx,
        cy: intrinsics.cy,
    };
    let mut revision = world.revision();
    if let Some(name) = &req.store_as {
        let put = Edit::PutCamera {
            name: name.clone(),
            camera: CameraSpec {
                pose: Some(camera.pose),
                look_at: None,
                intrinsics: Some(camera.intrinsics),
                baumgart: None,
            },
        };
        let Applied { revision: r, .. } = state.handle.apply_if(put, None).await?;
        revision = r;
    }
    let (r, t) = camera.to_opencv();
    let answer = Solved {
        camera: SolvedCamera {
            pose: camera.pose.into(),
            intrinsics: dto,
            view_direction: camera.view_direction().to_array(),
        },
        opencv: OpenCv {
            rvec: rotation_vector(&r).to_array(),
            tvec: t.to_array(),
            camera_matrix: camera_matrix(&intrinsics),
        },
        rms_px: outcome.rms_px,
        inliers: outcome.inliers,
        correspondences: outcome.correspondences,
        iterations: outcome.iterations,
        confident: outcome.confident,
        edges: outcome.edges,
        focal: outcome.focal,
        stored_as: req.store_as,
        revision,
    };
    Ok(([(ETAG, etag(revision))], Json(answer)).into_response())
}

/// Waits for a turn to solve: at most one solve per core at a time.
async fn turn(state: &AppState) -> Result<OwnedSemaphorePermit, Problem> {
    state
        .solves
        .clone()
        .acquire_owned()
        .await
        .map_err(|_| Problem::unavailable())
}

/// The camera from correspondences ([`solve_pnp`] or [`solve_pnp_focal`]).
async fn from_correspondences(
    state: &AppState,
    req: &SolveReq,
    world: &World,
    given: &IntrinsicsRef,
    list: &[CorrespondenceDto],
) -> Result<Outcome, Problem> {
    let options = req.options()?;
    let intrinsics = SolveReq::intrinsics(given, world)?;
    let (points, pixels) = SolveReq::pairs(list, world)?;
    let _turn = turn(state).await?;
    let started = Instant::now();
    let k = PixelIntrinsics {
        fx: intrinsics.fx,
        fy: intrinsics.fy,
        cx: intrinsics.cx,
        cy: intrinsics.cy,
    };
    let solve_focal = req.solve_focal;
    let solved: Result<(PnpSolution, Option<Focal>), SolveError> =
        tokio::task::spawn_blocking(move || {
            if solve_focal {
                let principal = DVec2::new(k.cx, k.cy);
                solve_pnp_focal(&points, &pixels, principal, k.fy / k.fx, &options).map(|s| {
                    let focal = Focal {
                        fx: s.fx,
                        fy: s.fy,
                        fx_std: s.fx_std,
                    };
                    (s.solution, Some(focal))
                })
            } else {
                solve_pnp(&points, &pixels, &k, &options).map(|s| (s, None))
            }
        })
        .await
        .map_err(Problem::internal)?;
    let n = list.len();
    let elapsed_ms = started.elapsed().as_secs_f64() * 1e3;
    let (solution, focal) = solved.map_err(|e| {
        tracing::info!(correspondences = n, elapsed_ms, error = %e, "camera solution refused");
        solve_problem(e)
    })?;
    tracing::info!(
        correspondences = n,
        inliers = solution.inliers.len(),
        rms_px = solution.rms_px,
        ransac_iterations = solution.ransac_iterations,
        elapsed_ms,
        "camera solved"
    );
    let intrinsics = match &focal {
        Some(f) => Intrinsics {
            fx: f.fx,
            fy: f.fy,
            ..intrinsics
        },
        None => intrinsics,
    };
    let camera = Camera::from_opencv(
        solution.pose.rotation,
        solution.pose.translation,
        intrinsics,
    )
    .map_err(Problem::internal)?;
    Ok(Outcome {
        camera,
        rms_px: solution.rms_px,
        inliers: Some(solution.inliers),
        correspondences: Some(n),
        iterations: Iterations {
            ransac: Some(solution.ransac_iterations),
            refine: solution.refine_iterations,
        },
        confident: Some(solution.confident),
        focal,
        edges: None,
    })
}

/// The camera from a picture and a rough camera ([`align_to_image`]).
async fn from_image(
    state: &AppState,
    world: Arc<World>,
    image: &str,
    initial: &CameraRef,
) -> Result<Outcome, Problem> {
    let start = initial.resolve(&world)?;
    let limits = ImageLimits::default();
    let image = image.trim();
    refuse_before_decoding(image, &start, &limits)?;
    let png = BASE64.decode(image).map_err(|e| {
        Problem::new(
            StatusCode::BAD_REQUEST,
            "invalid-image",
            "Invalid image",
            format!("image: not base64 ({e})"),
        )
    })?;
    let _turn = turn(state).await?;
    let appearance = state.appearance.clone();
    let started = Instant::now();
    let aligned = tokio::task::spawn_blocking(move || {
        let decoded = decode_png(&png, &limits).map_err(Problem::from)?;
        let luma = Luma::from_samples(
            decoded.width,
            decoded.height,
            decoded.channels,
            &decoded.pixels,
        )
        .map_err(|e| solve_problem(e.into()))?;
        let scene = appearance.scene(&world);
        align_to_image(&scene, &start, &luma, &AlignOptions::default()).map_err(|e| {
            tracing::info!(error = %e, "camera alignment refused");
            solve_problem(e)
        })
    })
    .await
    .map_err(Problem::internal)??;
    tracing::info!(
        samples = aligned.samples,
        inlier_fraction = aligned.inlier_fraction,
        rms_px = aligned.rms_px,
        iterations = aligned.iterations,
        elapsed_ms = started.elapsed().as_secs_f64() * 1e3,
        "camera aligned to an image"
    );
    Ok(Outcome {
        camera: aligned.camera,
        rms_px: aligned.rms_px,
        inliers: None,
        correspondences: None,
        iterations: Iterations {
            ransac: None,
            refine: aligned.iterations,
        },
        confident: None,
        focal: None,
        edges: Some(EdgeFit {
            samples: aligned.samples,
            inlier_fraction: aligned.inlier_fraction,
        }),
    })
}

/// The base64 characters that hold a PNG's header ([`PNG_HEADER_BYTES`], rounded up to
/// whole groups of four characters).
const PNG_HEADER_BASE64: usize = PNG_HEADER_BYTES.div_ceil(3) * 4;

/// Refuses a picture, given as base64 text, that decoding would refuse for its size:
/// more bytes than `limits` accept (413), or a PNG header claiming another size than
/// `camera`'s (422 `invalid-image`, the answer alignment gives). Only the text's length
/// and its first [`PNG_HEADER_BASE64`] characters are read, so neither the base64 nor the
/// PNG is decoded for a picture refused here.
///
/// Text that is no valid base64, or no PNG, passes: the full decode refuses it and
/// says why.
pub(super) fn refuse_before_decoding(
    image: &str,
    camera: &Camera,
    limits: &ImageLimits,
) -> Result<(), Problem> {
    let text = image.as_bytes();
    if text.len().is_multiple_of(4) {
        // Valid base64 has three bytes per four characters, less its padding.
        let padding = text.iter().rev().take(2).filter(|&&c| c == b'=').count();
        let bytes = (text.len() / 4 * 3).saturating_sub(padding);
        if bytes > limits.max_encoded_bytes {
            return Err(ImageError::TooLarge {
                what: Measure::Encoded,
                bytes: bytes as u64,
                limit: limits.max_encoded_bytes as u64,
            }
            .into());
        }
    }
    let head = &text[..text.len().min(PNG_HEADER_BASE64)];
    let Some((width, height)) = BASE64.decode(head).ok().and_then(|h| png_size(&h).ok()) else {
        return Ok(());
    };
    let k = camera.intrinsics;
    if (width, height) != (k.width, k.height) {
        return Err(solve_problem(SolveError::ImageSizeMismatch {
            image_width: width,
            image_height: height,
            camera_width: k.width,
            camera_height: k.height,
        }));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(width: u32, height: u32) -> Camera {
        let k = Intrinsics::new(width, height, 100.0, 100.0, 4.0, 2.0).expect("intrinsics");
        Camera::look_at(DVec3::new(0.0, -5.0, 0.0), DVec3::ZERO, DVec3::Z, k).expect("a camera")
    }

    fn grey_png(width: u32, height: u32) -> String {
        let mut out = Vec::new();
        let mut encoder = png::Encoder::new(&mut out, width, height);
        encoder.set_color(png::ColorType::Grayscale);
        encoder
            .write_header()
            .expect("a header")
            .write_image_data(&vec![0; (width * height) as usize])
            .expect("pixels");
        BASE64.encode(out)
    }

    #[test]
    fn a_header_of_another_size_is_refused_and_one_of_the_same_passes() {
        let limits = ImageLimits::default();
        let p =
            refuse_before_decoding(&grey_png(16, 4), &camera(8, 4), &limits).expect_err("refused");
        assert_eq!(
            (p.status, p.kind),
            (StatusCode::UNPROCESSABLE_ENTITY, "invalid-image")
        );
        assert!(
            p.detail.contains("16×4") && p.detail.contains("8×4"),
            "{}",
            p.detail
        );
        assert!(refuse_before_decoding(&grey_png(8, 4), &camera(8, 4), &limits).is_ok());
        // Not base64, not a PNG, cut short: left to the decoder to name.
        for text in ["%%%", "R0lGODlh", &grey_png(16, 4)[..20]] {
            assert!(refuse_before_decoding(text, &camera(8, 4), &limits).is_ok());
        }
    }

    #[test]
    fn too_many_bytes_are_refused_from_the_text_length() {
        let limits = ImageLimits {
            max_encoded_bytes: 5,
            ..ImageLimits::default()
        };
        // Eight characters with one of padding: five bytes, then eight more: eleven.
        assert!(refuse_before_decoding("AAAAAAA=", &camera(8, 4), &limits).is_ok());
        let p = refuse_before_decoding("AAAAAAAAAAAAAAA=", &camera(8, 4), &limits)
            .expect_err("refused");
        assert_eq!(p.status, StatusCode::PAYLOAD_TOO_LARGE);
        assert!(p.detail.contains("11 bytes"), "{}", p.detail);
    }
}
