//! PLY writing with `ply-rs-bw`: coordinates as doubles, polygon faces as `uchar`/`uint`
//! lists (a face of more than 255 corners as `uint`/`uint`).
//!
//! Binary little-endian when every face has the same number of corners; ASCII (each
//! double in Rust's shortest round-trip form, so still exact) when they differ, since
//! common readers (trimesh among them) read binary face lists of one length only.

use ply_rs_bw::ply::{
    Addable, ElementDef, Encoding, Header, PropertyAccess, PropertyDef, PropertyType, ScalarType,
};
use ply_rs_bw::writer::Writer;

use super::{ExportError, Solid};

struct OutVertex([f64; 3], [u8; 3]);

impl PropertyAccess for OutVertex {
    fn new() -> Self {
        OutVertex([0.0; 3], [0; 3])
    }

    fn get_double(&self, name: &str) -> Option<f64> {
        match name {
            "x" => Some(self.0[0]),
            "y" => Some(self.0[1]),
            "z" => Some(self.0[2]),
            _ => None,
        }
    }

    fn get_uchar(&self, name: &str) -> Option<u8> {
        match name {
            "red" => Some(self.1[0]),
            "green" => Some(self.1[1]),
            "blue" => Some(self.1[2]),
            _ => None,
        }
    }
}

struct OutFace(Vec<u32>);

impl PropertyAccess for OutFace {
    fn new() -> Self {
        OutFace(Vec::new())
    }

    fn get_list_uint(&self, name: &str) -> Option<&[u32]> {
        (name == "vertex_indices").then_some(&self.0[..])
    }
}

/// A solid as a PLY file (see the module's notes on its encoding), its colour on every
/// vertex.
pub fn write(solid: &Solid) -> Result<Vec<u8>, ExportError> {
    let encode = |e: std::io::Error| ExportError::Encode {
        format: "ply",
        detail: e.to_string(),
    };
    let mut header = Header::new();
    let mut sizes = solid.faces.iter().map(<[u32]>::len);
    let first = sizes.next();
    header.encoding = if sizes.all(|n| Some(n) == first) {
        Encoding::BinaryLittleEndian
    } else {
        Encoding::Ascii
    };
    header.comments.push("winged".to_string());
    let mut vertex = ElementDef::new("vertex".to_string());
    vertex.count = solid.positions.len();
    for axis in ["x", "y", "z"] {
        vertex.properties.add(PropertyDef::new(
            axis.to_string(),
            PropertyType::Scalar(ScalarType::Double),
        ));
    }
    for channel in ["red", "green", "blue"] {
        vertex.properties.add(PropertyDef::new(
            channel.to_string(),
            PropertyType::Scalar(ScalarType::UChar),
        ));
    }
    let mut face = ElementDef::new("face".to_string());
    face.count = solid.faces.len();
    let widest = solid.faces.iter().map(<[u32]>::len).max().unwrap_or(0);
    let count_type = if widest > 255 {
        ScalarType::UInt
    } else {
        ScalarType::UChar
    };
    face.properties.add(PropertyDef::new(
        "vertex_indices".to_string(),
        PropertyType::List(count_type, ScalarType::UInt),
    ));
    header.elements.add(vertex.clone());
    header.elements.add(face.clone());
    let vertices: Vec<OutVertex> = solid
        .positions
        .iter()
        .map(|p| OutVertex(p.to_array(), solid.color.0))
        .collect();
    let faces: Vec<OutFace> = solid.faces.iter().map(|f| OutFace(f.to_vec())).collect();
    let mut out = Vec::with_capacity(256 + 27 * vertices.len() + 17 * faces.len());
    Writer::<OutVertex>::new()
        .write_header(&mut out, &header)
        .map_err(encode)?;
    Writer::<OutVertex>::new()
        .write_payload_of_element(&mut out, &vertices, &vertex, &header)
        .map_err(encode)?;
    Writer::<OutFace>::new()
        .write_payload_of_element(&mut out, &faces, &face, &header)
        .map_err(encode)?;
    Ok(out)
}
