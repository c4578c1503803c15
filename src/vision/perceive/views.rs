//! From the views a request gives (solved cameras and masks) to carved bodies: masks
//! checked, widened by the model's occluders, traced into silhouettes, and carved.

use super::mesh::Mesh;
use super::silhouette::silhouettes;
use super::{Depths, Outline, PerceiveError, Sight, Tally, carve_by, occlusion, visual_hull};
use crate::model::camera::Camera;
use crate::render::Scene;
use crate::vision::image::Mask;

/// One view as a request gives it: a solved camera and the mask of the new object in
/// its picture (inside = the object, or where it may be).
#[derive(Clone, Debug)]
pub struct MaskView {
    /// The camera.
    pub camera: Camera,
    /// The mask, the camera's size.
    pub mask: Mask,
}

/// How silhouettes are made and cones taken.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerceiveOptions {
    /// The depths the cones span.
    pub depths: Depths,
    /// How far, in pixels, silhouettes are widened so that calibration error and blur
    /// do not cut into the object.
    pub tolerance_px: f64,
    /// Regions of fewer pixels are left out (specks of noise).
    pub min_area_px: f64,
}

impl Default for PerceiveOptions {
    /// Cones from 5 cm to 20 m, silhouettes widened by 1 pixel, regions of fewer than
    /// 16 pixels left out.
    fn default() -> Self {
        PerceiveOptions {
            depths: Depths::default(),
            tolerance_px: 1.0,
            min_area_px: 16.0,
        }
    }
}

/// Why views could not be carved into bodies.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ViewsError {
    /// A mask is not its camera's size.
    #[error(
        "view {view}: the mask is {mask_width} × {mask_height} pixels but the camera's picture is {camera_width} × {camera_height}"
    )]
    MaskSize {
        /// The view.
        view: u32,
        /// The mask's width.
        mask_width: u32,
        /// The mask's height.
        mask_height: u32,
        /// The camera's width.
        camera_width: u32,
        /// The camera's height.
        camera_height: u32,
    },
    /// A mask has no region of at least the least area.
    #[error("view {view}: the mask holds no region of {min_area_px} pixels or more")]
    EmptyMask {
        /// The view.
        view: u32,
        /// The least area asked for.
        min_area_px: f64,
    },
    /// The views' cones have no point in common.
    #[error("the cones of views {views:?} do not meet: no solid is seen by all of them")]
    ConesApart {
        /// Views whose cones do not meet (two, where two suffice).
        views: Vec<u32>,
    },
    /// Carving failed.
    #[error(transparent)]
    Perceive(#[from] PerceiveError),
}

/// The sights of `views`, numbered from `first`: each mask widened by what `occluders`
/// covers next to it (with `hull`, a solid holding the object, only where the covering
/// surface is nearer than the hull's far side; see [`occlusion`]), then traced (see
/// [`silhouettes`]); every region of a view goes into its outline.
pub fn sights(
    views: &[MaskView],
    occluders: Option<&Scene>,
    hull: Option<&[Mesh]>,
    options: &PerceiveOptions,
    first: u32,
) -> Result<Vec<Sight>, ViewsError> {
    let mut out = Vec::with_capacity(views.len());
    for (i, v) in views.iter().enumerate() {
        let view = first + i as u32;
        let k = v.camera.intrinsics;
        if (v.mask.width(), v.mask.height()) != (k.width, k.height) {
            return Err(ViewsError::MaskSize {
                view,
                mask_width: v.mask.width(),
                mask_height: v.mask.height(),
                camera_width: k.width,
                camera_height: k.height,
            });
        }
        let empty = ViewsError::EmptyMask {
            view,
            min_area_px: options.min_area_px,
        };
        if v.mask.count() == 0 {
            return Err(empty);
        }
        let mask = match occluders {
            Some(scene) => occlusion::with_occluders(&v.mask, scene, &v.camera, hull),
            None => v.mask.clone(),
        };
        let regions = silhouettes(&mask, options.tolerance_px, options.min_area_px);
        if regions.is_empty() {
            return Err(empty);
        }
        let rings = regions.into_iter().flat_map(|r| r.outline.rings).collect();
        out.push(Sight {
            camera: v.camera,
            outline: Outline { rings },
            view,
        });
    }
    Ok(out)
}

/// New bodies from `sights`: the visual hull's connected pieces, largest first. Refused
/// with [`ViewsError::ConesApart`] when nothing is left, naming two views whose cones
/// do not meet where there are such, else every view.
pub fn new_bodies(
    sights: &[Sight],
    depths: Depths,
    tally: &mut Tally,
) -> Result<Vec<Mesh>, ViewsError> {
    let pieces = visual_hull(sights, depths, tally)?;
    if !pieces.is_empty() {
        return Ok(pieces);
    }
    for j in 1..sights.len() {
        for i in 0..j {
            let pair = [sights[i].clone(), sights[j].clone()];
            if visual_hull(&pair, depths, &mut Tally::default())?.is_empty() {
                return Err(ViewsError::ConesApart {
                    views: vec![sights[i].view, sights[j].view],
                });
            }
        }
    }
    Err(ViewsError::ConesApart {
        views: sights.iter().map(|s| s.view).collect(),
    })
}

/// `body` (in world coordinates) carved by `sights`: its pieces, largest first; none when
/// the views carve it away.
pub fn carve_body(
    body: Mesh,
    sights: &[Sight],
    depths: Depths,
    tally: &mut Tally,
) -> Result<Vec<Mesh>, PerceiveError> {
    let mut pieces = vec![body];
    for s in sights {
        pieces = carve_by(pieces, s, depths, tally)?;
        if pieces.is_empty() {
            break;
        }
    }
    pieces.sort_by(|a, b| b.volume().total_cmp(&a.volume()));
    Ok(pieces)
}
