//! Stanford PLY, ASCII or binary, read with `ply-rs-bw`.
//!
//! The `vertex` element's `x`, `y`, `z` (of any numeric type, doubles kept exactly) and
//! `red`, `green`, `blue` (the first vertex's colour is the object's), and the `face`
//! element's `vertex_indices` (or `vertex_index`) lists; other elements and properties
//! are read past. Vertices and faces are numbered from 0, as the file counts them.

use std::io::BufReader;

use glam::DVec3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{DefaultElement, Property, PropertyAccess, PropertyAccessResult};

use super::{ImportError, ImportOptions, Polygons, RawObject, RawScene};
use crate::model::Color;

/// One vertex as read.
#[derive(Default)]
struct PlyVertex {
    at: [f64; 3],
    rgb: [Option<u8>; 3],
}

impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        PlyVertex::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let axis = match name {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            "red" | "green" | "blue" => {
                let k = ["red", "green", "blue"]
                    .iter()
                    .position(|&c| c == name)
                    .unwrap_or(0);
                self.rgb[k] = match property {
                    Property::UChar(v) => Some(v),
                    Property::Float(v) => Some((v.clamp(0.0, 1.0) * 255.0).round() as u8),
                    _ => None,
                };
                return PropertyAccessResult::Set;
            }
            _ => return PropertyAccessResult::Ignored,
        };
        self.at[axis] = match property {
            Property::Double(v) => v,
            Property::Float(v) => f64::from(v),
            Property::Char(v) => f64::from(v),
            Property::UChar(v) => f64::from(v),
            Property::Short(v) => f64::from(v),
            Property::UShort(v) => f64::from(v),
            Property::Int(v) => f64::from(v),
            Property::UInt(v) => f64::from(v),
            _ => return PropertyAccessResult::UnsupportedType,
        };
        PropertyAccessResult::Set
    }
}

/// One face as read; a negative index is kept as `u32::MAX`, which no vertex has.
#[derive(Default)]
struct PlyFace {
    indices: Vec<u32>,
}

impl PropertyAccess for PlyFace {
    fn new() -> Self {
        PlyFace::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if name != "vertex_indices" && name != "vertex_index" {
            return PropertyAccessResult::Ignored;
        }
        let signed = |v: i64| u32::try_from(v).unwrap_or(u32::MAX);
        self.indices = match property {
            Property::ListChar(v) => v.into_iter().map(|i| signed(i.into())).collect(),
            Property::ListUChar(v) => v.into_iter().map(u32::from).collect(),
            Property::ListShort(v) => v.into_iter().map(|i| signed(i.into())).collect(),
            Property::ListUShort(v) => v.into_iter().map(u32::from).collect(),
            Property::ListInt(v) => v.into_iter().map(|i| signed(i.into())).collect(),
            Property::ListUInt(v) => v,
            _ => return PropertyAccessResult::UnsupportedType,
        };
        PropertyAccessResult::Set
    }
}

/// Reads a PLY file into one object.
///
/// Refused with [`ImportError::Parse`] for what the parser refuses (a bad header, a
/// payload shorter than its counts, a property of a type that cannot be a coordinate or
/// an index); [`ImportError::TooLarge`] when the header counts more than
/// `options.max_file_faces` faces, before the payload is read.
pub fn read(bytes: &[u8], options: &ImportOptions) -> Result<RawScene, ImportError> {
    let parse = |e: ply_rs_bw::parser::ParseError| ImportError::Parse {
        format: "ply",
        detail: e.to_string(),
    };
    let mut reader = Reader::new(BufReader::new(bytes));
    let header = Parser::<DefaultElement>::new()
        .read_header(&mut reader)
        .map_err(parse)?;
    let mut positions = Vec::new();
    let mut faces = Polygons::default();
    let mut color = None;
    for (name, def) in header.elements.iter() {
        match name.as_str() {
            "vertex" => {
                if def.count > 2 * options.max_file_faces.max(4) {
                    return Err(too_large(def.count / 2, options));
                }
                let vs = Parser::<PlyVertex>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(parse)?;
                if let Some(v) = vs.first()
                    && let [Some(r), Some(g), Some(b)] = v.rgb
                {
                    color = Some(Color([r, g, b]));
                }
                positions = vs.into_iter().map(|v| DVec3::from_array(v.at)).collect();
            }
            "face" => {
                if def.count > options.max_file_faces {
                    return Err(too_large(def.count, options));
                }
                let fs = Parser::<PlyFace>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(parse)?;
                faces = Polygons::with_capacity(fs.len(), 3 * fs.len());
                for f in &fs {
                    faces.push(&f.indices);
                }
            }
            _ => {
                Parser::<DefaultElement>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(parse)?;
            }
        }
    }
    Ok(RawScene {
        objects: vec![RawObject {
            color,
            positions,
            faces,
            first_vertex: Some(0),
            ..RawObject::default()
        }],
        unit: None,
    })
}

fn too_large(count: usize, options: &ImportOptions) -> ImportError {
    ImportError::TooLarge {
        what: "faces in the file",
        count: count as u64,
        limit: options.max_file_faces as u64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_with_extra_properties_and_a_colour() {
        let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\n\
                    property double y\nproperty double z\nproperty float nx\n\
                    property uchar red\nproperty uchar green\nproperty uchar blue\n\
                    element face 4\nproperty list uchar int vertex_indices\nend_header\n\
                    0 0 0 1 10 20 30\n1 0 0 1 0 0 0\n0 1 0 1 0 0 0\n0 0 0.1 1 0 0 0\n\
                    3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
        let scene = read(text.as_bytes(), &ImportOptions::default()).expect("reads");
        let o = &scene.objects[0];
        assert_eq!(o.positions.len(), 4);
        assert_eq!(o.positions[3].z.to_bits(), 0.1f64.to_bits());
        assert_eq!(o.faces.len(), 4);
        assert_eq!(o.color, Some(Color([10, 20, 30])));
    }

    #[test]
    fn a_truncated_payload_and_a_bad_header_are_refused() {
        for text in [
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n0\n",
            "ply\nformat nonsense 1.0\nend_header\n",
            "not a ply file",
        ] {
            let e = read(text.as_bytes(), &ImportOptions::default());
            assert!(
                matches!(e, Err(ImportError::Parse { .. })),
                "{text:?}: {e:?}"
            );
        }
    }
}
