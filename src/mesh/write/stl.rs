//! STL writing with `stl_io`: binary, the faces' triangles, f32 coordinates.

use super::{ExportError, Solid};

/// Solids as one binary STL file of their triangles (each with its unit normal).
pub fn write(solids: &[Solid]) -> Result<Vec<u8>, ExportError> {
    let mut triangles = Vec::new();
    for s in solids {
        let f32s = |i: u32| {
            let p = s.positions[i as usize];
            stl_io::Vertex::new([p.x as f32, p.y as f32, p.z as f32])
        };
        for [a, b, c] in s.triangles() {
            let (pa, pb, pc) = (
                s.positions[a as usize],
                s.positions[b as usize],
                s.positions[c as usize],
            );
            let n = (pb - pa).cross(pc - pa).normalize_or_zero();
            triangles.push(stl_io::Triangle {
                normal: stl_io::Normal::new([n.x as f32, n.y as f32, n.z as f32]),
                vertices: [f32s(a), f32s(b), f32s(c)],
            });
        }
    }
    let mut out = Vec::with_capacity(84 + 50 * triangles.len());
    stl_io::write_stl(&mut out, triangles.iter()).map_err(|e| ExportError::Encode {
        format: "stl",
        detail: e.to_string(),
    })?;
    Ok(out)
}
