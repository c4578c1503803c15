//! Wavefront OBJ, read with `tobj` (triangulation off, so n-gons stay polygons).
//!
//! Each object or group of the file (`o`, `g`; tobj also starts a new one where the
//! material changes) becomes one [`RawObject`]. Points and lines are ignored; material
//! libraries (`mtllib`) are not opened (winged has no files beside the upload), so an
//! OBJ's colours are not read. Texture coordinates and normals (`vt`, `vn`) are not
//! given to tobj at all (see [`Geometry`]).

use std::io::{BufRead, Read};

use glam::DVec3;

use super::{ImportError, ImportOptions, Polygons, RawObject, RawScene};

/// Reads an OBJ file: its objects, positions as f64 exactly as written.
///
/// Refused with [`ImportError::Parse`] for what tobj cannot read (an unknown statement,
/// a face naming a vertex the file does not have, text that is not UTF-8).
pub fn read(bytes: &[u8], options: &ImportOptions) -> Result<RawScene, ImportError> {
    let load = tobj::LoadOptions {
        triangulate: false,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let mut reader = Geometry::new(bytes);
    let (models, _materials) =
        tobj::load_obj_buf(&mut reader, &load, |_| Err(tobj::LoadError::OpenFileFailed)).map_err(
            |e| ImportError::Parse {
                format: "obj",
                detail: e.to_string(),
            },
        )?;
    let mut scene = RawScene::default();
    let mut total = 0usize;
    for model in models {
        let mesh = model.mesh;
        let arities: Vec<u32> = if mesh.face_arities.is_empty() {
            vec![3; mesh.indices.len() / 3]
        } else {
            mesh.face_arities
        };
        if arities.is_empty() {
            continue;
        }
        total += arities.len();
        if total > options.max_file_faces {
            return Err(ImportError::TooLarge {
                what: "faces in the file",
                count: total as u64,
                limit: options.max_file_faces as u64,
            });
        }
        let positions: Vec<DVec3> = mesh
            .positions
            .chunks_exact(3)
            .map(|p| DVec3::new(p[0], p[1], p[2]))
            .collect();
        let mut faces = Polygons::with_capacity(arities.len(), mesh.indices.len());
        let mut at = 0usize;
        for &n in &arities {
            let end = at + n as usize;
            let Some(face) = mesh.indices.get(at..end) else {
                return Err(ImportError::Parse {
                    format: "obj",
                    detail: "a face's indices run past the end of the list".into(),
                });
            };
            faces.push(face);
            at = end;
        }
        scene.objects.push(RawObject {
            name: (!model.name.is_empty() && model.name != "unnamed_object").then_some(model.name),
            positions,
            faces,
            ..RawObject::default()
        });
    }
    Ok(scene)
}

/// An OBJ file's lines without its `vt` and `vn` statements, as tobj reads them (a line
/// whose first word, split at whitespace, is `vt` or `vn`).
///
/// winged uses neither, and tobj 4.0.5 multiplies a face's texture-coordinate and
/// normal indices unchecked (`vt * 2 + 1`, `vn * 3 + 2`): an index before the start of
/// the list (`f 1//-4` with fewer than four normals) wraps to a huge `usize`, which
/// overflows there. Without those lists tobj never looks at those indices. A line that
/// is not UTF-8 is kept, for tobj to refuse.
struct Geometry<'a> {
    /// What is left of the file.
    rest: &'a [u8],
    /// How many bytes at the start of `rest` are a kept line not yet read.
    line: usize,
}

impl<'a> Geometry<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        Geometry {
            rest: bytes,
            line: 0,
        }
    }
}

/// Whether `line` is a `vt` or `vn` statement.
fn is_attribute(line: &[u8]) -> bool {
    std::str::from_utf8(line)
        .ok()
        .and_then(|l| l.split_whitespace().next())
        .is_some_and(|word| word == "vt" || word == "vn")
}

impl BufRead for Geometry<'_> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        while self.line == 0 && !self.rest.is_empty() {
            let len = memchr::memchr(b'\n', self.rest).map_or(self.rest.len(), |i| i + 1);
            if is_attribute(&self.rest[..len]) {
                self.rest = &self.rest[len..];
            } else {
                self.line = len;
            }
        }
        Ok(&self.rest[..self.line])
    }

    fn consume(&mut self, amount: usize) {
        let amount = amount.min(self.line);
        self.rest = &self.rest[amount..];
        self.line -= amount;
    }
}

impl Read for Geometry<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let line = self.fill_buf()?;
        let n = line.len().min(buf.len());
        buf[..n].copy_from_slice(&line[..n]);
        self.consume(n);
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quad_stays_a_quad_and_coordinates_are_exact() {
        let text = "o sheet\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0.1 1 0\nf 1 2 3 4\n";
        let scene = read(text.as_bytes(), &ImportOptions::default()).expect("reads");
        assert_eq!(scene.objects.len(), 1);
        let o = &scene.objects[0];
        assert_eq!(o.name.as_deref(), Some("sheet"));
        assert_eq!(o.faces.face(0), &[0, 1, 2, 3]);
        assert_eq!(o.positions[3].x.to_bits(), 0.1f64.to_bits());
    }

    #[test]
    fn groups_are_objects_and_bad_indices_are_refused() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\ng a\nf 1 2 3\ng b\nf 1 2 4\n";
        let scene = read(text.as_bytes(), &ImportOptions::default()).expect("reads");
        assert_eq!(scene.objects.len(), 2);
        let bad = read(b"v 0 0 0\nf 1 2 9\n", &ImportOptions::default());
        assert!(matches!(bad, Err(ImportError::Parse { .. })), "{bad:?}");
    }
}
