//! OFF (Object File Format), read here.
//!
//! The one OFF crate (`off-rs`) parses coordinates as f32, which would break the
//! bit-exact round trip of f64 loci, so the format's few rules are read here: an `OFF`
//! keyword (optionally `COFF`, `NOFF`, `CNOFF`, `STOFF`: the per-vertex extras are
//! skipped), `#` comments, then the counts `V F E`, `V` lines of coordinates and `F`
//! lines `n i1 … in` (anything after the indices, a face colour, is skipped). Vertices
//! and faces are numbered from 0.

use glam::DVec3;

use super::{ImportError, ImportOptions, Polygons, RawObject, RawScene};

/// Reads an OFF file into one object.
///
/// Refused with [`ImportError::Parse`] (naming the line) for a missing keyword or count,
/// a number that does not parse, or a file that ends early; [`ImportError::TooLarge`]
/// when the counts exceed `options.max_file_faces` faces (or twice as many vertices).
pub fn read(bytes: &[u8], options: &ImportOptions) -> Result<RawScene, ImportError> {
    let text = std::str::from_utf8(bytes).map_err(|e| parse(0, format!("not UTF-8 text: {e}")))?;
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.split('#').next().unwrap_or("").trim()))
        .filter(|(_, l)| !l.is_empty());
    let (n, first) = lines
        .next()
        .ok_or_else(|| parse(0, "the file is empty".into()))?;
    let mut words: Vec<&str> = first.split_whitespace().collect();
    let keyword = words.first().copied().unwrap_or("");
    if !keyword.ends_with("OFF") {
        return Err(parse(
            n,
            format!("expected the keyword OFF, found {keyword:?}"),
        ));
    }
    if keyword.contains('4') || keyword.starts_with('n') {
        return Err(ImportError::Unsupported {
            detail: format!("OFF of other than three dimensions ({keyword}) is not read"),
        });
    }
    let extras = usize::from(keyword.contains("ST")) * 2
        + usize::from(keyword.contains('C')) * 4
        + usize::from(keyword.contains('N')) * 3;
    words.remove(0);
    let (line, counts) = if words.is_empty() {
        let (n, l) = lines
            .next()
            .ok_or_else(|| parse(n, "the counts are missing".into()))?;
        (n, l.split_whitespace().collect::<Vec<_>>())
    } else {
        (n, words)
    };
    let count = |k: usize, what: &str| -> Result<usize, ImportError> {
        counts
            .get(k)
            .ok_or_else(|| parse(line, format!("the {what} count is missing")))?
            .parse::<usize>()
            .map_err(|e| parse(line, format!("the {what} count: {e}")))
    };
    let (nv, nf) = (count(0, "vertex")?, count(1, "face")?);
    if nf > options.max_file_faces || nv > 2 * options.max_file_faces.max(4) {
        return Err(ImportError::TooLarge {
            what: "faces in the file",
            count: nf.max(nv / 2) as u64,
            limit: options.max_file_faces as u64,
        });
    }
    let mut positions = Vec::with_capacity(nv.min(bytes.len() / 6));
    for k in 0..nv {
        let (n, l) = lines
            .next()
            .ok_or_else(|| parse(line, format!("the file ends after {k} of {nv} vertices")))?;
        let mut xyz = [0.0f64; 3];
        let mut words = l.split_whitespace();
        for c in &mut xyz {
            let w = words
                .next()
                .ok_or_else(|| parse(n, "a vertex needs three coordinates".into()))?;
            *c = w
                .parse::<f64>()
                .map_err(|e| parse(n, format!("coordinate {w:?}: {e}")))?;
        }
        if words.count() < extras {
            return Err(parse(
                n,
                format!("{keyword} asks for {extras} more numbers"),
            ));
        }
        positions.push(DVec3::from_array(xyz));
    }
    let mut faces = Polygons::with_capacity(nf.min(bytes.len() / 6), 0);
    let mut face = Vec::new();
    for k in 0..nf {
        let (n, l) = lines
            .next()
            .ok_or_else(|| parse(line, format!("the file ends after {k} of {nf} faces")))?;
        let mut words = l.split_whitespace();
        let degree: usize = words
            .next()
            .unwrap_or("")
            .parse()
            .map_err(|e| parse(n, format!("a face's vertex count: {e}")))?;
        face.clear();
        for _ in 0..degree {
            let w = words
                .next()
                .ok_or_else(|| parse(n, format!("the face lists fewer than {degree} vertices")))?;
            face.push(
                w.parse::<u32>()
                    .map_err(|e| parse(n, format!("vertex index {w:?}: {e}")))?,
            );
        }
        faces.push(&face);
    }
    Ok(RawScene {
        objects: vec![RawObject {
            positions,
            faces,
            first_vertex: Some(0),
            ..RawObject::default()
        }],
        unit: None,
    })
}

fn parse(line: usize, what: String) -> ImportError {
    ImportError::Parse {
        format: "off",
        detail: if line == 0 {
            what
        } else {
            format!("line {line}: {what}")
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tetrahedron_with_comments_and_colours() {
        let text = "OFF\n# a comment\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n\
                    3 0 2 1 255 0 0\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
        let scene = read(text.as_bytes(), &ImportOptions::default()).expect("reads");
        let o = &scene.objects[0];
        assert_eq!(o.positions.len(), 4);
        assert_eq!(o.faces.face(0), &[0, 2, 1]);
    }

    #[test]
    fn broken_files_name_the_line() {
        for (text, want) in [
            ("PLY\n", "keyword"),
            ("OFF\n2 1 0\n0 0 0\n", "ends after 1 of 2 vertices"),
            ("OFF\n1 0 0\n0 x 0\n", "line 3"),
            ("OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "fewer than 4"),
        ] {
            let e = read(text.as_bytes(), &ImportOptions::default()).expect_err(text);
            assert!(e.to_string().contains(want), "{text:?}: {e}");
        }
    }
}
