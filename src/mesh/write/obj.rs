//! OBJ writing: polygon faces, coordinates in Rust's shortest round-trip form, so that
//! reading the file back gives every f64 bit for bit.

use std::fmt::Write as _;

use super::Solid;

/// Solids as one OBJ file, one object (`o`) each, named by the body's name (or
/// `body-<id>`). Faces keep their polygons; indices count from 1 over the whole file.
pub fn write(solids: &[Solid]) -> Vec<u8> {
    let mut out = String::from("# winged\n");
    let mut base = 1usize;
    for s in solids {
        let _ = match &s.name {
            Some(name) => writeln!(out, "o {}", name.replace(char::is_whitespace, "_")),
            None => writeln!(out, "o body-{}", s.id),
        };
        for p in &s.positions {
            let _ = writeln!(out, "v {:?} {:?} {:?}", p.x, p.y, p.z);
        }
        for face in s.faces.iter() {
            out.push('f');
            for &v in face {
                let _ = write!(out, " {}", v as usize + base);
            }
            out.push('\n');
        }
        base += s.positions.len();
    }
    out.into_bytes()
}
