//! Why a mesh file was not imported, and where in the file.

use std::fmt;

use serde::Serialize;

/// What is wrong with a surface that was read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Defect {
    /// A coordinate is NaN or infinite.
    NotFinite,
    /// A face names a vertex the file does not have.
    BadIndex,
    /// A face with fewer than three distinct vertices, or of zero area.
    Degenerate,
    /// An edge with a face on one side only: the surface has a hole.
    Open,
    /// An edge shared by more than two faces.
    NonManifoldEdge,
    /// A vertex whose faces form more than one fan.
    NonManifoldVertex,
    /// Two faces that run along an edge in the same direction.
    InconsistentOrientation,
    /// The surface faces inward (negative volume).
    Inward,
    /// Two faces that cross or overlap away from the edges and vertices they share.
    SelfIntersection,
    /// A planar face that would enclose a hole (refused rather than faked with a bridge).
    HoleInFace,
    /// The vertices span less than the smallest length the world holds, or lie beyond
    /// its range.
    OutOfRange,
    /// A face no other face is joined to by an edge, or another defect the kernel's
    /// builder found.
    Other,
}

impl Defect {
    /// A short phrase for the defect.
    pub fn phrase(self) -> &'static str {
        match self {
            Defect::NotFinite => "a coordinate is not a finite number",
            Defect::BadIndex => "a face names a vertex the file does not have",
            Defect::Degenerate => "a face is degenerate",
            Defect::Open => "the surface is open",
            Defect::NonManifoldEdge => "an edge is shared by more than two faces",
            Defect::NonManifoldVertex => "the faces about a vertex form more than one fan",
            Defect::InconsistentOrientation => "the faces are not oriented consistently",
            Defect::Inward => "the surface faces inward",
            Defect::SelfIntersection => "the surface intersects itself",
            Defect::HoleInFace => "a planar face would have a hole",
            Defect::OutOfRange => "the object is out of the world's range",
            Defect::Other => "the surface is not a closed polyhedron",
        }
    }
}

/// Where in a file a defect is: the object, and its faces and vertices in the file's own
/// numbering (vertices also by their coordinates, which every format shares).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Where {
    /// The object's index among the file's objects (from 0).
    pub object: usize,
    /// The object's name in the file, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Faces, as the file numbers them (from 0 in the file's order, for OBJ within the
    /// object).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub faces: Vec<u64>,
    /// Vertices, as the file numbers them (OBJ from 1, PLY and OFF from 0); empty where
    /// the file does not number them (STL).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub vertices: Vec<u64>,
    /// The same vertices' coordinates, in the file's unit.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub points: Vec<[f64; 3]>,
}

impl fmt::Display for Where {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "object {}", self.object)?;
        if let Some(name) = &self.name {
            write!(f, " ({name:?})")?;
        }
        if !self.faces.is_empty() {
            let s = if self.faces.len() == 1 { "" } else { "s" };
            write!(f, ", face{s} {}", list(&self.faces))?;
        }
        if !self.vertices.is_empty() {
            let what = if self.vertices.len() == 1 {
                "vertex"
            } else {
                "vertices"
            };
            write!(f, ", {what} {}", list(&self.vertices))?;
        }
        if !self.points.is_empty() {
            let pts: Vec<String> = self
                .points
                .iter()
                .map(|p| format!("({}, {}, {})", p[0], p[1], p[2]))
                .collect();
            write!(f, " at {}", pts.join(", "))?;
        }
        Ok(())
    }
}

fn list(xs: &[u64]) -> String {
    let s: Vec<String> = xs.iter().map(u64::to_string).collect();
    s.join(", ")
}

/// Why a mesh file was not imported.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ImportError {
    /// The bytes are not a file of the format, or the file is broken.
    #[error("the {format} file could not be read: {detail}")]
    Parse {
        /// The format's name.
        format: &'static str,
        /// The parser's own words.
        detail: String,
    },
    /// Something of the format winged does not read.
    #[error("{detail}")]
    Unsupported {
        /// What it is.
        detail: String,
    },
    /// More than a limit allows.
    #[error("the file has {count} {what}, above the limit of {limit}")]
    TooLarge {
        /// What was counted.
        what: &'static str,
        /// How many there are (or would be).
        count: u64,
        /// The limit.
        limit: u64,
    },
    /// The file has no faces.
    #[error("the file has no faces")]
    Empty,
    /// A surface that is not a valid closed polyhedron.
    #[error("{at}: {}{}", defect.phrase(), if detail.is_empty() { String::new() } else { format!(": {detail}") })]
    Invalid {
        /// What is wrong.
        defect: Defect,
        /// Where.
        at: Box<Where>,
        /// More words on it.
        detail: String,
    },
}
