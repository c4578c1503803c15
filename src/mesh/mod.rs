//! Mesh files in and out: OBJ, STL, PLY, OFF, glTF/GLB and 3MF.
//!
//! **Reading** is two steps. A format's reader ([`obj`], [`stl`], [`ply`], [`off`],
//! [`gltf`], [`threemf`]) turns the file into a [`RawScene`]: one [`RawObject`] per
//! object of the file (an OBJ group, a glTF node with a mesh, a 3MF object), each a list
//! of vertex loci and polygon faces numbered as the file numbers them, with a name, a
//! pose and a parent among the scene's objects. Then [`polygons`] makes bodies of them:
//! vertices are welded, the surface is checked (closed, manifold, consistently oriented,
//! no degenerate face, no two faces crossing), adjacent triangles in one plane are merged
//! into polygon faces, and each connected piece becomes one [`MeshBody`]. Whatever is
//! wrong is an [`ImportError`] naming the object, faces and vertices in the file's own
//! numbering.
//!
//! **Writing** ([`write`]) takes bodies of a [`World`](crate::model::World): OBJ, PLY and
//! OFF keep polygon faces and f64 coordinates exactly; STL, glTF and 3MF are triangulated
//! (see [`crate::model::triangulate`]), and glTF's coordinates are f32.
//!
//! Everything here is pure and synchronous; the server runs it off the world's owner.

pub mod error;
pub mod gltf;
pub mod obj;
pub mod off;
pub mod ply;
pub mod polygons;
pub mod stl;
pub mod threemf;
pub mod write;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::model::{Color, Pose};

pub use error::{ImportError, Where};

/// Hash maps keyed by coordinates' bits and vertex indices: foldhash's fixed-seed
/// hasher, fast on small keys and the same in every run.
pub(crate) type Map<K, V> = std::collections::HashMap<K, V, foldhash::fast::FixedState>;
pub use polygons::{Imported, MeshBody};

/// A mesh file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// Wavefront OBJ (text; polygon faces; groups and objects).
    Obj,
    /// STL, binary or ASCII (triangles only, no shared vertices).
    Stl,
    /// Stanford PLY, ASCII or binary (polygon faces).
    Ply,
    /// Object File Format (text; polygon faces).
    Off,
    /// glTF 2.0 JSON, with its buffers as data URIs.
    Gltf,
    /// glTF 2.0 binary (GLB).
    Glb,
    /// 3D Manufacturing Format (a zip package of XML).
    #[serde(rename = "3mf")]
    ThreeMf,
}

impl Format {
    /// Every format, in the order the documentation lists them.
    pub const ALL: [Format; 7] = [
        Format::Obj,
        Format::Stl,
        Format::Ply,
        Format::Off,
        Format::Gltf,
        Format::Glb,
        Format::ThreeMf,
    ];

    /// The format named `name` (`obj`, `stl`, `ply`, `off`, `gltf`, `glb`, `3mf`; any
    /// case), `None` for any other name.
    pub fn parse(name: &str) -> Option<Format> {
        Format::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(name))
    }

    /// The format's name as the API spells it.
    pub fn name(self) -> &'static str {
        match self {
            Format::Obj => "obj",
            Format::Stl => "stl",
            Format::Ply => "ply",
            Format::Off => "off",
            Format::Gltf => "gltf",
            Format::Glb => "glb",
            Format::ThreeMf => "3mf",
        }
    }

    /// The media type of a file of this format.
    pub fn media_type(self) -> &'static str {
        match self {
            Format::Obj => "model/obj",
            Format::Stl => "model/stl",
            Format::Ply => "application/x-ply",
            Format::Off => "application/x-off",
            Format::Gltf => "model/gltf+json",
            Format::Glb => "model/gltf-binary",
            Format::ThreeMf => "model/3mf",
        }
    }
}

/// The length unit of a file's coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Unit {
    /// Meters.
    M,
    /// Millimeters.
    Mm,
    /// Centimeters.
    Cm,
    /// Inches.
    In,
}

impl Unit {
    /// Meters per unit.
    pub fn meters(self) -> f64 {
        match self {
            Unit::M => 1.0,
            Unit::Mm => 1e-3,
            Unit::Cm => 1e-2,
            Unit::In => 0.0254,
        }
    }
}

/// How a file is read into bodies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImportOptions {
    /// The unit of the file's coordinates; `None` for the format's own: meters, but for
    /// a 3MF file, whose model declares its unit (millimeters when it does not).
    pub unit: Option<Unit>,
    /// Whether adjacent faces in one plane become one polygon face (see [`polygons`]).
    pub merge_coplanar: bool,
    /// Vertices closer than this (meters, after the unit) are one vertex; 0 welds only
    /// vertices with equal coordinates.
    pub weld: f64,
    /// How far (as a fraction of the piece's bounding-box diagonal) a face's vertices
    /// may lie from a merged face's plane; faces also merge only when their normals are
    /// within [`polygons::MERGE_ANGLE`] of it.
    pub coplanar_tolerance: f64,
    /// Whether faces are tested for crossing one another (a self-intersecting surface is
    /// refused); off only for files known to be clean, to save the time.
    pub check_crossings: bool,
    /// The most faces one body may have after merging
    /// ([`crate::model::range::MAX_BODY_FACES`] by default).
    pub max_faces: usize,
    /// The most triangles and polygons the whole file may hold, read before anything is
    /// built.
    pub max_file_faces: usize,
}

impl Default for ImportOptions {
    fn default() -> Self {
        ImportOptions {
            unit: None,
            merge_coplanar: true,
            weld: 0.0,
            coplanar_tolerance: 1e-6,
            check_crossings: true,
            max_faces: crate::model::range::MAX_BODY_FACES,
            max_file_faces: 4 * crate::model::range::MAX_BODY_FACES,
        }
    }
}

/// Faces as lists of vertex indices, stored flat.
///
/// Invariant: `ends` is non-decreasing and ends at `corners.len()`; face `i` is
/// `corners[ends[i - 1]..ends[i]]` (from 0 for face 0).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Polygons {
    /// Every face's vertex indices, one face after another.
    pub corners: Vec<u32>,
    /// The end of each face in `corners`.
    pub ends: Vec<u32>,
}

impl Polygons {
    /// An empty list with room for `faces` faces of `corners` indices in all.
    pub fn with_capacity(faces: usize, corners: usize) -> Self {
        Polygons {
            corners: Vec::with_capacity(corners),
            ends: Vec::with_capacity(faces),
        }
    }

    /// The number of faces.
    pub fn len(&self) -> usize {
        self.ends.len()
    }

    /// Whether there are no faces.
    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }

    /// Appends a face. Postcondition: the last face is `face`.
    pub fn push(&mut self, face: &[u32]) {
        self.corners.extend_from_slice(face);
        self.ends.push(self.corners.len() as u32);
    }

    /// Face `i`. Precondition: `i < len()`.
    pub fn face(&self, i: usize) -> &[u32] {
        let start = if i == 0 { 0 } else { self.ends[i - 1] as usize };
        &self.corners[start..self.ends[i] as usize]
    }

    /// The faces in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = &[u32]> + '_ {
        (0..self.len()).map(|i| self.face(i))
    }
}

/// One object of a file, as the file gives it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RawObject {
    /// Its name in the file (an OBJ `o` or `g` name, a glTF node's or mesh's name, a 3MF
    /// object's name), if any.
    pub name: Option<String>,
    /// The object it is a part of (an index into [`RawScene::objects`], always lower than
    /// this object's own), `None` for a top-level object.
    pub parent: Option<usize>,
    /// Its frame in its parent's frame (or in the file's, at the top level), rigid; any
    /// scale or mirror of the file's transforms is already applied to `positions`.
    pub pose: Pose,
    /// Its colour, if the file gives one.
    pub color: Option<Color>,
    /// Vertex loci in the object's frame, in the file's unit, numbered as the file
    /// numbers them (see `first_vertex`).
    pub positions: Vec<DVec3>,
    /// Faces as indices into `positions`, in the file's order, counter-clockwise seen
    /// from outside as every one of these formats asks.
    pub faces: Polygons,
    /// The file's own number of `positions[0]` (OBJ counts from 1 over the whole file;
    /// PLY and OFF from 0), so that errors name vertices as the file does; `None` when
    /// the file does not number vertices (STL) or the reader renumbered them.
    pub first_vertex: Option<u64>,
    /// The file's own number of `faces` 0 (an STL's triangles and a PLY's or OFF's faces
    /// count from 0 over the file).
    pub first_face: u64,
}

/// Everything a file holds: its objects, parents before their parts.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RawScene {
    /// The objects.
    pub objects: Vec<RawObject>,
    /// The unit the file declares (3MF), if any.
    pub unit: Option<Unit>,
}

impl RawScene {
    /// The total number of faces over every object.
    pub fn face_count(&self) -> usize {
        self.objects.iter().map(|o| o.faces.len()).sum()
    }
}

/// Reads `bytes` as a file of `format` into objects, without building bodies.
///
/// Refused with [`ImportError::Parse`] when the file is not of that format or is
/// broken, [`ImportError::TooLarge`] when it holds more than `options.max_file_faces`
/// faces or a 3MF part would inflate past the limit, [`ImportError::Unsupported`] for
/// what winged does not read (glTF buffers in external files, say).
pub fn read(
    format: Format,
    bytes: &[u8],
    options: &ImportOptions,
) -> Result<RawScene, ImportError> {
    let scene = match format {
        Format::Obj => obj::read(bytes, options)?,
        Format::Stl => stl::read(bytes, options)?,
        Format::Ply => ply::read(bytes, options)?,
        Format::Off => off::read(bytes, options)?,
        Format::Gltf | Format::Glb => gltf::read(bytes, options)?,
        Format::ThreeMf => threemf::read(bytes, options)?,
    };
    let faces = scene.face_count();
    if faces > options.max_file_faces {
        return Err(ImportError::TooLarge {
            what: "faces in the file",
            count: faces as u64,
            limit: options.max_file_faces as u64,
        });
    }
    Ok(scene)
}

/// Reads `bytes` as a file of `format` and makes bodies of its objects
/// ([`read`], then [`polygons::bodies`]).
pub fn import(
    format: Format,
    bytes: &[u8],
    options: &ImportOptions,
) -> Result<Imported, ImportError> {
    let scene = read(format, bytes, options)?;
    polygons::bodies(scene, options)
}

#[cfg(test)]
mod tests;
