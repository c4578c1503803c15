//! Appearance: what the world looks like from a camera.
//!
//! Rendering reads a [`Scene`], the world flattened for drawing at one revision, and
//! never touches the shared world. [`scene`] builds it; [`image`] holds the raster
//! images and their PNG encoding; [`lines`] draws anti-aliased lines; [`raster`] makes
//! the pixel pictures (z-buffer, shaded, wireframe, depth and body ids); [`hidden`]
//! computes the exact hidden-line drawing as vector segments (and draws it, or writes it
//! as SVG); [`render`] chooses among them by [`Mode`]. Three private modules serve them:
//! `buffers`, a pool of large pixel buffers kept from one picture for the next (give a
//! picture's buffers back with [`raster::Frame::recycle`] and [`RgbImage::recycle`]);
//! `cache`, the shadow maps a scene keeps for its pictures ([`raster::ShadowCache`]);
//! and `deflate`, the parallel DEFLATE encoder behind the PNG files.
//!
//! Every mode starts from the same camera ([`crate::camera::View`]) and the same clipping
//! at the near plane, so a pixel of the `ids` image, a depth value and a hidden-line
//! segment all describe the same picture.

pub(crate) mod buffers;
mod cache;
mod deflate;
pub mod hidden;
pub mod image;
pub mod lines;
pub mod raster;
pub mod sample;
pub mod scene;

pub use image::{Gray16, RgbImage};
pub use scene::{Scene, SceneBody, SceneEdge, SceneFace};

use serde::{Deserialize, Serialize};

use crate::camera::{Camera, DEFAULT_NEAR, View};
use crate::model::BodyId;

/// What to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Z-buffered faces in their material colours, ambient light plus every light
    /// source, Lambert shading and cast shadows.
    #[default]
    Shaded,
    /// Every edge, anti-aliased.
    Wire,
    /// The exact hidden-line drawing: only the visible portions of edges.
    Hidden,
    /// 16-bit depth: −ZCC of the nearest surface, in units of
    /// [`Options::depth_scale`] meters; 0 where no surface is.
    Depth,
    /// 16-bit body ids: which body covers each pixel, through a legend; 0 for none.
    Ids,
}

impl Mode {
    /// The mode's name as the API spells it.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Shaded => "shaded",
            Mode::Wire => "wire",
            Mode::Hidden => "hidden",
            Mode::Depth => "depth",
            Mode::Ids => "ids",
        }
    }
}

/// How to draw: colours, shadows, near plane and depth scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Background colour (`shaded`, `wire`, `hidden`).
    pub background: [u8; 3],
    /// Line colour (`wire`, `hidden`).
    pub ink: [u8; 3],
    /// Whether `shaded` casts shadows.
    pub shadows: bool,
    /// Ambient light in `shaded`, 0 to 1.
    pub ambient: f64,
    /// Near-plane distance, meters (> 0).
    pub near: f64,
    /// Meters per unit of a `depth` image (> 0): 0.001 gives millimetres, 65.535 m at
    /// most.
    pub depth_scale: f64,
}

impl Default for Options {
    /// White background and black ink for drawings (the background of `shaded` is a
    /// light grey-blue), shadows on, ambient 0.25, near plane at
    /// [`crate::camera::DEFAULT_NEAR`], depth in millimetres.
    fn default() -> Self {
        Options {
            background: [255, 255, 255],
            ink: [0, 0, 0],
            shadows: true,
            ambient: 0.25,
            near: DEFAULT_NEAR,
            depth_scale: 0.001,
        }
    }
}

/// The background `shaded` uses unless one is given.
pub const SHADED_BACKGROUND: [u8; 3] = [200, 210, 225];

/// A finished rendering, before encoding.
#[derive(Clone, Debug)]
pub enum Picture {
    /// `shaded` and `wire`.
    Rgb(RgbImage),
    /// `hidden`: the visible segments, to be drawn, written as SVG or listed.
    Lines {
        /// The visible portions of edges.
        segments: Vec<hidden::Segment>,
        /// Image width, pixels.
        width: u32,
        /// Image height, pixels.
        height: u32,
    },
    /// `depth`.
    Depth {
        /// The depth image.
        image: Gray16,
        /// Meters per unit.
        meters_per_unit: f64,
    },
    /// `ids`.
    Ids {
        /// Pixel value v ≥ 1 is body `legend[v − 1]`; 0 is background.
        image: Gray16,
        /// The bodies that appear, in id order.
        legend: Vec<BodyId>,
    },
}

/// Why a rendering was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RenderError {
    /// More bodies appear than a 16-bit ids image can number.
    #[error(transparent)]
    Ids(#[from] raster::IdsError),
}

/// Draws `scene` as `camera` sees it, in `mode`.
///
/// Preconditions: `camera` is valid ([`Camera::validated`]); `options.near` and
/// `options.depth_scale` are finite and positive. The image is
/// `camera.intrinsics.width × height` pixels.
pub fn render(
    scene: &Scene,
    camera: &Camera,
    mode: Mode,
    options: &Options,
) -> Result<Picture, RenderError> {
    let view = View::new(camera, options.near);
    let (width, height) = view.size();
    Ok(match mode {
        Mode::Shaded => Picture::Rgb(raster::shaded(
            scene,
            &view,
            &raster::Shading {
                background: options.background,
                ambient: options.ambient,
                shadows: options.shadows,
                ..raster::Shading::default()
            },
        )),
        Mode::Wire => Picture::Rgb(raster::wire(scene, &view, options.background, options.ink)),
        Mode::Hidden => Picture::Lines {
            segments: hidden::hidden_lines(scene, &view),
            width,
            height,
        },
        Mode::Depth => {
            let frame = raster::rasterize(scene, &view);
            let image = raster::depth_image(&frame, options.depth_scale);
            frame.recycle();
            Picture::Depth {
                image,
                meters_per_unit: options.depth_scale,
            }
        }
        Mode::Ids => {
            let frame = raster::rasterize(scene, &view);
            let ids = raster::ids_image(scene, &frame);
            frame.recycle();
            let (image, legend) = ids?;
            Picture::Ids { image, legend }
        }
    })
}
