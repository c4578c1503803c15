//! Recognition: which modeled bodies a picture shows, where they really are, and what in
//! it nothing modeled explains (Baumgart's second access mode).
//!
//! Baumgart compared two image models, the one predicted from the world model and the
//! one found in the camera's picture. Here the prediction is exact: the hidden-line
//! drawing gives each body's visible edge pieces, polygon clipping in the image plane
//! gives each body's visible and whole projected areas ([`visible`]), and the z-buffer
//! gives the depth the model predicts at every pixel. The picture's model is its edges
//! (sub-pixel positions and directions, with their distance transform), and its depth
//! when an RGB-D camera gave one.
//!
//! # Method
//!
//! 1. **Prediction.** From the camera, every body with a visible projected area is *in
//!    view*. Its visible edge pieces are sampled every
//!    [`Matching::spacing_px`](evidence::Matching) pixels, leaving out smooth edges
//!    (between two faces seen from in front and within [`RecognizeOptions::smooth_deg`]
//!    of each other, as the sides of a many-sided cylinder), which a picture shows
//!    faintly if at all.
//! 2. **Evidence where the model has it.** A sample is *supported* when an image edge
//!    lies within [`Matching::tolerance_px`](evidence::Matching) and runs within the
//!    largest angle of the predicted edge. The body's edge support is the fraction of its
//!    samples supported; with depth, its depth agreement is the fraction of its predicted
//!    visible pixels with a reading whose reading agrees with the prediction
//!    ([`DepthTolerance`]). Its evidence is the edge support, or with depth the mean of
//!    the two. A body whose evidence reaches [`RecognizeOptions::seen_evidence`] is
//!    `seen`.
//! 3. **Search.** A body that is not seen is looked for near where the model has it
//!    ([`search`]: an image-shift search, then its pose aligned with the picture's edges,
//!    the rest of the scene in place, within [`SearchBounds`]). If its evidence at the
//!    pose found reaches the threshold, it is `moved`, with that motion.
//! 4. **What the model explains.** The scene with the moved bodies moved and the bodies
//!    neither seen nor moved taken out is drawn again. Image edge pixels that one of its
//!    visible edges accounts for (within the tolerance, the same way) are explained.
//! 5. **Unexplained regions.** From the picture alone, two cues, joined:
//!    * *outlines*: the unexplained edge pixels are grown by
//!      [`RecognizeOptions::close_px`] (bridging small gaps in outlines), the holes they
//!      enclose filled and the result shrunk back: regions bounded by edges that nothing
//!      modeled has;
//!    * *surfaces*: the updated model, drawn from the camera, says which face each pixel
//!      shows and how it is lit (its own shading, shadows included); the pixels that show
//!      one face lit one way form a class. A planar face under distant light shows one
//!      grey level up to noise whatever drew it, so a pixel far from its class's median
//!      (beyond [`RecognizeOptions::deviation_spread`] robust deviations and
//!      [`RecognizeOptions::deviation_least`] grey levels) shows something else: those
//!      pixels, opened to drop the slivers along edges that blur and calibration leave.
//!
//!    Their union, holes filled, is unexplained. With depth, the pixels whose readings are
//!    nearer than the updated model predicts (or show a surface where it predicts none)
//!    are the regions instead: depth is direct evidence. Specks are removed by an
//!    opening, and regions smaller than [`RecognizeOptions::min_region_px`] dropped; the
//!    rest are traced into polygons.
//! 6. **Absent or occluded.** A body neither seen nor moved is `occluded` when most of
//!    what the model predicts of it is covered by something unmodeled (with depth: most
//!    of its predicted pixels with readings read nearer than predicted; without: most of
//!    its edge samples lie in unexplained regions), and `absent` otherwise.
//!
//! # Scores
//!
//! A body's score is a logistic function of its evidence, centred on the threshold:
//! `σ(SCORE_SLOPE·(e − seen_evidence))` for seen and moved bodies, `1 − σ(…)` for absent
//! ones, and `σ(SCORE_SLOPE·(o − ½))` of the covered fraction `o` for occluded ones; it
//! is shrunk toward ½ when the body shows fewer than [`RecognizeOptions::min_points`]
//! edge samples. The slope is a fixed constant, not yet fitted to measured outcomes.
//!
//! # Not done
//!
//! The shadows of modeled bodies are predicted with the world's own lights: a picture lit
//! otherwise shows shadows where the model has none, and their outlines are unexplained.

pub mod depth;
pub mod evidence;
pub mod search;
pub mod unexplained;
pub mod visible;

use std::collections::HashMap;

use crate::camera::{Camera, DEFAULT_NEAR, View};
use glam::DVec3;

use crate::model::BodyId;
use crate::render::hidden::{Segment, hidden_lines};
use crate::render::raster::{Frame, NO_FACE, Shading, rasterize, shaded};
use crate::render::{Scene, SceneBody};
use crate::vision::image::{ContourOptions, EdgeMap, Luma, Mask, Region, trace_regions};
use crate::vision::solve::align::{AlignOptions, EdgePyramid, Motion};

pub use depth::{DepthError, DepthImage, DepthTolerance, Reading};
pub use evidence::{EdgePoint, Matching, edge_points};
pub use search::{Moved, Search, SearchBounds};
use unexplained::{Flags, deviant, enclosed, opened};
pub use visible::{BodyArea, projected_areas};

/// The slope of the logistic that turns evidence into a score.
pub const SCORE_SLOPE: f64 = 12.0;

/// How [`recognize`] runs.
#[derive(Debug, Clone, PartialEq)]
pub struct RecognizeOptions {
    /// How predicted edges are matched with image edges.
    pub matching: Matching,
    /// The evidence (edge support, or its mean with depth agreement) from which a body is
    /// seen (or moved), in (0, 1].
    pub seen_evidence: f64,
    /// Edges between two faces seen from in front whose normals are within this many
    /// degrees are smooth: not expected to show, so not counted as evidence.
    pub smooth_deg: f64,
    /// Edge samples below which a body's score is shrunk toward ½.
    pub min_points: usize,
    /// Where to look for bodies that moved; `None` does not look.
    pub search: Option<SearchBounds>,
    /// How a body's pose is aligned once the search has found it.
    pub align: AlignOptions,
    /// How the camera is aligned with the picture when asked to be (before recognizing):
    /// the model may be partly wrong (bodies moved or gone), so fewer of its edges need
    /// to lie on the picture's than when the model is trusted.
    pub refine: AlignOptions,
    /// How near a depth reading must be to the prediction to agree.
    pub depth_tolerance: DepthTolerance,
    /// Gaps in outlines of unexplained edges up to about twice this are bridged, pixels.
    pub close_px: usize,
    /// A pixel departs from its class (the pixels the model predicts show one face lit
    /// one way) when its grey level is farther from the class's median than this many
    /// robust deviations...
    pub deviation_spread: f64,
    /// ...and than this many grey levels.
    pub deviation_least: f64,
    /// Unexplained regions smaller than this are dropped, pixels².
    pub min_region_px: f64,
    /// Region outlines are simplified within this, pixels.
    pub outline_tolerance_px: f64,
    /// The near plane of the drawing, meters.
    pub near: f64,
}

impl Default for RecognizeOptions {
    /// Matches within 2 pixels and 30°, samples every 2 pixels, seen from an evidence of
    /// ½, edges between faces within 20° smooth, bodies aligned on two levels from samples
    /// every pixel (steps down to 0.05 pixel, 40 iterations a level, the last pose taken
    /// if 30 % of its samples lie on edges: the evidence decides), smooth edges left out of
    /// every alignment, the camera aligned when 40 % of the model's edges lie on the picture's, scores shrunk below 12 samples, a search within 10 cm and 10°, depth within
    /// 1 cm + 1 %, gaps of about 6 pixels bridged, pixels departing from their class by
    /// 4 deviations and 16 grey levels, regions from 64 pixels², outlines
    /// within ¾ pixel, the renderer's near plane.
    fn default() -> Self {
        RecognizeOptions {
            matching: Matching {
                tolerance_px: 2.0,
                min_cos: 30f64.to_radians().cos(),
                spacing_px: 2.0,
            },
            seen_evidence: 0.5,
            smooth_deg: 20.0,
            min_points: 12,
            search: Some(SearchBounds::default()),
            align: AlignOptions {
                levels: 2,
                sample_spacing_px: 1.0,
                min_samples: 12,
                tolerance_px: 0.05,
                max_iterations: 40,
                min_inlier_fraction: 0.3,
                converged_only: false,
                smooth_deg: 20.0,
                ..AlignOptions::default()
            },
            refine: AlignOptions {
                min_inlier_fraction: 0.4,
                smooth_deg: 20.0,
                ..AlignOptions::default()
            },
            depth_tolerance: DepthTolerance {
                absolute_m: 0.01,
                relative: 0.01,
            },
            close_px: 3,
            deviation_spread: 4.0,
            deviation_least: 16.0,
            min_region_px: 64.0,
            outline_tolerance_px: 0.75,
            near: DEFAULT_NEAR,
        }
    }
}

/// What recognition says of one body.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// Where the model has it.
    Seen,
    /// Found near where the model has it; [`BodyReport::motion`] carries it there.
    Moved,
    /// The picture contradicts it: the model predicts it in view and it is not there.
    Absent,
    /// Something the model does not have hides it.
    Occluded,
}

impl Status {
    /// The name the API uses.
    pub fn name(self) -> &'static str {
        match self {
            Status::Seen => "seen",
            Status::Moved => "moved",
            Status::Absent => "absent",
            Status::Occluded => "occluded",
        }
    }
}

/// One body in view, as recognition found it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyReport {
    /// Index into the scene's bodies.
    pub body: usize,
    /// The body's id.
    pub id: BodyId,
    /// What recognition says of it.
    pub status: Status,
    /// The probability that the body is there as reported, in [0, 1] (see the module
    /// documentation).
    pub score: f64,
    /// Its visible projected area over its whole projected area, where the model (with
    /// moved bodies moved) has it.
    pub visible_fraction: f64,
    /// The box `[u0, v0, u1, v1]` of its visible part, pixels.
    pub bbox: Option<[f64; 4]>,
    /// The fraction of its visible edge samples that image edges support.
    pub edge_support: f64,
    /// How many visible edge samples it has.
    pub edge_points: usize,
    /// With depth: the fraction of its predicted visible pixels with readings whose
    /// reading agrees.
    pub depth_agreement: Option<f64>,
    /// For a moved body: the motion (world points `X ↦ motion·X`) from where the model has
    /// it to where it is.
    pub motion: Option<Motion>,
}

/// What [`recognize`] found.
#[derive(Debug, Clone)]
pub struct Recognition {
    /// Every body in view, in the scene's order.
    pub bodies: Vec<BodyReport>,
    /// The regions nothing modeled explains, largest first.
    pub unexplained: Vec<Region>,
    /// The same as a mask.
    pub unexplained_mask: Mask,
}

/// Why recognition was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RecognizeError {
    #[error(
        "the picture is {image_width}×{image_height} but the camera's image is {camera_width}×{camera_height}"
    )]
    ImageSize {
        image_width: u32,
        image_height: u32,
        camera_width: u32,
        camera_height: u32,
    },
    #[error(
        "the depth picture is {depth_width}×{depth_height} but the camera's image is {camera_width}×{camera_height}"
    )]
    DepthSize {
        depth_width: u32,
        depth_height: u32,
        camera_width: u32,
        camera_height: u32,
    },
    /// The camera is not valid.
    #[error("invalid camera: {0}")]
    Camera(String),
    /// An option is out of range.
    #[error("{what} is out of range: {value}")]
    Option { what: &'static str, value: f64 },
}

impl RecognizeOptions {
    fn validate(&self) -> Result<(), RecognizeError> {
        let bad = |what: &'static str, value: f64| Err(RecognizeError::Option { what, value });
        let m = &self.matching;
        if !(m.tolerance_px.is_finite() && m.tolerance_px > 0.0) {
            return bad("the edge tolerance", m.tolerance_px);
        }
        if !(m.min_cos > 0.0 && m.min_cos <= 1.0) {
            return bad("the cosine of the largest edge angle", m.min_cos);
        }
        if !(m.spacing_px.is_finite() && m.spacing_px >= 0.25) {
            return bad("the sample spacing", m.spacing_px);
        }
        if !(0.0..90.0).contains(&self.smooth_deg) {
            return bad("the angle of smooth edges", self.smooth_deg);
        }
        if !(self.seen_evidence > 0.0 && self.seen_evidence <= 1.0) {
            return bad("the evidence to be seen", self.seen_evidence);
        }
        if let Some(s) = &self.search {
            if !(s.translation_m.is_finite() && s.translation_m > 0.0) {
                return bad("search.translation_m", s.translation_m);
            }
            if !(s.rotation_deg > 0.0 && s.rotation_deg <= 180.0) {
                return bad("search.rotation_deg", s.rotation_deg);
            }
        }
        let t = &self.depth_tolerance;
        if !(t.absolute_m.is_finite()
            && t.absolute_m >= 0.0
            && t.relative.is_finite()
            && t.relative >= 0.0)
        {
            return bad("the depth tolerance", t.absolute_m);
        }
        if !(self.min_region_px.is_finite() && self.min_region_px >= 0.0) {
            return bad("min_region_px", self.min_region_px);
        }
        if !(self.outline_tolerance_px.is_finite() && self.outline_tolerance_px >= 0.0) {
            return bad("the outline tolerance", self.outline_tolerance_px);
        }
        if !(self.near.is_finite() && self.near > 0.0) {
            return bad("the near plane", self.near);
        }
        Ok(())
    }
}

/// Per body, counts of how the depth readings over its predicted pixels compare.
#[derive(Debug, Clone, Copy, Default)]
struct DepthCounts {
    agrees: usize,
    nearer: usize,
    farther: usize,
}

impl DepthCounts {
    fn readings(&self) -> usize {
        self.agrees + self.nearer + self.farther
    }

    fn agreement(&self) -> Option<f64> {
        let n = self.readings();
        (n > 0).then(|| self.agrees as f64 / n as f64)
    }

    fn covered(&self) -> Option<f64> {
        let n = self.readings();
        (n > 0).then(|| self.nearer as f64 / n as f64)
    }
}

/// The depth readings of `depth` over each body's pixels in `frame`, compared.
fn depth_counts(
    scene: &Scene,
    frame: &Frame,
    depth: &DepthImage,
    tolerance: &DepthTolerance,
) -> Vec<DepthCounts> {
    let mut counts = vec![DepthCounts::default(); scene.bodies.len()];
    for (i, &face) in frame.face.iter().enumerate() {
        let Some(f) = scene.faces.get(face as usize) else {
            continue;
        };
        let c = &mut counts[f.body as usize];
        match tolerance.compare(depth, frame, i) {
            Reading::Agrees => c.agrees += 1,
            Reading::Nearer => c.nearer += 1,
            Reading::Farther => c.farther += 1,
            Reading::None => {}
        }
    }
    counts
}

/// The visible pieces of each body of `scene` (by index), from one drawing seen from
/// `eye`, without the pieces of smooth edges: edges between two faces turned toward the
/// eye whose normals are within the angle of cosine `smooth_cos` (the sides of a
/// many-sided cylinder). Their two faces are lit almost alike, so a picture shows them
/// faintly or not at all, and their absence says nothing. Of a provisional body (a
/// visual hull), only the outline is kept: its other edges are where cones met.
fn pieces_by_body(
    scene: &Scene,
    segments: &[Segment],
    eye: DVec3,
    smooth_cos: f64,
) -> Vec<Vec<Segment>> {
    let faces: HashMap<(u64, u64), [u32; 2]> = scene
        .edges
        .iter()
        .map(|e| ((scene.bodies[e.body as usize].id.get(), e.serial), e.faces))
        .collect();
    let smooth = |s: &Segment| {
        faces.get(&(s.body.get(), s.edge)).is_some_and(|&[f, g]| {
            let (f, g) = (&scene.faces[f as usize], &scene.faces[g as usize]);
            f.faces_toward(eye) && g.faces_toward(eye) && f.normal.dot(g.normal) > smooth_cos
        })
    };
    // A provisional body is a visual hull: its edges between two faces turned toward
    // the eye are where cones met, not edges the object shows; only its outline is.
    let inner = |s: &Segment| {
        faces.get(&(s.body.get(), s.edge)).is_some_and(|&[f, g]| {
            let (f, g) = (&scene.faces[f as usize], &scene.faces[g as usize]);
            scene.bodies[f.body as usize].provisional && f.faces_toward(eye) && g.faces_toward(eye)
        })
    };
    let mut by_body = vec![Vec::new(); scene.bodies.len()];
    for s in segments.iter().filter(|s| !smooth(s) && !inner(s)) {
        if let Ok(b) = scene.bodies.binary_search_by_key(&s.body, |b| b.id) {
            by_body[b].push(*s);
        }
    }
    by_body
}

/// How `body`'s predicted edges are matched: a provisional body's outline may lie up to
/// its `outline_px` outside the object's, so its tolerance is widened by that.
fn for_body(matching: &Matching, body: &SceneBody) -> Matching {
    Matching {
        tolerance_px: matching.tolerance_px + body.outline_px,
        ..*matching
    }
}

/// Marks in `explained` the image edges that the drawing `all` of `scene` accounts for:
/// those along the predicted edges (each body's matched as [`for_body`] says), and every
/// edge inside a provisional body's picture, whose inner edges the model does not know.
fn explain_by_bodies(
    scene: &Scene,
    view: &View,
    all: &[Segment],
    matching: &Matching,
    edges: &EdgeMap,
    explained: &mut [bool],
) {
    let body_of = |id: BodyId| scene.bodies.binary_search_by_key(&id, |b| b.id).ok();
    let (plain, widened): (Vec<Segment>, Vec<Segment>) = all
        .iter()
        .partition(|s| body_of(s.body).is_none_or(|b| scene.bodies[b].outline_px == 0.0));
    matching.explain(edges, &edge_points(&plain, 1.0), explained);
    for s in &widened {
        if let Some(b) = body_of(s.body) {
            let points = edge_points(std::slice::from_ref(s), 1.0);
            for_body(matching, &scene.bodies[b]).explain(edges, &points, explained);
        }
    }
    if scene.bodies.iter().any(|b| b.provisional) {
        let frame = rasterize(scene, view);
        for (bit, &face) in explained.iter_mut().zip(&frame.face) {
            if face != NO_FACE && scene.bodies[scene.faces[face as usize].body as usize].provisional
            {
                *bit = true;
            }
        }
        frame.recycle();
    }
}

/// The logistic of `x`.
fn logistic(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// Evidence from edge support and, when there is depth, depth agreement.
fn evidence(edge_support: f64, depth_agreement: Option<f64>) -> f64 {
    match depth_agreement {
        Some(a) => 0.5 * (edge_support + a),
        None => edge_support,
    }
}

/// The class of every pixel as `scene` predicts it through `view`: pixels that show the
/// same face (or no face) lit alike (the predicted grey level in steps of 16) are one
/// class. Row-major.
fn shade_classes(scene: &Scene, view: &View) -> Vec<u32> {
    let frame = rasterize(scene, view);
    let lit = shaded(scene, view, &Shading::default());
    let mut ids: HashMap<(u32, u8), u32> = HashMap::new();
    frame
        .face
        .iter()
        .zip(lit.data.chunks_exact(3))
        .map(|(&face, rgb)| {
            let grey = (0.299 * rgb[0] as f64 + 0.587 * rgb[1] as f64 + 0.114 * rgb[2] as f64)
                .round() as u8;
            let next = ids.len() as u32;
            *ids.entry((face, grey / 16)).or_insert(next)
        })
        .collect()
}

/// Recognizes the bodies of `scene` in `image` (whose edges `pyramid` holds) and its
/// depth, if given, taken by `camera` (see the [module documentation](self)).
///
/// Preconditions, refused with [`RecognizeError`]: `camera` is valid, the picture and the
/// depth are of the camera's size, the options are in range.
///
/// Postconditions: one report for every body with a visible projected area from the
/// camera, in the scene's order; moved bodies' motions are within the search bounds;
/// the unexplained mask is of the camera's size and the regions are its traced
/// components. Reads `scene` only.
pub fn recognize(
    scene: &Scene,
    camera: &Camera,
    image: &Luma,
    pyramid: &EdgePyramid,
    depth: Option<&DepthImage>,
    options: &RecognizeOptions,
) -> Result<Recognition, RecognizeError> {
    let camera = camera
        .validated()
        .map_err(|e| RecognizeError::Camera(e.to_string()))?;
    let k = camera.intrinsics;
    let (width, height) = pyramid.size();
    if (width, height) != (k.width, k.height) || (image.width(), image.height()) != (width, height)
    {
        return Err(RecognizeError::ImageSize {
            image_width: width,
            image_height: height,
            camera_width: k.width,
            camera_height: k.height,
        });
    }
    if let Some(d) = depth
        && d.size() != (k.width, k.height)
    {
        let (depth_width, depth_height) = d.size();
        return Err(RecognizeError::DepthSize {
            depth_width,
            depth_height,
            camera_width: k.width,
            camera_height: k.height,
        });
    }
    options.validate()?;
    let edges = pyramid.finest();
    let view = View::new(&camera, options.near);
    let matching = &options.matching;

    // 1–2. The prediction where the model has every body, and its evidence.
    let areas = projected_areas(scene, &view);
    let eye = camera.position();
    let smooth_cos = options.smooth_deg.to_radians().cos();
    let pieces = pieces_by_body(scene, &hidden_lines(scene, &view), eye, smooth_cos);
    let frame = depth.map(|_| rasterize(scene, &view));
    let counts = match (depth, &frame) {
        (Some(d), Some(f)) => depth_counts(scene, f, d, &options.depth_tolerance),
        _ => Vec::new(),
    };
    let in_view: Vec<usize> = (0..scene.bodies.len())
        .filter(|&b| areas[b].visible > 0.0)
        .collect();
    // Each body's edge points where the model has it, sampled once.
    let points: Vec<Vec<EdgePoint>> = pieces
        .iter()
        .map(|p| edge_points(p, matching.spacing_px))
        .collect();
    let mut reports = Vec::with_capacity(in_view.len());
    for &b in &in_view {
        let points = &points[b];
        let edge_support = for_body(matching, &scene.bodies[b])
            .support(edges, points)
            .unwrap_or(0.0);
        let depth_agreement = counts.get(b).and_then(DepthCounts::agreement);
        let whole = areas[b].whole;
        reports.push(BodyReport {
            body: b,
            id: scene.bodies[b].id,
            status: Status::Seen,
            score: 0.0,
            visible_fraction: if whole > 0.0 {
                (areas[b].visible / whole).clamp(0.0, 1.0)
            } else {
                0.0
            },
            bbox: areas[b].bbox,
            edge_support,
            edge_points: points.len(),
            depth_agreement,
            motion: None,
        });
    }

    // 3. The bodies not seen where the model has them, looked for nearby.
    let unconfirmed =
        |r: &BodyReport| evidence(r.edge_support, r.depth_agreement) < options.seen_evidence;
    if let Some(bounds) = options.search {
        let search = Search {
            scene,
            camera: &camera,
            pyramid,
            matching: *matching,
            bounds,
            align: &options.align,
        };
        for report in reports.iter_mut().filter(|r| unconfirmed(r)) {
            let b = report.body;
            let Some(found) = search.find(b, &points[b]) else {
                continue;
            };
            // The evidence where the search put it.
            let moved = scene.with_body_moved(b, &scene.body_points(b), &found.motion);
            let drawn = pieces_by_body(&moved, &hidden_lines(&moved, &view), eye, smooth_cos);
            let points = edge_points(&drawn[b], matching.spacing_px);
            let edge_support = for_body(matching, &scene.bodies[b])
                .support(edges, &points)
                .unwrap_or(0.0);
            let depth_agreement = match depth {
                Some(d) => {
                    let f = rasterize(&moved, &view);
                    depth_counts(&moved, &f, d, &options.depth_tolerance)[b].agreement()
                }
                None => None,
            };
            tracing::debug!(
                body = ?scene.bodies[b].name,
                edge_support,
                ?depth_agreement,
                "evidence where the search put it"
            );
            if evidence(edge_support, depth_agreement) >= options.seen_evidence {
                let area = projected_areas(&moved, &view)[b];
                report.status = Status::Moved;
                report.motion = Some(found.motion);
                report.edge_support = edge_support;
                report.edge_points = points.len();
                report.depth_agreement = depth_agreement;
                report.bbox = area.bbox;
                report.visible_fraction = if area.whole > 0.0 {
                    (area.visible / area.whole).clamp(0.0, 1.0)
                } else {
                    0.0
                };
            }
        }
    }
    for report in reports.iter_mut() {
        if report.status == Status::Seen && unconfirmed(report) {
            // Decided below: absent or occluded.
            report.status = Status::Absent;
        }
    }

    // 4. The model as recognized: moved bodies moved, the others not confirmed taken out.
    let mut updated = scene.clone();
    for r in reports.iter().filter(|r| r.status == Status::Moved) {
        if let Some(m) = &r.motion {
            updated = updated.with_body_moved(r.body, &scene.body_points(r.body), m);
        }
    }
    let gone: Vec<bool> = {
        let mut gone = vec![false; scene.bodies.len()];
        for r in reports.iter().filter(|r| r.status == Status::Absent) {
            gone[r.body] = true;
        }
        gone
    };
    let updated = updated.without_bodies(|b| gone[b]);
    let (w, h) = (k.width as usize, k.height as usize);
    let mut explained = vec![false; w * h];
    let all = hidden_lines(&updated, &view);
    explain_by_bodies(&updated, &view, &all, matching, edges, &mut explained);

    // 5. The unexplained regions.
    let regions = match depth {
        Some(d) => {
            let f = rasterize(&updated, &view);
            let mut nearer = Flags::new(w, h);
            for (i, bit) in nearer.bits.iter_mut().enumerate() {
                *bit = options.depth_tolerance.compare(d, &f, i) == Reading::Nearer;
            }
            opened(&nearer, 1)
        }
        None => {
            // The edge pixels (as `explained` marks them: by the pixel, not by the
            // sub-pixel position) that nothing explains.
            let mut loose = Flags::new(w, h);
            for (i, bit) in loose.bits.iter_mut().enumerate() {
                *bit = !explained[i] && edges.edgel_at((i % w) as u32, (i / w) as u32).is_some();
            }
            let classes = shade_classes(&updated, &view);
            let unlike = deviant(
                image.pixels(),
                &classes,
                w,
                h,
                options.deviation_spread,
                options.deviation_least,
            );
            let outlined = enclosed(&loose, options.close_px);
            opened(&outlined.union(&opened(&unlike, 2)).filled(), 1)
        }
    };
    let regions = regions.without_specks(options.min_region_px.ceil() as usize);
    let mask = Mask::from_fn(k.width, k.height, |x, y| {
        regions.bits[y as usize * w + x as usize]
    });
    let mut unexplained = trace_regions(
        &mask,
        &ContourOptions {
            tolerance_px: options.outline_tolerance_px,
            min_area_px: 0.0,
            outward: false,
        },
    );
    unexplained.sort_by(|a, b| b.area.total_cmp(&a.area));

    // 6. Absent or occluded, and the scores.
    for report in reports.iter_mut() {
        let b = report.body;
        let e = evidence(report.edge_support, report.depth_agreement);
        let certainty =
            report.edge_points as f64 / (report.edge_points + options.min_points) as f64;
        let sure = |p: f64| 0.5 + (p - 0.5) * certainty;
        match report.status {
            Status::Seen | Status::Moved => {
                report.score = sure(logistic(SCORE_SLOPE * (e - options.seen_evidence)));
            }
            Status::Absent | Status::Occluded => {
                let covered = match counts.get(b).and_then(DepthCounts::covered) {
                    Some(c) => c,
                    None => {
                        let points = &points[b];
                        let inside = points
                            .iter()
                            .filter(|p| {
                                let (x, y) = (p.pixel.x.floor(), p.pixel.y.floor());
                                x >= 0.0
                                    && y >= 0.0
                                    && (x as usize) < w
                                    && (y as usize) < h
                                    && regions.bits[y as usize * w + x as usize]
                            })
                            .count();
                        if points.is_empty() {
                            0.0
                        } else {
                            inside as f64 / points.len() as f64
                        }
                    }
                };
                if covered >= 0.5 {
                    report.status = Status::Occluded;
                    report.score = sure(logistic(SCORE_SLOPE * (covered - 0.5)));
                } else {
                    report.score = sure(1.0 - logistic(SCORE_SLOPE * (e - options.seen_evidence)));
                }
            }
        }
    }
    Ok(Recognition {
        bodies: reports,
        unexplained,
        unexplained_mask: mask,
    })
}

#[cfg(test)]
mod tests;
