//! The commands of the edit language: what each write asks for (a body's shape, an Euler
//! operator, a transform, a camera or a light), in the kernel's own types, and in the
//! serde form the journal stores.
//!
//! These are not the HTTP API's types: the server reads a request in types of its own
//! and turns it into a command, so the API's JSON can change without changing what the
//! journal holds. The serde form here **is** the journal's format, version
//! [`FORMAT`]: a change to it must keep reading every entry ever written, or come with a
//! new version and a reader for the old one; `tests/fixtures/journal-2026-11/` holds a
//! journal of version 1 that must keep replaying to its world.
//!
//! Ids are the kernel's serial numbers (JSON integers). Vectors are `[x, y, z]` arrays in
//! meters; a pose is `{"position": [x, y, z], "rotation": [qx, qy, qz, qw]}`; a colour
//! is `"#rrggbb"`.

pub mod bounded;
mod face_list;
pub mod packed;

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::model::{
    BaumgartRaster, Camera, Color, Frame, Intrinsics, Light, LightError, Maker, Pose,
    camera::CameraError,
};
pub use face_list::FaceList;

/// The version of the serde form of [`Edit`](super::Edit) and its commands that this
/// build writes (and, with every earlier one, reads).
///
/// Version 2 packs the geometry of the edits that carry computed polygons
/// ([`ImportedBody`], [`BooleanPiece`], [`PerceivedPiece`]) into base64 strings (see
/// [`packed`]); version 1 wrote it as JSON lists, which still reads. Every other
/// command's form is that of version 1.
pub const FORMAT: u32 = 2;

/// The most faces a body made by one edit may have: the model's own limit, which a
/// boolean's result is held to as well.
pub use crate::model::range::MAX_BODY_FACES;

/// The most vertices a polyhedron given in one edit may have: twice the faces, which
/// every closed polyhedron of [`MAX_BODY_FACES`] faces without handles stays below
/// (its vertices number at most `2F − 4`, when each meets three faces).
pub const MAX_BODY_VERTICES: usize = 2 * MAX_BODY_FACES;

/// The most vertex indices a polyhedron given in one edit may list in all its faces:
/// six per face, which every closed polyhedron of [`MAX_BODY_FACES`] faces without
/// handles stays below (its indices, two per edge, number at most `6F − 12`).
pub const MAX_BODY_CORNERS: usize = 6 * MAX_BODY_FACES;

/// The solid a new body starts as. Primitives are centred on the body's origin; those
/// with an axis have it on z, centred in height. Parameters are checked when the body is
/// built (see [`crate::model::solids`]). Read, a missing count of steps is 32 round the
/// axis and 16 round a sphere's or torus's other way, a missing seminal locus the
/// origin (every entry written has them all).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Shape {
    /// MKCUBE: a box of edge lengths `size`.
    Box {
        /// Edge lengths along x, y and z.
        size: DVec3,
    },
    /// MKTETRA: a regular tetrahedron with vertices `radius` from the centre.
    Tetrahedron {
        /// Circumradius.
        radius: f64,
    },
    /// PRISM: a polygon in the xy-plane swept up by `height`.
    Prism {
        /// The polygon's corners, in order.
        polygon: Vec<DVec2>,
        /// The height.
        height: f64,
    },
    /// PYRAMID: a polygon in the xy-plane with a peak `height` above its centroid.
    Pyramid {
        /// The polygon's corners, in order.
        polygon: Vec<DVec2>,
        /// The height.
        height: f64,
    },
    /// A cylinder of `segments` sides.
    Cylinder {
        /// Radius.
        radius: f64,
        /// Height.
        height: f64,
        /// Sides round the axis.
        #[serde(default = "d32")]
        segments: u32,
    },
    /// A cone of `segments` sides.
    Cone {
        /// Base radius.
        radius: f64,
        /// Height.
        height: f64,
        /// Sides round the axis.
        #[serde(default = "d32")]
        segments: u32,
    },
    /// A UV sphere of `segments × rings` faces.
    Sphere {
        /// Radius.
        radius: f64,
        /// Meridians.
        #[serde(default = "d32")]
        segments: u32,
        /// Parallels, bands from pole to pole.
        #[serde(default = "d16")]
        rings: u32,
    },
    /// A torus about the z axis.
    Torus {
        /// Distance from the axis to the tube's centre.
        major_radius: f64,
        /// The tube's radius.
        minor_radius: f64,
        /// Steps round the axis.
        #[serde(default = "d32")]
        segments: u32,
        /// Steps round the tube.
        #[serde(default = "d16")]
        rings: u32,
    },
    /// A closed polyhedron from vertex and face lists; each face lists vertex indices
    /// counter-clockwise seen from outside.
    Polyhedron {
        /// Vertex loci.
        vertices: Vec<DVec3>,
        /// Faces as vertex indices.
        faces: FaceList,
    },
    /// MKBFV: one face and one vertex, the seed of an Euler construction.
    Seminal {
        /// The vertex locus.
        #[serde(default)]
        position: DVec3,
    },
}

fn d32() -> u32 {
    32
}

fn d16() -> u32 {
    16
}

fn up_z() -> DVec3 {
    DVec3::Z
}

fn one() -> f64 {
    1.0
}

/// One closed shell of a boolean's result, as the journal keeps it: polygons in the
/// frame of the body the boolean kept (B1), the faces counter-clockwise seen from
/// outside. Replaying it builds the body from these polygons with
/// [`crate::model::Body::from_polygons`]; the kernel that computed them is not run
/// again.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct BooleanPiece {
    /// Vertex loci ([packed](packed)).
    #[serde(with = "packed::loci")]
    pub positions: Vec<DVec3>,
    /// Faces as vertex indices ([packed](packed)).
    #[serde(with = "packed::faces")]
    pub faces: FaceList,
}

/// One body perception carved, as the journal keeps it (see
/// [`Edit::Perception`](super::Edit::Perception)): polygons and what made each face.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PerceivedPiece {
    /// The provisional body carved again; `None` for a new body.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body: Option<u64>,
    /// A new body's name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Views that carved it, over every request.
    pub views: u32,
    /// How far, in pixels, its outline may lie outside the object's in the views that
    /// carved it.
    #[serde(default)]
    pub outline_px: f64,
    /// Vertex loci: world coordinates for a new body (placed under the world with the
    /// identity pose), the body's own frame for one carved again ([packed](packed)).
    #[serde(with = "packed::loci")]
    pub positions: Vec<DVec3>,
    /// Faces as vertex indices, counter-clockwise seen from outside ([packed](packed)).
    #[serde(with = "packed::faces")]
    pub faces: FaceList,
    /// What made each face.
    pub makers: Vec<Maker>,
}

/// One body of a mesh file's import: polygons and its place in the parts tree.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ImportedBody {
    /// A unique name, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The supart's id, when it is a body already in the world (`None` and no `within`:
    /// the world).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parent: Option<u64>,
    /// The supart, when it is an earlier body of the same import (its index in the
    /// list); wins over `parent`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub within: Option<usize>,
    /// Pose relative to the supart (`None`: identity).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose: Option<Pose>,
    /// Material colour (`None`: one chosen from the body's id).
    #[serde(default, with = "hex::maybe", skip_serializing_if = "Option::is_none")]
    pub color: Option<Color>,
    /// Vertex loci in the body's frame, meters ([packed](packed)).
    #[serde(with = "packed::loci")]
    pub vertices: Vec<DVec3>,
    /// Faces as vertex indices, counter-clockwise seen from outside ([packed](packed)).
    #[serde(with = "packed::faces")]
    pub faces: FaceList,
}

/// Make a body.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CreateBody {
    /// A unique name, if any.
    pub name: Option<String>,
    /// The supart's id (`None`: the world).
    pub parent: Option<u64>,
    /// Pose relative to the supart (`None`: identity).
    pub pose: Option<Pose>,
    /// Material colour (`None`: one chosen from the body's id).
    #[serde(default, with = "hex::maybe", skip_serializing_if = "Option::is_none")]
    pub color: Option<Color>,
    /// The solid.
    pub shape: Shape,
}

/// Change any of a body's name, supart, pose and colour.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Default)]
pub struct PatchBody {
    /// New name, `Some(None)` to remove it; `None` (absent) for no change.
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
    pub pose: Option<Pose>,
    /// New colour, `Some(None)` for the default; `None` (absent) for no change.
    #[serde(
        default,
        with = "hex::maybe_maybe",
        skip_serializing_if = "Option::is_none"
    )]
    pub color: Option<Option<Color>>,
}

fn some_or_null<'de, D, T>(d: D) -> Result<Option<Option<T>>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    Option::<T>::deserialize(d).map(Some)
}

/// Colours as `"#rrggbb"` strings.
mod hex {
    use serde::{Deserialize, Deserializer, Serializer};

    use crate::model::Color;

    fn read<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Color>, D::Error> {
        match Option::<String>::deserialize(d)? {
            None => Ok(None),
            Some(text) => Color::from_hex(&text).map(Some).ok_or_else(|| {
                serde::de::Error::custom(format!("colour {text:?} is not \"#rrggbb\""))
            }),
        }
    }

    /// `Option<Color>`: a string or `null`.
    pub mod maybe {
        use super::*;

        pub fn serialize<S: Serializer>(c: &Option<Color>, s: S) -> Result<S::Ok, S::Error> {
            match c {
                Some(c) => s.serialize_str(&c.to_hex()),
                None => s.serialize_none(),
            }
        }

        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Color>, D::Error> {
            read(d)
        }
    }

    /// `Option<Option<Color>>`: absent (no change), `null` or a string.
    pub mod maybe_maybe {
        use super::*;

        pub fn serialize<S: Serializer>(
            c: &Option<Option<Color>>,
            s: S,
        ) -> Result<S::Ok, S::Error> {
            maybe::serialize(&c.flatten(), s)
        }

        pub fn deserialize<'de, D: Deserializer<'de>>(
            d: D,
        ) -> Result<Option<Option<Color>>, D::Error> {
            read(d).map(Some)
        }
    }
}

/// One Euler operator, by its Baumgart name, on entities named by serial.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "op", rename_all = "snake_case")]
pub enum EulerOp {
    /// MKEV: a spur from `vertex` into `face`, its new vertex at `position` (`None`: at
    /// `vertex`).
    Mkev {
        /// Face.
        face: u64,
        /// Vertex.
        vertex: u64,
        /// Locus of the new vertex.
        position: Option<DVec3>,
    },
    /// MKFE: split `face` by a new edge from `v1` (its PVT) to `v2`.
    Mkfe {
        /// First vertex.
        v1: u64,
        /// Face.
        face: u64,
        /// Second vertex.
        v2: u64,
    },
    /// ESPLIT: split `edge` at `position` (`None`: its midpoint).
    Esplit {
        /// Edge.
        edge: u64,
        /// Locus of the new vertex.
        position: Option<DVec3>,
    },
    /// KLFE: kill `edge` and its NFACE.
    Klfe {
        /// Edge.
        edge: u64,
    },
    /// KLEV: kill `vertex` (one or two edges) and its PED.
    Klev {
        /// Vertex.
        vertex: u64,
    },
    /// KLVE: kill `edge` and its NVT.
    Klve {
        /// Edge.
        edge: u64,
    },
    /// INVERT: turn `edge` round.
    Invert {
        /// Edge.
        edge: u64,
    },
    /// GLUE: identify `face2` (of this or another body) with `face1`, pairing `vertex1`
    /// with `vertex2` (`None`: the first vertex of `face1` with the nearest of `face2`).
    Glue {
        /// Face of this body.
        face1: u64,
        /// Face of this or another body.
        face2: u64,
        /// Vertex of `face1`.
        vertex1: Option<u64>,
        /// Vertex of `face2`.
        vertex2: Option<u64>,
    },
    /// GLUEE: a wasp edge from `vertex1` on `face1` to `vertex2` on `face2`, killing
    /// `face2`.
    Gluee {
        /// Face of this body.
        face1: u64,
        /// Vertex of `face1`.
        vertex1: u64,
        /// Face of this or another body.
        face2: u64,
        /// Vertex of `face2`.
        vertex2: u64,
    },
    /// GLUEFF: a tube of quadrilaterals between `face1` and `face2`.
    Glueff {
        /// Face of this body.
        face1: u64,
        /// Face of this or another body.
        face2: u64,
    },
    /// UNGLUE: cut along the closed loop of `edges`.
    Unglue {
        /// Edges forming one closed loop.
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

/// A Euclidean motion, its numbers in the frame a [`Move`] names.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "op", rename_all = "snake_case")]
pub enum Motion {
    /// TRANSLATE by `vector`.
    Translate {
        /// The displacement.
        vector: DVec3,
    },
    /// ROTATE by `angle_deg` about `axis` through `center` (right-hand rule).
    Rotate {
        /// Axis direction.
        axis: DVec3,
        /// Angle in degrees.
        angle_deg: f64,
        /// A point on the axis (read as the origin when missing).
        #[serde(default)]
        center: DVec3,
    },
    /// DILATE by `factor` about `center`.
    Dilate {
        /// Scale factor.
        factor: f64,
        /// Fixed point (read as the origin when missing).
        #[serde(default)]
        center: DVec3,
    },
    /// REFLECT in the plane through `point` with `normal`.
    Reflect {
        /// Plane normal.
        normal: DVec3,
        /// A point of the plane (read as the origin when missing).
        #[serde(default)]
        point: DVec3,
    },
}

/// A motion of a body, or of one of its faces, edges or vertices.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Move {
    /// The motion.
    #[serde(flatten)]
    pub motion: Motion,
    /// The frame its numbers are in (read as the world's when missing).
    #[serde(default, with = "frame")]
    pub frame: Frame,
    /// A face, edge or vertex of the body to move instead of the whole body.
    pub target: Option<u64>,
}

/// [`Frame`]s as `"world"` or `"body"`.
mod frame {
    use serde::{Deserialize, Deserializer, Serializer};

    use crate::model::Frame;

    pub fn serialize<S: Serializer>(f: &Frame, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(match f {
            Frame::World => "world",
            Frame::Body => "body",
        })
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Frame, D::Error> {
        match String::deserialize(d)?.as_str() {
            "world" => Ok(Frame::World),
            "body" => Ok(Frame::Body),
            other => Err(serde::de::Error::unknown_variant(other, &["world", "body"])),
        }
    }
}

/// The sweep primitives.
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

/// A sweep of one face of a body.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Sweep {
    /// The face swept.
    pub face: u64,
    /// Which sweep.
    pub kind: SweepKind,
    /// How far along the face's outward normal, when neither `offset` nor `peak` is
    /// given (`None`: 1).
    pub distance: Option<f64>,
    /// The offset of the new ring (prisms), body frame.
    pub offset: Option<DVec3>,
    /// The peak (pyramid), body frame.
    pub peak: Option<DVec3>,
    /// Scale of the new ring about the face centre (prisms; `None`: 1).
    pub scale: Option<f64>,
}

/// Where a camera stands and looks: a pose, or an eye looking at a target.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct LookAt {
    /// Lens centre.
    pub eye: DVec3,
    /// Point looked at.
    pub target: DVec3,
    /// Up direction (read as +z when missing).
    #[serde(default = "up_z")]
    pub up: DVec3,
}

/// Baumgart's camera raster, as [`BaumgartRaster`].
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Raster {
    /// FOCAL.
    pub focal: f64,
    /// LDX.
    pub ldx: u32,
    /// LDY.
    pub ldy: u32,
    /// PDX.
    pub pdx: f64,
    /// PDY.
    pub pdy: f64,
}

/// A camera as a write describes it: exactly one of `pose` and `look_at`, and exactly
/// one of `intrinsics` and `baumgart`.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct CameraSpec {
    /// Pose in the world (the camera looks along its −k axis).
    pub pose: Option<Pose>,
    /// Or: where it stands and what it looks at.
    pub look_at: Option<LookAt>,
    /// Intrinsics in pixels.
    pub intrinsics: Option<Intrinsics>,
    /// Or: Baumgart's raster.
    pub baumgart: Option<Raster>,
}

/// Why a camera description is not a camera.
#[derive(Debug, thiserror::Error)]
pub enum CameraSpecError {
    /// Neither or both of pose and look_at.
    #[error("give exactly one of \"pose\" and \"look_at\"")]
    Placement,
    /// Neither or both of intrinsics and baumgart.
    #[error("give exactly one of \"intrinsics\" and \"baumgart\"")]
    Lens,
    /// The camera itself is invalid.
    #[error(transparent)]
    Camera(#[from] CameraError),
}

impl CameraSpec {
    /// The camera described, checked.
    pub fn to_camera(&self) -> Result<Camera, CameraSpecError> {
        let intrinsics = match (self.intrinsics, self.baumgart) {
            (Some(i), None) => Intrinsics::new(i.width, i.height, i.fx, i.fy, i.cx, i.cy)?,
            (None, Some(b)) => Intrinsics::from_baumgart(&BaumgartRaster {
                focal: b.focal,
                ldx: b.ldx,
                ldy: b.ldy,
                pdx: b.pdx,
                pdy: b.pdy,
            })?,
            _ => return Err(CameraSpecError::Lens),
        };
        match (self.pose, self.look_at) {
            (Some(p), None) => Ok(Camera::new(p, intrinsics)?),
            (None, Some(l)) => Ok(Camera::look_at(l.eye, l.target, l.up, intrinsics)?),
            _ => Err(CameraSpecError::Placement),
        }
    }
}

/// A light as a write describes it.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum LightSpec {
    /// Light at infinity.
    Sun {
        /// Direction the light travels.
        direction: DVec3,
        /// Intensity (read as 1 when missing).
        #[serde(default = "one")]
        intensity: f64,
    },
    /// A point lamp.
    Point {
        /// Where it is.
        position: DVec3,
        /// Intensity (read as 1 when missing).
        #[serde(default = "one")]
        intensity: f64,
    },
}

impl LightSpec {
    /// The light described, checked.
    pub fn to_light(self) -> Result<Light, LightError> {
        match self {
            LightSpec::Sun {
                direction,
                intensity,
            } => Light::sun(direction, intensity),
            LightSpec::Point {
                position,
                intensity,
            } => Light::point(position, intensity),
        }
    }
}
