//! Writing solids as a 3MF package.

use std::fmt::Write as _;
use std::io::{Cursor, Write as _};

use zip::CompressionMethod;
use zip::ZipWriter;
use zip::write::SimpleFileOptions;

use super::MODEL_RELATIONSHIP;
use crate::mesh::write::{ExportError, Solid};

/// The root model part's name in written packages (the conventional one, which some
/// readers, trimesh among them, look for by name).
pub(super) const MODEL_PART: &str = "3D/3dmodel.model";

const CONTENT_TYPES: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types"><Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/><Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/></Types>
"#;

fn encode_error(detail: impl ToString) -> ExportError {
    ExportError::Encode {
        format: "3mf",
        detail: detail.to_string(),
    }
}

/// Solids as one 3MF package: `[Content_Types].xml`, `_rels/.rels` and the model part
/// `3D/3dmodel.model` in `unit="meter"`, one object per solid (ids from 1, `type="model"`,
/// its name if it has one) holding its positions as they are and its triangles
/// ([`Solid::triangles`], wound as its faces), one build item per object, and one
/// `basematerials` group (id `solids.len() + 1`, written before the objects that use it)
/// with each solid's colour as the `displaycolor` (`#RRGGBB`) of the base its object's
/// `pid`/`pindex` names.
///
/// Coordinates are written in Rust's shortest round-trip decimal form, so a reader that
/// parses them correctly gets each f64 back bit for bit.
///
/// Refused with [`ExportError::Encode`] when a coordinate is not finite (3MF has no
/// spelling for it) or the zip writer fails.
pub fn write(solids: &[Solid]) -> Result<Vec<u8>, ExportError> {
    let model = model_xml(solids)?;
    let deflated = SimpleFileOptions::default().compression_method(CompressionMethod::Deflated);
    let mut zip = ZipWriter::new(Cursor::new(Vec::new()));
    let rels = format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships"><Relationship Target="/{MODEL_PART}" Id="rel0" Type="{MODEL_RELATIONSHIP}"/></Relationships>
"#
    );
    let files = [
        ("[Content_Types].xml", CONTENT_TYPES.as_bytes()),
        ("_rels/.rels", rels.as_bytes()),
        (MODEL_PART, model.as_bytes()),
    ];
    for (name, bytes) in files {
        let options = deflated.large_file(bytes.len() as u64 >= u64::from(u32::MAX));
        zip.start_file(name, options).map_err(encode_error)?;
        zip.write_all(bytes).map_err(encode_error)?;
    }
    let cursor = zip.finish().map_err(encode_error)?;
    Ok(cursor.into_inner())
}

/// The model part's XML.
fn model_xml(solids: &[Solid]) -> Result<String, ExportError> {
    let size: usize = solids
        .iter()
        .map(|s| 80 * s.positions.len() + 60 * s.faces.len())
        .sum();
    let mut x = String::with_capacity(size + 1024);
    // Writing to a String cannot fail; the results are passed on all the same.
    let fmt = |e: std::fmt::Error| encode_error(e);
    x.push_str(concat!(
        r#"<?xml version="1.0" encoding="UTF-8"?>"#,
        "\n",
        r#"<model unit="meter" xml:lang="en-US" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">"#,
        "\n <resources>\n"
    ));
    let materials = solids.len() + 1;
    if !solids.is_empty() {
        writeln!(x, r#"  <basematerials id="{materials}">"#).map_err(fmt)?;
        for s in solids {
            let name = match &s.name {
                Some(n) => attribute(n),
                None => format!("body {}", s.id),
            };
            let [r, g, b] = s.color.0;
            writeln!(
                x,
                r##"   <base name="{name}" displaycolor="#{r:02X}{g:02X}{b:02X}"/>"##
            )
            .map_err(fmt)?;
        }
        x.push_str("  </basematerials>\n");
    }
    for (k, s) in solids.iter().enumerate() {
        let id = k + 1;
        write!(x, r#"  <object id="{id}" type="model""#).map_err(fmt)?;
        if let Some(n) = &s.name {
            write!(x, r#" name="{}""#, attribute(n)).map_err(fmt)?;
        }
        writeln!(x, r#" pid="{materials}" pindex="{k}">"#).map_err(fmt)?;
        x.push_str("   <mesh>\n    <vertices>\n");
        for p in &s.positions {
            if !p.is_finite() {
                return Err(encode_error(format!(
                    "body {} has a vertex at ({}, {}, {}), not finite",
                    s.id, p.x, p.y, p.z
                )));
            }
            // `{}` of an f64 is the shortest decimal that parses back to it, with no
            // exponent: 3MF's number syntax.
            writeln!(x, r#"     <vertex x="{}" y="{}" z="{}"/>"#, p.x, p.y, p.z).map_err(fmt)?;
        }
        x.push_str("    </vertices>\n    <triangles>\n");
        for [a, b, c] in s.triangles() {
            writeln!(x, r#"     <triangle v1="{a}" v2="{b}" v3="{c}"/>"#).map_err(fmt)?;
        }
        x.push_str("    </triangles>\n   </mesh>\n  </object>\n");
    }
    x.push_str(" </resources>\n <build>\n");
    for k in 0..solids.len() {
        writeln!(x, r#"  <item objectid="{}"/>"#, k + 1).map_err(fmt)?;
    }
    x.push_str(" </build>\n</model>\n");
    Ok(x)
}

/// Text escaped for an attribute value: markup characters and white space other than
/// the space as references (so that a reader's normalization keeps them), characters
/// XML 1.0 cannot hold dropped.
fn attribute(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' => out.push_str("&#9;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            c if (c as u32) < 0x20 || c == '\u{fffe}' || c == '\u{ffff}' => {}
            c => out.push(c),
        }
    }
    out
}
