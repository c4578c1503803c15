//! Polygon meshes in the OFF text format (`OFF`, then `V F 0`, then V lines `x y z`,
//! then F lines `n i1 … in`), written with Rust's shortest round-trip float text so
//! that a reader gets every locus back bit for bit.

use std::fmt::Write as _;
use std::path::Path;

use glam::DVec3;

/// Vertex loci and faces (rings of indices, counter-clockwise seen from outside).
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// The loci.
    pub positions: Vec<DVec3>,
    /// The faces.
    pub faces: Vec<Vec<u32>>,
}

impl Mesh {
    /// Appends `other`, renumbering its indices.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.faces.extend(
            other
                .faces
                .iter()
                .map(|f| f.iter().map(|&i| i + base).collect()),
        );
    }

    /// The triangles manifold3d sees once every face is cut into `n − 2`.
    pub fn triangle_count(&self) -> usize {
        self.faces.iter().map(|f| f.len().saturating_sub(2)).sum()
    }
}

/// Writes `mesh` to `path`.
pub fn write(path: &Path, mesh: &Mesh) -> std::io::Result<()> {
    let mut s = String::with_capacity(48 * (mesh.positions.len() + mesh.faces.len()));
    let _ = writeln!(s, "OFF\n{} {} 0", mesh.positions.len(), mesh.faces.len());
    for p in &mesh.positions {
        let _ = writeln!(s, "{} {} {}", p.x, p.y, p.z);
    }
    for f in &mesh.faces {
        let _ = write!(s, "{}", f.len());
        for i in f {
            let _ = write!(s, " {i}");
        }
        s.push('\n');
    }
    std::fs::write(path, s)
}

/// Reads an OFF file, refusing malformed text, counts that disagree and indices past
/// the vertex list.
pub fn read(path: &Path) -> Result<Mesh, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    parse(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Parses OFF text.
pub fn parse(text: &str) -> Result<Mesh, String> {
    let mut words = text
        .lines()
        .map(|l| l.split('#').next().unwrap_or(""))
        .flat_map(str::split_whitespace);
    if words.next() != Some("OFF") {
        return Err("does not start with OFF".into());
    }
    let mut number = |what: &str| -> Result<usize, String> {
        let w = words.next().ok_or(format!("ends before {what}"))?;
        w.parse()
            .map_err(|_| format!("{what}: {w:?} is not a count"))
    };
    let (nv, nf, _) = (
        number("the vertex count")?,
        number("the face count")?,
        number("the edge count")?,
    );
    let mut mesh = Mesh::default();
    let coordinate = |words: &mut dyn Iterator<Item = &str>| -> Result<f64, String> {
        let w = words.next().ok_or("ends inside the vertex list")?;
        w.parse().map_err(|_| format!("{w:?} is not a number"))
    };
    for _ in 0..nv {
        let (x, y, z) = (
            coordinate(&mut words)?,
            coordinate(&mut words)?,
            coordinate(&mut words)?,
        );
        mesh.positions.push(DVec3::new(x, y, z));
    }
    for f in 0..nf {
        let w = words.next().ok_or("ends inside the face list")?;
        let n: usize = w
            .parse()
            .map_err(|_| format!("face {f}: {w:?} is not a count"))?;
        let mut ring = Vec::with_capacity(n);
        for _ in 0..n {
            let w = words.next().ok_or("ends inside a face")?;
            let i: u32 = w
                .parse()
                .map_err(|_| format!("face {f}: {w:?} is not an index"))?;
            if i as usize >= nv {
                return Err(format!("face {f} names vertex {i} of {nv}"));
            }
            ring.push(i);
        }
        mesh.faces.push(ring);
    }
    Ok(mesh)
}
