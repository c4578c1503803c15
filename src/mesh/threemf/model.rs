//! One model part's XML (the 3MF core schema, as far as winged uses it) parsed with a
//! streaming reader into objects, base materials and build items.
//!
//! Elements are matched by their local names, whatever prefix they carry, and only where
//! the core schema puts them (a `vertex` counts only inside `model/resources/object/
//! mesh/vertices`); every other element, and everything inside it, is skipped. Core
//! attributes are matched unprefixed, as the schema declares them; a component's or
//! item's `path` (the production extension's `p:path`) with any prefix.
//!
//! Triangles are counted as they are read, so that a part with more than the limit is
//! refused before its lists grow past it.

use glam::{DAffine3, DMat3, DVec3};
use quick_xml::XmlVersion;
use quick_xml::events::{BytesStart, Event};
use quick_xml::reader::Reader;

use super::parse_error;
use crate::mesh::{ImportError, Map};
use crate::model::Color;

/// The units a 3MF model may declare.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum FileUnit {
    Micron,
    Millimeter,
    Centimeter,
    Inch,
    Foot,
    Meter,
}

impl FileUnit {
    /// The unit named by a model's `unit` attribute.
    fn parse(s: &str) -> Option<FileUnit> {
        Some(match s.trim() {
            "micron" => FileUnit::Micron,
            "millimeter" => FileUnit::Millimeter,
            "centimeter" => FileUnit::Centimeter,
            "inch" => FileUnit::Inch,
            "foot" => FileUnit::Foot,
            "meter" => FileUnit::Meter,
            _ => return None,
        })
    }

    /// Micrometres per unit, exactly.
    pub(super) fn microns(self) -> f64 {
        match self {
            FileUnit::Micron => 1.0,
            FileUnit::Millimeter => 1e3,
            FileUnit::Centimeter => 1e4,
            FileUnit::Inch => 25_400.0,
            FileUnit::Foot => 304_800.0,
            FileUnit::Meter => 1e6,
        }
    }
}

/// A reference to an object: a build item or a component.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Ref {
    /// The object's id.
    pub object: u64,
    /// Maps the object's coordinates to the referring frame's (identity when absent).
    pub transform: DAffine3,
    /// The part that defines the object (`p:path`, as written), `None` for the
    /// referring part itself.
    pub path: Option<String>,
}

/// One `object` resource.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Object {
    /// Its id in its part.
    pub id: u64,
    /// Its `name` attribute.
    pub name: Option<String>,
    /// Its `partnumber` attribute.
    pub partnumber: Option<String>,
    /// False for the types that are not printed as solids: `support`, `surface`, `other`.
    pub solid: bool,
    /// Its `pid` and `pindex` (the object's default property).
    pub pid: Option<u64>,
    pub pindex: Option<u64>,
    /// Its mesh's vertices.
    pub positions: Vec<DVec3>,
    /// Its mesh's triangles as written (`v1 v2 v3`), indices saturated at `u32::MAX`.
    pub triangles: Vec<[u32; 3]>,
    /// Its components.
    pub components: Vec<Ref>,
}

/// What one model part holds.
#[derive(Clone, Debug, Default)]
pub(super) struct Part {
    /// Its declared unit (millimetres when it declares none).
    pub unit: Option<FileUnit>,
    /// Its objects, in the file's order.
    pub objects: Vec<Object>,
    /// Object id → index into `objects`.
    pub ids: Map<u64, usize>,
    /// Base-materials group id → each base's display colour (`None` when unreadable).
    pub materials: Map<u64, Vec<Option<Color>>>,
    /// Its build items.
    pub build: Vec<Ref>,
}

impl Part {
    /// The declared unit, millimetres by default as the specification says.
    pub(super) fn unit(&self) -> FileUnit {
        self.unit.unwrap_or(FileUnit::Millimeter)
    }

    /// Multiplies every coordinate and translation of the part by `factor` (a change of
    /// unit: a linear part commutes with a uniform scale, so only translations change).
    pub(super) fn rescale(&mut self, factor: f64) {
        for o in &mut self.objects {
            for p in &mut o.positions {
                *p *= factor;
            }
            for c in &mut o.components {
                c.transform.translation *= factor;
            }
        }
        for item in &mut self.build {
            item.transform.translation *= factor;
        }
    }

    /// Every reference the part makes to another part (by its `path`).
    pub(super) fn paths(&self) -> impl Iterator<Item = &str> {
        self.objects
            .iter()
            .flat_map(|o| o.components.iter())
            .chain(self.build.iter())
            .filter_map(|r| r.path.as_deref())
    }
}

/// Where the parser is in the schema's tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum At {
    Model,
    Resources,
    Object,
    Mesh,
    Vertices,
    Triangles,
    Components,
    Materials,
    Build,
}

/// Parses model part `name`'s XML. `faces` counts triangles over every part read so far;
/// it is raised by this part's.
///
/// Refused with [`ImportError::Parse`] for XML that is not well-formed, a root element
/// other than `model`, an unknown unit, a required attribute missing, a number that does
/// not parse, two objects with one id; [`ImportError::TooLarge`] as soon as `faces`
/// passes `max_faces`.
pub(super) fn parse(
    xml: &str,
    name: &str,
    faces: &mut usize,
    max_faces: usize,
) -> Result<Part, ImportError> {
    let mut reader = Reader::from_str(xml);
    let mut parser = Parser {
        name,
        part: Part::default(),
        stack: Vec::new(),
        object: None,
        group: None,
        seen_root: false,
        faces,
        max_faces,
    };
    // Depth inside an element that is skipped (0: not skipping).
    let mut skip = 0usize;
    loop {
        let at = reader.buffer_position();
        let event = reader.read_event().map_err(|e| {
            parse_error(format!(
                "{name}: {e} (near byte {})",
                reader.error_position()
            ))
        })?;
        let fail = |e: ImportError| match e {
            ImportError::Parse { format, detail } => ImportError::Parse {
                format,
                detail: format!("{name}, near byte {at}: {detail}"),
            },
            other => other,
        };
        match event {
            Event::Start(e) => {
                if skip > 0 {
                    skip += 1;
                } else {
                    match parser.open(&e).map_err(fail)? {
                        Some(at) => parser.stack.push(at),
                        None => skip = 1,
                    }
                }
            }
            Event::Empty(e) => {
                if skip == 0
                    && let Some(at) = parser.open(&e).map_err(fail)?
                {
                    parser.close(at).map_err(fail)?;
                }
            }
            Event::End(_) => {
                if skip > 0 {
                    skip -= 1;
                } else if let Some(at) = parser.stack.pop() {
                    parser.close(at).map_err(fail)?;
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    if !parser.seen_root {
        return Err(parse_error(format!("{name}: there is no <model> element")));
    }
    if skip > 0 || !parser.stack.is_empty() {
        return Err(parse_error(format!(
            "{name}: the XML ends inside an element"
        )));
    }
    Ok(parser.part)
}

struct Parser<'a> {
    name: &'a str,
    part: Part,
    stack: Vec<At>,
    /// The object being read.
    object: Option<Object>,
    /// The base-materials group being read.
    group: Option<(u64, Vec<Option<Color>>)>,
    seen_root: bool,
    faces: &'a mut usize,
    max_faces: usize,
}

impl Parser<'_> {
    /// An element opens: handles it, and returns where the parser now is when it is a
    /// container to descend into (`None` for a leaf or an element that is skipped).
    fn open(&mut self, e: &BytesStart<'_>) -> Result<Option<At>, ImportError> {
        let local = e.local_name();
        let local = local.as_ref();
        let Some(&parent) = self.stack.last() else {
            if self.seen_root {
                return Ok(None);
            }
            if local != "model" {
                return Err(parse_error(format!(
                    "the root element is <{local}>, not a 3MF <model>"
                )));
            }
            self.seen_root = true;
            let mut unit = None;
            attributes(e, |key, value| {
                if key == "unit" {
                    unit = Some(
                        FileUnit::parse(value)
                            .ok_or_else(|| parse_error(format!("unknown unit {value:?}")))?,
                    );
                }
                Ok(())
            })?;
            self.part.unit = unit;
            return Ok(Some(At::Model));
        };
        Ok(match (parent, local) {
            (At::Model, "resources") => Some(At::Resources),
            (At::Model, "build") => Some(At::Build),
            (At::Resources, "object") => {
                self.object = Some(object(e)?);
                Some(At::Object)
            }
            (At::Resources, "basematerials") => {
                let mut id = None;
                attributes(e, |key, value| {
                    if key == "id" {
                        id = Some(integer(value, "id")?);
                    }
                    Ok(())
                })?;
                let id = id.ok_or_else(|| missing("basematerials", "id"))?;
                self.group = Some((id, Vec::new()));
                Some(At::Materials)
            }
            (At::Object, "mesh") => Some(At::Mesh),
            (At::Object, "components") => Some(At::Components),
            (At::Mesh, "vertices") => Some(At::Vertices),
            (At::Mesh, "triangles") => Some(At::Triangles),
            (At::Vertices, "vertex") => {
                let p = vertex(e)?;
                if let Some(o) = &mut self.object {
                    o.positions.push(p);
                }
                None
            }
            (At::Triangles, "triangle") => {
                *self.faces = self.faces.saturating_add(1);
                if *self.faces > self.max_faces {
                    return Err(ImportError::TooLarge {
                        what: "faces in the file",
                        count: *self.faces as u64,
                        limit: self.max_faces as u64,
                    });
                }
                let t = triangle(e)?;
                if let Some(o) = &mut self.object {
                    o.triangles.push(t);
                }
                None
            }
            (At::Components, "component") => {
                let r = reference(e, "component")?;
                if let Some(o) = &mut self.object {
                    o.components.push(r);
                }
                None
            }
            (At::Build, "item") => {
                let r = reference(e, "item")?;
                self.part.build.push(r);
                None
            }
            (At::Materials, "base") => {
                let mut color = None;
                attributes(e, |key, value| {
                    if key == "displaycolor" {
                        color = display_color(value);
                    }
                    Ok(())
                })?;
                if let Some((_, bases)) = &mut self.group {
                    bases.push(color);
                }
                None
            }
            _ => None,
        })
    }

    /// An element that `open` descended into closes.
    fn close(&mut self, at: At) -> Result<(), ImportError> {
        match at {
            At::Object => {
                if let Some(o) = self.object.take() {
                    let index = self.part.objects.len();
                    if self.part.ids.insert(o.id, index).is_some() {
                        return Err(parse_error(format!(
                            "{}: two objects have id {}",
                            self.name, o.id
                        )));
                    }
                    self.part.objects.push(o);
                }
            }
            At::Materials => {
                if let Some((id, bases)) = self.group.take() {
                    self.part.materials.insert(id, bases);
                }
            }
            _ => {}
        }
        Ok(())
    }
}

/// Calls `f` with each of an element's attributes: its qualified name and its value
/// (entities replaced, white space normalized as XML asks).
fn attributes(
    e: &BytesStart<'_>,
    mut f: impl FnMut(&str, &str) -> Result<(), ImportError>,
) -> Result<(), ImportError> {
    for a in e.attributes() {
        let a = a.map_err(|err| parse_error(err.to_string()))?;
        let value = a
            .normalized_value(XmlVersion::Implicit1_0)
            .map_err(|err| parse_error(err.to_string()))?;
        f(a.key.0, &value)?;
    }
    Ok(())
}

fn missing(element: &str, attribute: &str) -> ImportError {
    parse_error(format!("a <{element}> has no {attribute} attribute"))
}

/// A non-negative integer attribute.
fn integer(value: &str, what: &str) -> Result<u64, ImportError> {
    value
        .trim()
        .parse::<u64>()
        .map_err(|_| parse_error(format!("{what} {value:?} is not a non-negative integer")))
}

/// A number attribute (any `f64` Rust parses, so a non-finite one passes through for the
/// caller to refuse with its place).
fn number(value: &str, what: &str) -> Result<f64, ImportError> {
    value
        .trim()
        .parse::<f64>()
        .map_err(|_| parse_error(format!("{what} {value:?} is not a number")))
}

fn object(e: &BytesStart<'_>) -> Result<Object, ImportError> {
    let mut o = Object {
        solid: true,
        ..Object::default()
    };
    let mut id = None;
    attributes(e, |key, value| {
        match key {
            "id" => id = Some(integer(value, "object id")?),
            "name" => o.name = Some(value.to_owned()),
            "partnumber" => o.partnumber = Some(value.to_owned()),
            "type" => o.solid = !matches!(value.trim(), "support" | "surface" | "other"),
            "pid" => o.pid = Some(integer(value, "pid")?),
            "pindex" => o.pindex = Some(integer(value, "pindex")?),
            _ => {}
        }
        Ok(())
    })?;
    o.id = id.ok_or_else(|| missing("object", "id"))?;
    Ok(o)
}

fn vertex(e: &BytesStart<'_>) -> Result<DVec3, ImportError> {
    let mut xyz = [None; 3];
    attributes(e, |key, value| {
        let k = match key {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => return Ok(()),
        };
        xyz[k] = Some(number(value, "a vertex coordinate")?);
        Ok(())
    })?;
    match xyz {
        [Some(x), Some(y), Some(z)] => Ok(DVec3::new(x, y, z)),
        _ => Err(parse_error("a <vertex> lacks one of x, y, z".into())),
    }
}

fn triangle(e: &BytesStart<'_>) -> Result<[u32; 3], ImportError> {
    let mut v = [None; 3];
    attributes(e, |key, value| {
        let k = match key {
            "v1" => 0,
            "v2" => 1,
            "v3" => 2,
            _ => return Ok(()),
        };
        // An index past u32::MAX names no vertex anyway (a part holds fewer); it is kept
        // out of range for the caller to report.
        let i = integer(value, "a vertex index")?;
        v[k] = Some(u32::try_from(i).unwrap_or(u32::MAX));
        Ok(())
    })?;
    match v {
        [Some(a), Some(b), Some(c)] => Ok([a, b, c]),
        _ => Err(parse_error("a <triangle> lacks one of v1, v2, v3".into())),
    }
}

fn reference(e: &BytesStart<'_>, element: &str) -> Result<Ref, ImportError> {
    let mut object = None;
    let mut transform = DAffine3::IDENTITY;
    let mut path = None;
    attributes(e, |key, value| {
        match key {
            "objectid" => object = Some(integer(value, "objectid")?),
            "transform" => transform = parse_transform(value)?,
            k if k == "path" || k.ends_with(":path") => path = Some(value.to_owned()),
            _ => {}
        }
        Ok(())
    })?;
    Ok(Ref {
        object: object.ok_or_else(|| missing(element, "objectid"))?,
        transform,
        path,
    })
}

/// A 3MF `transform`: twelve numbers `m00 m01 m02 m10 m11 m12 m20 m21 m22 m30 m31 m32`
/// for row vectors, `[x y z 1] · M`. Row `i` of the 3×3 part is the image of axis `i`, a
/// column of the column-vector matrix; the last row is the translation.
///
/// Refused unless there are exactly twelve finite numbers.
pub(super) fn parse_transform(value: &str) -> Result<DAffine3, ImportError> {
    let mut m = [0.0f64; 12];
    let mut n = 0;
    for word in value.split_ascii_whitespace() {
        if n == 12 {
            return Err(parse_error(format!(
                "transform {value:?} has more than 12 numbers"
            )));
        }
        let x = number(word, "a transform entry")?;
        if !x.is_finite() {
            return Err(parse_error(format!(
                "transform {value:?} has a non-finite entry"
            )));
        }
        m[n] = x;
        n += 1;
    }
    if n != 12 {
        return Err(parse_error(format!(
            "transform {value:?} has {n} numbers, not 12"
        )));
    }
    Ok(DAffine3 {
        matrix3: DMat3::from_cols(
            DVec3::new(m[0], m[1], m[2]),
            DVec3::new(m[3], m[4], m[5]),
            DVec3::new(m[6], m[7], m[8]),
        ),
        translation: DVec3::new(m[9], m[10], m[11]),
    })
}

/// `#RRGGBB` or `#RRGGBBAA` (alpha dropped); `None` for anything else.
pub(super) fn display_color(value: &str) -> Option<Color> {
    let hex = value.trim().strip_prefix('#')?;
    if !(hex.len() == 6 || hex.len() == 8) || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    let channel = |i: usize| u8::from_str_radix(hex.get(i..i + 2)?, 16).ok();
    Some(Color([channel(0)?, channel(2)?, channel(4)?]))
}
