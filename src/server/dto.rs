//! The JSON shapes of the HTTP API's answers, and their conversions from the kernel's
//! types. What a write request carries is read by [`super::request`].

use serde::{Deserialize, Serialize};

use crate::edit::Outcome;
use crate::model::{Body, Camera, Light, geometry::Bounds};

use super::request::{HexColor, IntrinsicsDto, LightDto, PoseDto};

/// `GET /v1/world`: the world's revision and size.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct WorldSummary {
    /// The revision.
    pub revision: u64,
    /// Bodies, not counting the world itself.
    pub bodies: usize,
    /// Faces in all bodies.
    pub faces: usize,
    /// Edges in all bodies.
    pub edges: usize,
    /// Vertices in all bodies.
    pub vertices: usize,
    /// Cameras.
    pub cameras: usize,
    /// Lights.
    pub lights: usize,
}

/// `GET /v1/bodies`: the bodies asked for, and the revision they were read at.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct BodyList {
    /// The bodies, in id order.
    pub bodies: Vec<BodyDto>,
    /// The revision.
    pub revision: u64,
}

/// `GET /v1/bodies/{id}`: a body and the revision it was read at.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct BodyAnswer {
    /// The body.
    #[serde(flatten)]
    pub body: BodyDto,
    /// The revision.
    pub revision: u64,
}

/// `GET /v1/changes`: the changes after a revision, or word to read the world again.
#[derive(Clone, Debug, Serialize)]
pub struct ChangesPage {
    /// The revision asked after.
    pub since: u64,
    /// The world's revision.
    pub revision: u64,
    /// Whether the history no longer reaches back to `since`: read the world whole.
    pub resync: bool,
    /// With `resync`: the oldest revision whose change is kept (`null` if none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub oldest: Option<Option<u64>>,
    /// Whether more changes follow the last one given.
    pub more: bool,
    /// The changes, oldest first.
    pub changes: Vec<std::sync::Arc<super::changes::Change>>,
}

/// `POST /v1/bodies/{id}/boolean`: the bodies the boolean left and those it killed.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct BooleanAnswer {
    /// The body the boolean was asked of (B1); it is the first piece, or among the
    /// killed when nothing is left.
    pub id: u64,
    /// The bodies holding the result, B1 first.
    pub pieces: Vec<PieceDto>,
    /// The bodies removed, each with its parts.
    pub killed: Vec<u64>,
    /// The revision.
    pub revision: u64,
}

/// One body a boolean left.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PieceDto {
    /// Its id.
    pub id: u64,
    /// Face count.
    pub faces: usize,
    /// Edge count.
    pub edges: usize,
    /// Vertex count.
    pub vertices: usize,
    /// Enclosed volume, m³.
    pub volume: f64,
    /// `[face, from body, from face]` for each face: the input face it is a piece of.
    pub sources: Vec<[u64; 3]>,
}

impl BooleanAnswer {
    /// The answer to a boolean of `body` that ended with `outcome` at `revision`.
    pub fn new(body: u64, outcome: Outcome, revision: u64) -> Self {
        let pieces = outcome.pieces.unwrap_or_default();
        BooleanAnswer {
            id: body,
            pieces: pieces
                .into_iter()
                .map(|p| PieceDto {
                    id: p.id,
                    faces: p.faces,
                    edges: p.edges,
                    vertices: p.vertices,
                    volume: p.volume,
                    sources: p.sources,
                })
                .collect(),
            killed: outcome.killed,
            revision,
        }
    }
}

/// `GET /healthz`.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Health {
    /// Always `"ok"`.
    pub status: &'static str,
    /// The newest revision published.
    pub revision: u64,
}

/// `GET /readyz`.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Ready {
    /// Always `"ready"`.
    pub status: &'static str,
    /// The world's revision.
    pub revision: u64,
    /// Requests waiting for the world's owner.
    pub queue: usize,
}

/// A light as answered: its name beside the light as `PUT /v1/lights/{name}` takes it.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct LightAnswer {
    /// Its name.
    pub name: String,
    /// The light.
    #[serde(flatten)]
    pub light: LightDto,
}

impl LightAnswer {
    /// The answer for light `l` named `name`.
    pub fn new(name: &str, l: &Light) -> Self {
        LightAnswer {
            name: name.to_owned(),
            light: LightDto::from(l),
        }
    }
}

/// A camera as answered.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CameraDto {
    /// Its name.
    pub name: String,
    /// Pose in the world.
    pub pose: PoseDto,
    /// Intrinsics.
    pub intrinsics: IntrinsicsDto,
    /// The direction it looks along (−k).
    pub view_direction: [f64; 3],
}

impl CameraDto {
    /// The answer for camera `c` named `name`.
    pub fn new(name: &str, c: &Camera) -> Self {
        let i = c.intrinsics;
        CameraDto {
            name: name.to_owned(),
            pose: c.pose.into(),
            intrinsics: IntrinsicsDto {
                width: i.width,
                height: i.height,
                fx: i.fx,
                fy: i.fy,
                cx: i.cx,
                cy: i.cy,
            },
            view_direction: c.view_direction().to_array(),
        }
    }
}

/// Counts and Euler numbers of a body.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct EulerDto {
    /// Faces.
    #[serde(rename = "F")]
    pub f: usize,
    /// Edges.
    #[serde(rename = "E")]
    pub e: usize,
    /// Vertices.
    #[serde(rename = "V")]
    pub v: usize,
    /// Handles.
    #[serde(rename = "H")]
    pub h: u32,
}

/// Axis-aligned bounds in the body frame.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct BoundsDto {
    /// Smallest corner.
    pub min: [f64; 3],
    /// Largest corner.
    pub max: [f64; 3],
}

impl From<Bounds> for BoundsDto {
    fn from(b: Bounds) -> Self {
        BoundsDto {
            min: b.min.to_array(),
            max: b.max.to_array(),
        }
    }
}

/// `GET /v1/bodies/{id}` and the items of `GET /v1/bodies`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct BodyDto {
    /// Its id.
    pub id: u64,
    /// Its name.
    pub name: Option<String>,
    /// Its supart's id.
    pub parent: u64,
    /// Its sub-parts' ids.
    pub parts: Vec<u64>,
    /// Pose relative to the parent.
    pub pose: PoseDto,
    /// Pose in the world.
    pub world_pose: PoseDto,
    /// The material colour appearance draws it with (its own, or the default for its id).
    pub color: HexColor,
    /// Counts.
    pub euler: EulerDto,
    /// Enclosed volume (m³; meaningful for closed bodies).
    pub volume: f64,
    /// Surface area (m²).
    pub area: f64,
    /// Bounds in the body frame; `null` for a body without vertices.
    pub bounds: Option<BoundsDto>,
    /// Whether perception made the body and may carve it further.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub provisional: bool,
    /// For a provisional body: how many views carved it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub views: Option<u32>,
}

/// Counts of a body, for summaries.
pub fn euler_of(b: &Body) -> EulerDto {
    EulerDto {
        f: b.face_count(),
        e: b.edge_count(),
        v: b.vertex_count(),
        h: b.handles(),
    }
}

/// A vertex of `GET /v1/bodies/{id}/topology`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct VertexDto {
    /// Id.
    pub id: u64,
    /// Locus, body frame.
    pub position: [f64; 3],
    /// PED: one edge at the vertex (`null` in a seminal body).
    pub ped: Option<u64>,
}

/// An edge of `GET /v1/bodies/{id}/topology`: Baumgart's eight links.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct EdgeDto {
    /// Id.
    pub id: u64,
    /// Negative vertex.
    pub nvt: u64,
    /// Positive vertex.
    pub pvt: u64,
    /// Negative face.
    pub nface: u64,
    /// Positive face.
    pub pface: u64,
    /// Wing in NFACE clockwise.
    pub ncw: u64,
    /// Wing in PFACE clockwise.
    pub pcw: u64,
    /// Wing in NFACE counter-clockwise.
    pub nccw: u64,
    /// Wing in PFACE counter-clockwise.
    pub pccw: u64,
}

/// A face of `GET /v1/bodies/{id}/topology`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct FaceDto {
    /// Id.
    pub id: u64,
    /// PED: one edge of the face (`null` in a seminal body).
    pub ped: Option<u64>,
    /// Plane `[a, b, c, d]` with `a·x + b·y + c·z = d`, `[a, b, c]` the outward unit
    /// normal; `null` for a face of zero area.
    pub plane: Option<[f64; 4]>,
    /// The perimeter's vertex ids, counter-clockwise seen from outside.
    pub vertices: Vec<u64>,
    /// For a face of a provisional body: the view (and silhouette edge) that made it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub made_by: Option<crate::model::Maker>,
}

/// `GET /v1/bodies/{id}/topology`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct TopologyDto {
    /// The body.
    pub id: u64,
    /// World revision of the snapshot read.
    pub revision: u64,
    /// Vertices.
    pub vertices: Vec<VertexDto>,
    /// Edges.
    pub edges: Vec<EdgeDto>,
    /// Faces.
    pub faces: Vec<FaceDto>,
}
