//! STL, binary or ASCII, read with `stl_io`.
//!
//! An STL file is one object: a list of triangles, each with its own three corners.
//! Corners with the same coordinates (bit for bit, as f32) are made one vertex here; a
//! `weld` tolerance joins nearer ones later ([`super::polygons`]). Triangles are
//! numbered from 0 in the file's order; STL does not number vertices.

use std::io::Cursor;

use glam::DVec3;

use super::Map;
use super::{ImportError, ImportOptions, Polygons, RawObject, RawScene};

/// Bytes of a binary STL's header and of each of its triangles.
const HEADER: usize = 84;
const TRIANGLE: usize = 50;

/// Reads an STL file into one object of triangles.
///
/// Refused with [`ImportError::Parse`] when the file is neither ASCII nor binary STL,
/// or a binary file is shorter than the triangles its header counts;
/// [`ImportError::TooLarge`] above `options.max_file_faces` triangles (counted from the
/// header before any is read).
pub fn read(bytes: &[u8], options: &ImportOptions) -> Result<RawScene, ImportError> {
    let parse = |detail: String| ImportError::Parse {
        format: "stl",
        detail,
    };
    let ascii = is_ascii(bytes);
    let declared = if ascii {
        None
    } else {
        let Some(count) = bytes.get(80..84) else {
            return Err(parse(format!(
                "a binary STL has an 84-byte header; this file has {} bytes",
                bytes.len()
            )));
        };
        let n = u32::from_le_bytes([count[0], count[1], count[2], count[3]]) as usize;
        if n > options.max_file_faces {
            return Err(ImportError::TooLarge {
                what: "faces in the file",
                count: n as u64,
                limit: options.max_file_faces as u64,
            });
        }
        let need = HEADER + TRIANGLE * n;
        if bytes.len() < need {
            return Err(parse(format!(
                "the header counts {n} triangles ({need} bytes), but the file has {} bytes",
                bytes.len()
            )));
        }
        Some(n)
    };
    let mut cursor = Cursor::new(bytes);
    let reader = stl_io::create_stl_reader(&mut cursor).map_err(|e| parse(e.to_string()))?;
    let mut index: Map<[u32; 3], u32> = Map::default();
    let capacity = declared.unwrap_or(0);
    index.reserve(capacity / 2 + 3);
    let mut positions = Vec::with_capacity(capacity / 2 + 3);
    let mut faces = Polygons::with_capacity(capacity, 3 * capacity);
    for t in reader {
        let t = t.map_err(|e| parse(e.to_string()))?;
        if faces.len() >= options.max_file_faces {
            return Err(ImportError::TooLarge {
                what: "faces in the file",
                count: faces.len() as u64 + 1,
                limit: options.max_file_faces as u64,
            });
        }
        let mut tri = [0u32; 3];
        for (k, v) in t.vertices.iter().enumerate() {
            let key = v.0.map(f32::to_bits);
            let next = positions.len() as u32;
            tri[k] = *index.entry(key).or_insert_with(|| {
                positions.push(DVec3::new(
                    f64::from(v.0[0]),
                    f64::from(v.0[1]),
                    f64::from(v.0[2]),
                ));
                next
            });
        }
        faces.push(&tri);
    }
    Ok(RawScene {
        objects: vec![RawObject {
            name: ascii.then(|| solid_name(bytes)).flatten(),
            positions,
            faces,
            ..RawObject::default()
        }],
        unit: None,
    })
}

/// Whether the file is ASCII STL: it starts with `solid` and, since binary files may
/// start so too, a `facet` (or `endsolid`) follows in its first kilobyte and its length
/// is not exactly what a binary header would count.
fn is_ascii(bytes: &[u8]) -> bool {
    let text = trim_start(bytes);
    if !text.starts_with(b"solid") {
        return false;
    }
    if bytes.len() >= HEADER {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if HEADER.checked_add(TRIANGLE.saturating_mul(n)) == Some(bytes.len()) {
            return false;
        }
    }
    let head = &bytes[..bytes.len().min(1024)];
    head.windows(5).any(|w| w == b"facet") || head.windows(8).any(|w| w == b"endsolid")
}

fn trim_start(bytes: &[u8]) -> &[u8] {
    let n = bytes.iter().take_while(|b| b.is_ascii_whitespace()).count();
    &bytes[n..]
}

/// The name after `solid` on an ASCII file's first line, if any.
fn solid_name(bytes: &[u8]) -> Option<String> {
    let text = trim_start(bytes);
    let line = text.split(|&b| b == b'\n').next()?;
    let name = std::str::from_utf8(line.get(5..)?).ok()?.trim();
    (!name.is_empty()).then(|| name.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn binary(tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
        let mut out = vec![0u8; 80];
        out.extend_from_slice(&(tris.len() as u32).to_le_bytes());
        for t in tris {
            out.extend_from_slice(&[0u8; 12]);
            for v in t {
                for c in v {
                    out.extend_from_slice(&c.to_le_bytes());
                }
            }
            out.extend_from_slice(&[0, 0]);
        }
        out
    }

    #[test]
    fn shared_corners_become_one_vertex() {
        let a = [0.0, 0.0, 0.0];
        let b = [1.0, 0.0, 0.0];
        let c = [0.0, 1.0, 0.0];
        let d = [0.0, 0.0, 1.0];
        let file = binary(&[[a, c, b], [a, b, d], [a, d, c], [b, c, d]]);
        let scene = read(&file, &ImportOptions::default()).expect("reads");
        let o = &scene.objects[0];
        assert_eq!(o.positions.len(), 4);
        assert_eq!(o.faces.len(), 4);
    }

    #[test]
    fn a_short_binary_file_is_refused_before_reading() {
        let mut file = binary(&[[[0.0; 3]; 3]]);
        file[80..84].copy_from_slice(&1000u32.to_le_bytes());
        let e = read(&file, &ImportOptions::default()).expect_err("short");
        assert!(e.to_string().contains("1000 triangles"), "{e}");
    }

    #[test]
    fn ascii_is_read_with_its_name() {
        let text = "solid part\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
                    vertex 0 1 0\nendloop\nendfacet\nendsolid part\n";
        let scene = read(text.as_bytes(), &ImportOptions::default()).expect("reads");
        assert_eq!(scene.objects[0].name.as_deref(), Some("part"));
        assert_eq!(scene.objects[0].faces.len(), 1);
    }
}
