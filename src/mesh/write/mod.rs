//! Writing bodies as mesh files.
//!
//! A body is first taken as a [`Solid`]: its vertex loci in the frame asked for and its
//! faces as polygons (vertex indices counter-clockwise seen from outside), in the order
//! of the body's arenas. OBJ, PLY and OFF write those polygons and f64 coordinates
//! exactly; STL, glTF and 3MF write the triangles of [`Solid::triangles`].

pub mod obj;
pub mod off;
pub mod ply;
pub mod stl;

use glam::DVec3;

use super::{Format, Polygons};
use crate::model::triangulate::FaceTriangulator;
use crate::model::{Body, BodyId, Color, Pose, World, default_color};

/// The frame an exported body's coordinates are in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Frame {
    /// The world's frame: the body's world pose applied.
    World,
    /// The body's own frame (its loci as stored).
    Body,
}

/// Why a body could not be written.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ExportError {
    /// No body has that id (or it is the world's root, which has no geometry).
    #[error("no body has id {0}")]
    NotFound(u64),
    /// The format cannot hold what is asked (a whole world in STL, say).
    #[error("{0}")]
    Unsupported(String),
    /// The encoder failed.
    #[error("the {format} file could not be written: {detail}")]
    Encode {
        /// The format's name.
        format: &'static str,
        /// The encoder's own words.
        detail: String,
    },
}

/// One body to write: its name, colour, vertex loci and polygon faces.
#[derive(Clone, Debug, PartialEq)]
pub struct Solid {
    /// The body's id.
    pub id: u64,
    /// Its name, if any.
    pub name: Option<String>,
    /// Its colour (its own, or [`default_color`] of its id).
    pub color: Color,
    /// Vertex loci.
    pub positions: Vec<DVec3>,
    /// Faces as indices into `positions`, counter-clockwise seen from outside.
    pub faces: Polygons,
    /// The body's signed volume (m³), as the kernel computes it.
    pub volume: f64,
}

impl Solid {
    /// Body `b` of `world` with its loci in `frame`; `None` when there is no such body
    /// (or it is the root).
    pub fn of(world: &World, b: BodyId, frame: Frame) -> Option<Solid> {
        if b == world.root() {
            return None;
        }
        let node = world.node(b)?;
        let pose = match frame {
            Frame::World => world.world_pose(b)?,
            Frame::Body => Pose::IDENTITY,
        };
        Some(Solid::from_body(
            b.get(),
            node.name.clone(),
            node.color.unwrap_or_else(|| default_color(b)),
            &node.body,
            &pose,
        ))
    }

    /// `body`'s faces with each locus moved by `pose` (the identity keeps the loci bit
    /// for bit).
    pub fn from_body(
        id: u64,
        name: Option<String>,
        color: Color,
        body: &Body,
        pose: &Pose,
    ) -> Solid {
        let slots = body.vertices().map(|v| v.index() + 1).max().unwrap_or(0);
        let mut local = vec![u32::MAX; slots];
        let identity = *pose == Pose::IDENTITY;
        let mut positions = Vec::with_capacity(body.vertex_count());
        for v in body.vertices() {
            local[v.index()] = positions.len() as u32;
            let p = body.position(v);
            positions.push(if identity { p } else { pose.transform_point(p) });
        }
        let mut faces = Polygons::with_capacity(body.face_count(), 2 * body.edge_count());
        let mut ring = Vec::new();
        for f in body.faces() {
            ring.clear();
            ring.extend(body.face_vertices(f).map(|v| local[v.index()]));
            faces.push(&ring);
        }
        Solid {
            id,
            name,
            color,
            positions,
            faces,
            volume: body.volume(),
        }
    }

    /// The faces cut into triangles of their own corners, each wound like its face.
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        let mut ear = FaceTriangulator::new();
        let mut out = Vec::with_capacity(2 * self.faces.len());
        let mut tris = Vec::new();
        for face in self.faces.iter() {
            if face.len() == 3 {
                out.push([face[0], face[1], face[2]]);
                continue;
            }
            let normal = newell(&self.positions, face).normalize_or_zero();
            if normal == DVec3::ZERO {
                continue;
            }
            ear.triangulate(&self.positions, face, normal, &mut tris);
            out.extend_from_slice(&tris);
        }
        out
    }
}

/// The Newell normal of a polygon (twice its vector area).
fn newell(points: &[DVec3], face: &[u32]) -> DVec3 {
    let mut n = DVec3::ZERO;
    for (k, &a) in face.iter().enumerate() {
        let p = points[a as usize];
        let q = points[face[(k + 1) % face.len()] as usize];
        n += DVec3::new(
            (p.y - q.y) * (p.z + q.z),
            (p.z - q.z) * (p.x + q.x),
            (p.x - q.x) * (p.y + q.y),
        );
    }
    n
}

/// Body `b` of `world` as a file of `format`, its loci in `frame`.
pub fn body(
    world: &World,
    b: BodyId,
    format: Format,
    frame: Frame,
) -> Result<Vec<u8>, ExportError> {
    let solid = Solid::of(world, b, frame).ok_or(ExportError::NotFound(b.get()))?;
    match format {
        Format::Obj => Ok(obj::write(std::slice::from_ref(&solid))),
        Format::Off => Ok(off::write(&solid)),
        Format::Ply => ply::write(&solid),
        Format::Stl => stl::write(std::slice::from_ref(&solid)),
        Format::Glb => super::gltf::write_solid(&solid),
        Format::Gltf => Err(ExportError::Unsupported(
            "glTF is written as GLB (format=glb), its binary form".into(),
        )),
        Format::ThreeMf => super::threemf::write(std::slice::from_ref(&solid)),
    }
}

/// The whole world as one GLB file: one node per body, the parts tree as the node
/// hierarchy, poses as node transforms, colours as materials, names kept, cameras as
/// glTF cameras (see [`super::gltf::write_world`]).
pub fn world_glb(world: &World) -> Result<Vec<u8>, ExportError> {
    super::gltf::write_world(world)
}
