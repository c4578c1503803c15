//! The JSON bodies of the write requests (`POST /v1/bodies`, `PATCH /v1/bodies/{id}`,
//! the Euler, transform, sweep and boolean routes, `PUT /v1/cameras/{name}`, `PUT
//! /v1/lights/{name}`), as the HTTP API reads them: defaults filled, unknown fields
//! refused, lists bounded while they are read (a polyhedron past the edit language's
//! limits is refused with 413 before the rest of it is read).
//!
//! Each converts into the edit language's command ([`crate::edit::command`]) with
//! `From`; the journal keeps the command, never the request, so this JSON can grow
//! without changing the journal's format.
//!
//! Ids are the kernel's serial numbers (JSON integers). Vectors are `[x, y, z]` arrays in
//! meters; a pose is `{"position": [x, y, z], "rotation": [qx, qy, qz, qw]}`.

mod into_command;
mod shape_json;

pub use into_command::{MeshCreate, NewBody};

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

use crate::edit::command::{CameraSpec, CameraSpecError};
pub use crate::edit::command::{
    FaceList, MAX_BODY_CORNERS, MAX_BODY_FACES, MAX_BODY_VERTICES, bounded,
};
use crate::model::{Camera, Color, Light, Pose};

/// A pose relative to the parent body.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PoseDto {
    /// Position `[x, y, z]`, meters.
    #[serde(default)]
    pub position: [f64; 3],
    /// Unit quaternion `[qx, qy, qz, qw]`.
    #[serde(default = "identity_quat")]
    pub rotation: [f64; 4],
}

fn identity_quat() -> [f64; 4] {
    [0.0, 0.0, 0.0, 1.0]
}

impl PoseDto {
    /// The kernel pose (not yet validated: the world validates it).
    pub fn to_pose(self) -> Pose {
        let [x, y, z, w] = self.rotation;
        Pose {
            position: DVec3::from_array(self.position),
            rotation: DQuat::from_xyzw(x, y, z, w),
        }
    }
}

impl From<Pose> for PoseDto {
    fn from(p: Pose) -> Self {
        PoseDto {
            position: p.position.to_array(),
            rotation: p.rotation.to_array(),
        }
    }
}

fn d32() -> u32 {
    32
}
fn d16() -> u32 {
    16
}

/// The solid a new body starts as. Primitives are centred on the body's origin; those
/// with an axis have it on z, centred in height.
///
/// In JSON, an object whose `type` names the variant (snake case) beside the variant's
/// fields. It is read field by field as it streams, lists bounded while they are read
/// (see `shape_json`): unknown fields and those of other variants are refused, and a
/// polyhedron past [`MAX_BODY_VERTICES`], [`MAX_BODY_FACES`] or [`MAX_BODY_CORNERS`]
/// is refused before the rest of it is read.
#[derive(Clone, Debug, Serialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Shape {
    /// A box of `size` `[x, y, z]` (Baumgart's MKCUBE).
    Box {
        /// Edge lengths.
        size: [f64; 3],
    },
    /// A regular tetrahedron with vertices `radius` from the centre (MKTETRA).
    Tetrahedron {
        /// Circumradius.
        radius: f64,
    },
    /// A polygon in the xy-plane swept up by `height` (PRISM).
    Prism {
        /// The polygon's corners `[x, y]`, in order.
        polygon: Vec<[f64; 2]>,
        /// The height.
        height: f64,
    },
    /// A polygon in the xy-plane with a peak `height` above its centroid (PYRAMID).
    Pyramid {
        /// The polygon's corners `[x, y]`, in order.
        polygon: Vec<[f64; 2]>,
        /// The height.
        height: f64,
    },
    /// A cylinder of `segments` sides.
    Cylinder {
        /// Radius.
        radius: f64,
        /// Height.
        height: f64,
        /// Sides round the axis (default 32).
        segments: u32,
    },
    /// A cone of `segments` sides.
    Cone {
        /// Base radius.
        radius: f64,
        /// Height.
        height: f64,
        /// Sides round the axis (default 32).
        segments: u32,
    },
    /// A UV sphere.
    Sphere {
        /// Radius.
        radius: f64,
        /// Meridians (default 32).
        segments: u32,
        /// Parallels, bands from pole to pole (default 16).
        rings: u32,
    },
    /// A torus about the z axis.
    Torus {
        /// Distance from the axis to the tube's centre.
        major_radius: f64,
        /// The tube's radius.
        minor_radius: f64,
        /// Steps round the axis (default 32).
        segments: u32,
        /// Steps round the tube (default 16).
        rings: u32,
    },
    /// A closed polyhedron from vertex and face lists; each face lists vertex indices
    /// counter-clockwise seen from outside.
    Polyhedron {
        /// Vertex loci.
        vertices: Vec<[f64; 3]>,
        /// Faces as vertex indices.
        faces: FaceList,
    },
    /// MKBFV: one face and one vertex, the seed of an Euler construction.
    Seminal {
        /// The vertex locus (default the origin).
        position: [f64; 3],
    },
    /// A mesh file (base64 in `data`), one body per object of the file.
    Mesh(Box<MeshShape>),
}

/// A mesh file inside a JSON request, and how to read it.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct MeshShape {
    /// The file's format.
    pub format: crate::mesh::Format,
    /// The file, base64 (standard alphabet, padding optional).
    pub data: String,
    /// How to read it.
    #[serde(flatten)]
    pub options: MeshOptions,
}

/// How a mesh file is read: the `mesh` shape's fields, or `POST /v1/bodies/import`'s
/// query parameters. Unset, each takes the default of [`crate::mesh::ImportOptions`].
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct MeshOptions {
    /// The file's length unit (`m`, `mm`, `cm`, `in`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit: Option<crate::mesh::Unit>,
    /// Whether adjacent coplanar faces become one polygon (default true).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub merge_coplanar: Option<bool>,
    /// Vertices closer than this many meters are one (default 0: equal coordinates).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weld: Option<f64>,
    /// How far from a merged face's plane its vertices may lie, as a fraction of the
    /// piece's size (default 1e-6).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coplanar_tolerance: Option<f64>,
    /// Whether faces are tested for crossing each other (default true).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub check_intersections: Option<bool>,
}

impl MeshOptions {
    /// The import options these ask for.
    ///
    /// # Errors
    /// A `weld` that is negative, not finite or above 1 m; a `coplanar_tolerance`
    /// outside `[0, 0.01]`.
    pub fn to_import(self) -> Result<crate::mesh::ImportOptions, String> {
        let mut o = crate::mesh::ImportOptions {
            unit: self.unit,
            ..crate::mesh::ImportOptions::default()
        };
        if let Some(m) = self.merge_coplanar {
            o.merge_coplanar = m;
        }
        if let Some(w) = self.weld {
            if !(w.is_finite() && (0.0..=1.0).contains(&w)) {
                return Err(format!("weld must be between 0 and 1 (meters), not {w}"));
            }
            o.weld = w;
        }
        if let Some(t) = self.coplanar_tolerance {
            if !(t.is_finite() && (0.0..=0.01).contains(&t)) {
                return Err(format!(
                    "coplanar_tolerance must be between 0 and 0.01, not {t}"
                ));
            }
            o.coplanar_tolerance = t;
        }
        if let Some(c) = self.check_intersections {
            o.check_crossings = c;
        }
        Ok(o)
    }
}

/// A material colour in JSON: the string `"#rrggbb"`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HexColor(pub Color);

impl Serialize for HexColor {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.0.to_hex())
    }
}

impl<'de> Deserialize<'de> for HexColor {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let text = String::deserialize(d)?;
        Color::from_hex(&text).map(HexColor).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "colour {text:?} is not of the form \"#rrggbb\" (hexadecimal)"
            ))
        })
    }
}

/// `POST /v1/bodies`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CreateBody {
    /// A unique name (optional).
    #[serde(default)]
    pub name: Option<String>,
    /// The supart's id (default: the world).
    #[serde(default)]
    pub parent: Option<u64>,
    /// Pose relative to the supart (default: identity).
    #[serde(default)]
    pub pose: Option<PoseDto>,
    /// Material colour `"#rrggbb"` (default: one chosen from the body's id).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<HexColor>,
    /// The solid.
    pub shape: Shape,
}

/// `PATCH /v1/bodies/{id}`: any of name, parent, pose and colour. `"name": null` removes
/// the name; `"color": null` restores the default colour.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct PatchBody {
    /// New name; `null` to remove it. Absent (not `null`) when written out with no
    /// change of name, so that it reads back as no change.
    #[serde(
        default,
        deserialize_with = "some_or_null",
        skip_serializing_if = "Option::is_none"
    )]
    pub name: Option<Option<String>>,
    /// New supart.
    #[serde(default)]
    pub parent: Option<u64>,
    /// New pose relative to the supart.
    #[serde(default)]
    pub pose: Option<PoseDto>,
    /// New material colour `"#rrggbb"`; `null` restores the default. Absent when
    /// written out with no change of colour.
    #[serde(
        default,
        deserialize_with = "some_or_null",
        skip_serializing_if = "Option::is_none"
    )]
    pub color: Option<Option<HexColor>>,
}

fn some_or_null<'de, D, T>(d: D) -> Result<Option<Option<T>>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    Option::<T>::deserialize(d).map(Some)
}

/// `POST /v1/bodies/{id}/euler`: one Euler operator, by its Baumgart name.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "op", rename_all = "snake_case", deny_unknown_fields)]
pub enum EulerOp {
    /// MKEV: a spur from `vertex` into `face`, its new vertex at `position` (default: at
    /// `vertex`).
    Mkev {
        /// Face id.
        face: u64,
        /// Vertex id.
        vertex: u64,
        /// Locus of the new vertex.
        #[serde(default)]
        position: Option<[f64; 3]>,
    },
    /// MKFE: split `face` by a new edge from `v1` to `v2`.
    Mkfe {
        /// First vertex id (the new edge's PVT).
        v1: u64,
        /// Face id.
        face: u64,
        /// Second vertex id.
        v2: u64,
    },
    /// ESPLIT: split `edge` at `position` (default: its midpoint).
    Esplit {
        /// Edge id.
        edge: u64,
        /// Locus of the new vertex.
        #[serde(default)]
        position: Option<[f64; 3]>,
    },
    /// KLFE: kill `edge` and its NFACE.
    Klfe {
        /// Edge id.
        edge: u64,
    },
    /// KLEV: kill `vertex` (one or two edges) and its PED.
    Klev {
        /// Vertex id.
        vertex: u64,
    },
    /// KLVE: kill `edge` and its NVT (contract it).
    Klve {
        /// Edge id.
        edge: u64,
    },
    /// INVERT: turn `edge` round.
    Invert {
        /// Edge id.
        edge: u64,
    },
    /// GLUE: identify `face2` (of this or another body) with `face1`, pairing `vertex1`
    /// with `vertex2` (default: the first vertex of `face1` with the nearest of `face2`).
    Glue {
        /// Face id in this body.
        face1: u64,
        /// Face id in this or another body.
        face2: u64,
        /// Vertex of `face1`.
        #[serde(default)]
        vertex1: Option<u64>,
        /// Vertex of `face2`.
        #[serde(default)]
        vertex2: Option<u64>,
    },
    /// GLUEE: a wasp edge from `vertex1` on `face1` to `vertex2` on `face2`, killing
    /// `face2`.
    Gluee {
        /// Face id in this body.
        face1: u64,
        /// Vertex of `face1`.
        vertex1: u64,
        /// Face id in this or another body.
        face2: u64,
        /// Vertex of `face2`.
        vertex2: u64,
    },
    /// GLUEFF: a tube of quadrilaterals between `face1` and `face2`.
    Glueff {
        /// Face id in this body.
        face1: u64,
        /// Face id in this or another body.
        face2: u64,
    },
    /// UNGLUE: cut along the closed loop of `edges`.
    Unglue {
        /// Edge ids forming one closed loop.
        edges: Vec<u64>,
    },
}

impl EulerOp {
    /// The face a gluing operator names in a second (possibly other) body.
    pub fn second_face(&self) -> Option<u64> {
        match *self {
            EulerOp::Glue { face2, .. }
            | EulerOp::Gluee { face2, .. }
            | EulerOp::Glueff { face2, .. } => Some(face2),
            _ => None,
        }
    }
}

/// What to move in `POST /v1/bodies/{id}/transform`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "op", rename_all = "snake_case")]
pub enum TransformOp {
    /// TRANSLATE by `vector`.
    Translate {
        /// The displacement.
        vector: [f64; 3],
    },
    /// ROTATE by `angle_deg` about `axis` through `center`.
    Rotate {
        /// Axis direction.
        axis: [f64; 3],
        /// Angle in degrees (right-hand rule).
        angle_deg: f64,
        /// A point on the axis (default: the frame's origin).
        #[serde(default)]
        center: [f64; 3],
    },
    /// DILATE by `factor` about `center`.
    Dilate {
        /// Scale factor, > 0.
        factor: f64,
        /// Fixed point (default: the frame's origin).
        #[serde(default)]
        center: [f64; 3],
    },
    /// REFLECT in the plane through `point` with `normal`.
    Reflect {
        /// Plane normal.
        normal: [f64; 3],
        /// A point of the plane (default: the frame's origin).
        #[serde(default)]
        point: [f64; 3],
    },
}

/// The frame a transform's numbers are given in.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum FrameDto {
    /// World coordinates.
    #[default]
    World,
    /// The body's own coordinates.
    Body,
}

/// `POST /v1/bodies/{id}/transform`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct TransformReq {
    /// The transform.
    #[serde(flatten)]
    pub op: TransformOp,
    /// `world` (default) or `body`.
    #[serde(default)]
    pub frame: FrameDto,
    /// A face, edge or vertex id of the body to move instead of the whole body.
    #[serde(default)]
    pub target: Option<u64>,
}

/// The sweep primitives of `POST /v1/bodies/{id}/sweep`.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SweepKind {
    /// PRISM: translational sweep.
    Prism,
    /// PYRAMID: a peak joined to every vertex.
    Pyramid,
    /// CWPRISMOID.
    CwPrismoid,
    /// CCWPRISMOID.
    CcwPrismoid,
}

/// `POST /v1/bodies/{id}/sweep`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SweepReq {
    /// The face swept.
    pub face: u64,
    /// Which sweep.
    pub kind: SweepKind,
    /// How far along the face's outward normal (prisms: the offset; pyramid: the peak's
    /// height over the face centre). Ignored when `offset` or `peak` is given.
    #[serde(default)]
    pub distance: Option<f64>,
    /// The sweep's offset vector (prisms), body frame.
    #[serde(default)]
    pub offset: Option<[f64; 3]>,
    /// The peak (pyramid), body frame.
    #[serde(default)]
    pub peak: Option<[f64; 3]>,
    /// Scale of the new ring about the face centre (prisms; default 1).
    #[serde(default)]
    pub scale: Option<f64>,
}

/// The booleans of `POST /v1/bodies/{id}/boolean`.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum BooleanOp {
    /// BIN: the points inside both bodies.
    Intersection,
    /// BUN: the points inside either body.
    Union,
    /// The points inside this body and not inside the other.
    Difference,
}

/// `POST /v1/bodies/{id}/boolean`: this body combined with the body `with`; the result
/// replaces this body.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct BooleanReq {
    /// Which boolean.
    pub op: BooleanOp,
    /// The other body's id.
    pub with: u64,
    /// Whether the other body survives (default: it is killed).
    #[serde(default)]
    pub keep_with: bool,
}

/// `POST /v1/bodies/{id}/copy`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct CopyReq {
    /// The copy's name.
    #[serde(default)]
    pub name: Option<String>,
}

/// Camera intrinsics in pixels.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct IntrinsicsDto {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Focal length along u.
    pub fx: f64,
    /// Focal length along v.
    pub fy: f64,
    /// Principal point u.
    pub cx: f64,
    /// Principal point v.
    pub cy: f64,
}

/// Baumgart's camera raster: FOCAL (mm), logical raster LDX × LDY, physical PDX × PDY.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BaumgartDto {
    /// Focal length.
    pub focal: f64,
    /// Logical raster width (pixels).
    pub ldx: u32,
    /// Logical raster height (pixels).
    pub ldy: u32,
    /// Physical raster width (same unit as focal).
    pub pdx: f64,
    /// Physical raster height.
    pub pdy: f64,
}

/// The look-at helper: a camera at `eye` looking at `target`, `up` roughly up.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LookAtDto {
    /// Lens centre.
    pub eye: [f64; 3],
    /// Point looked at.
    pub target: [f64; 3],
    /// Up direction (default +z).
    #[serde(default = "up_z")]
    pub up: [f64; 3],
}

fn up_z() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

/// `PUT /v1/cameras/{name}`: a pose or a look-at, and intrinsics or Baumgart's raster.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraReq {
    /// Pose in the world (camera looks along its −k axis).
    #[serde(default)]
    pub pose: Option<PoseDto>,
    /// Or: where it stands and what it looks at.
    #[serde(default)]
    pub look_at: Option<LookAtDto>,
    /// Intrinsics in pixels.
    #[serde(default)]
    pub intrinsics: Option<IntrinsicsDto>,
    /// Or: Baumgart's form.
    #[serde(default)]
    pub baumgart: Option<BaumgartDto>,
}

impl CameraReq {
    /// The camera described, checked (as a write of it would be).
    pub fn to_camera(&self) -> Result<Camera, CameraSpecError> {
        CameraSpec::from(*self).to_camera()
    }
}

/// `PUT /v1/lights/{name}`: a sun (direction the light travels) or a point lamp.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum LightDto {
    /// Light at infinity.
    Sun {
        /// Direction the light travels (a noon sun is `[0, 0, -1]`).
        direction: [f64; 3],
        /// Intensity ≥ 0 (default 1).
        #[serde(default = "one")]
        intensity: f64,
    },
    /// A point lamp.
    Point {
        /// Where it is.
        position: [f64; 3],
        /// Intensity ≥ 0 (default 1).
        #[serde(default = "one")]
        intensity: f64,
    },
}

fn one() -> f64 {
    1.0
}

impl From<&Light> for LightDto {
    fn from(l: &Light) -> Self {
        match *l {
            Light::Sun {
                direction,
                intensity,
            } => LightDto::Sun {
                direction: direction.to_array(),
                intensity,
            },
            Light::Point {
                position,
                intensity,
            } => LightDto::Point {
                position: position.to_array(),
                intensity,
            },
        }
    }
}
