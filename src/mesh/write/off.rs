//! OFF writing: polygon faces, coordinates in Rust's shortest round-trip form.

use std::fmt::Write as _;

use super::Solid;

/// A solid as an OFF file (vertices and faces numbered from 0).
pub fn write(solid: &Solid) -> Vec<u8> {
    let corners: usize = solid.faces.iter().map(<[u32]>::len).sum();
    let mut out = String::with_capacity(64 + 60 * solid.positions.len() + 12 * corners);
    let _ = writeln!(
        out,
        "OFF\n{} {} {}",
        solid.positions.len(),
        solid.faces.len(),
        corners / 2
    );
    for p in &solid.positions {
        let _ = writeln!(out, "{:?} {:?} {:?}", p.x, p.y, p.z);
    }
    for face in solid.faces.iter() {
        let _ = write!(out, "{}", face.len());
        for &v in face {
            let _ = write!(out, " {v}");
        }
        out.push('\n');
    }
    out.into_bytes()
}
