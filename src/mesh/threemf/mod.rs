//! 3MF: reading a package's build into objects, writing solids as a package.
//!
//! A 3MF file is a zip package (Open Packaging Conventions) whose root model part,
//! named by `_rels/.rels` (usually `3D/3dmodel.model`), is XML: `resources` (objects,
//! each a triangle mesh or a list of components referring to other objects; base
//! materials) and a `build` of items, the objects to print, each with a transform.
//!
//! **Reading** ([`read`]). Only what the build reaches becomes objects (3MF prints build
//! items only). An item referring to a mesh object is one [`RawObject`]; an item referring
//! to a components object is flattened: one top-level object per mesh it reaches, with the
//! transforms on the way composed (no parent links: 3MF's components are instances, not
//! a parts tree). Components may refer to objects of other model parts (the production
//! extension's `p:path`). Each object's transform is split into a rigid pose (the
//! [`RawObject::pose`]) and a residual linear part (scale, shear, mirror) applied to its
//! positions; a mirror reverses each triangle. Objects of type `support`, `surface` or
//! `other` (not solids) and meshes without triangles are skipped. The name is the mesh
//! object's `name`, else its `partnumber`, else the nearest referring object's. The
//! colour is the object's `pid`/`pindex` base material's `displaycolor` (inherited the
//! same way). Vertices are numbered from 0 and triangles from 0 within each object.
//!
//! Units: [`Unit`] has no micron or foot, so a micron model is read as millimetres and a
//! foot model as inches, the coordinates (and translations) scaled by 1/1000 and 12. When
//! model parts declare different units, the others are scaled into the root part's.
//! When the caller names a unit ([`ImportOptions::unit`]), it overrides every declared
//! unit: nothing is scaled, and [`RawScene::unit`] is that unit.
//!
//! Poses and positions stay in the (root part's) file unit; the caller scales both.
//!
//! **Refusals before inflating.** The central directory's declared sizes of the parts to
//! be read (`_rels/.rels` and every `*.model` part) may add up to [`MAX_INFLATED`] bytes,
//! and a part larger than [`RATIO_FLOOR`] bytes may not declare more than [`MAX_RATIO`]
//! times its compressed size ([`ImportError::TooLarge`] either way, nothing inflated).
//! Since a declared size can lie, each part is then read through a reader that stops one
//! byte past its declared size, and refused (TooLarge) when that byte comes.
//! Triangles are counted as the XML is read, and refused past
//! [`ImportOptions::max_file_faces`]; so are the faces and vertices the build's
//! instances would hold (counted before any instance is built), which bounds what
//! components referring to one another many times could multiply.
//!
//! **Writing** ([`write`]): one `3D/3dmodel.model` part in metres, one object per solid
//! with its triangles ([`Solid::triangles`]) and a build item each, its colour as a base
//! material; coordinates are written in Rust's shortest round-trip form, so they read
//! back bit for bit.
//!
//! The `threemf` crate's `Model` types are not used: its deserializer matches elements by
//! local name, so its `m:basematerials` never matches the core `basematerials` (colours
//! would be lost); it has no `p:path`; and its writer names the model part
//! `3D/model.model`, which readers that look for `3D/3dmodel.model` (trimesh) miss.

mod model;
mod write;

#[cfg(test)]
mod tests;

use std::io::{Cursor, Read};

use glam::{DAffine3, DMat3, DQuat, DVec3};
use quick_xml::XmlVersion;
use quick_xml::events::Event;
use quick_xml::reader::Reader;
use zip::ZipArchive;

use super::{ImportError, ImportOptions, Map, Polygons, RawObject, RawScene, Unit};
use crate::model::{Color, Pose};
use model::{FileUnit, Part, Ref};

pub use write::write;

/// The most bytes the parts read from one package may inflate to (256 MiB).
pub const MAX_INFLATED: u64 = 64 * 1024 * 1024 * 4;

/// The most a part's declared size may exceed its compressed size, as a ratio, when it
/// is larger than [`RATIO_FLOOR`]. Deflate itself tops out near 1032:1, reached only
/// by long runs of one byte, which no honest model part holds.
pub const MAX_RATIO: u64 = 1000;

/// Parts up to this size (1 MiB) are not held to [`MAX_RATIO`].
pub const RATIO_FLOOR: u64 = 1024 * 1024;

/// The deepest chain of components followed from a build item; deeper (or a cycle) is
/// refused.
pub const MAX_COMPONENT_DEPTH: usize = 32;

/// The most objects a package's build may expand to (each mesh instance is one).
pub const MAX_OBJECTS: u64 = 100_000;

/// The relationship type of a package's root 3D model part.
const MODEL_RELATIONSHIP: &str = "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel";

/// A [`ImportError::Parse`] for 3MF.
fn parse_error(detail: String) -> ImportError {
    ImportError::Parse {
        format: "3mf",
        detail,
    }
}

/// Reads a 3MF package: the root model's build items as objects (see the module's
/// documentation for how components, transforms, units and colours are read).
///
/// Postconditions: every object is top-level (`parent: None`), its pose rigid and
/// finite, `first_vertex` `Some(0)`, `first_face` 0; triangle indices are as the file
/// gives them (an index too large for `u32` becomes `u32::MAX`), not checked against the
/// positions; [`RawScene::unit`] is the unit the coordinates are in.
///
/// Refused with [`ImportError::Parse`] when the bytes are not a zip package, the package
/// holds no model part (a zip without one is not a 3MF file), a part's XML is broken or
/// not a 3MF model, a reference names an object or part that is not there, components
/// nest deeper than [`MAX_COMPONENT_DEPTH`] (or in a cycle), or a transform is singular;
/// [`ImportError::TooLarge`] for a package that would inflate too far (see the module's
/// documentation) or holds more than `options.max_file_faces` triangles. A model whose
/// build is empty is an empty scene. Never panics.
pub fn read(bytes: &[u8], options: &ImportOptions) -> Result<RawScene, ImportError> {
    let mut zip = ZipArchive::new(Cursor::new(bytes)).map_err(|e| parse_error(e.to_string()))?;
    let package = Package::survey(&zip)?;
    let mut budget = Budget::default();

    // The root model part: named by the package's relationships, else by convention.
    let mut root = None;
    if let Some(rels) = package.rels {
        budget.declare(&package.entries[rels])?;
        let xml = budget.inflate(&mut zip, &package.entries[rels])?;
        if let Some(target) = root_target(text(&xml, &package.entries[rels].name)?)? {
            let name = part_name(&target);
            root = Some(package.find(name).ok_or_else(|| {
                parse_error(format!(
                    "the package's relationships name the model part {target:?}, which it does not hold"
                ))
            })?);
        }
    }
    let root = match root {
        Some(r) => r,
        None => package
            .find("3D/3dmodel.model")
            .or_else(|| package.models.first().copied())
            .ok_or_else(|| parse_error("the package holds no 3D model part".into()))?,
    };
    // Every part that may be read is declared before any is inflated.
    let mut to_read = package.models.clone();
    if !to_read.contains(&root) {
        to_read.push(root);
    }
    for m in to_read {
        budget.declare(&package.entries[m])?;
    }

    // Parts in the order they are reached: the root, then those referred to by path.
    let mut parts: Vec<Part> = Vec::new();
    let mut loaded: Map<usize, usize> = Map::default();
    let mut queue = vec![root];
    let mut faces = 0usize;
    while let Some(entry) = queue.pop() {
        if loaded.contains_key(&entry) {
            continue;
        }
        let e = &package.entries[entry];
        let xml = budget.inflate(&mut zip, e)?;
        let part = model::parse(
            text(&xml, &e.name)?,
            &e.name,
            &mut faces,
            options.max_file_faces,
        )?;
        drop(xml);
        for path in part.paths() {
            if let Some(i) = package.find(part_name(path)) {
                queue.push(i);
            }
        }
        loaded.insert(entry, parts.len());
        parts.push(part);
    }

    // Units: the root's (micron and foot as millimetres and inches), others scaled to it.
    let root_unit = parts[0].unit();
    let (unit, target_microns) = match options.unit {
        Some(u) => (u, None),
        None => {
            let u = match root_unit {
                FileUnit::Micron | FileUnit::Millimeter => Unit::Mm,
                FileUnit::Centimeter => Unit::Cm,
                FileUnit::Inch | FileUnit::Foot => Unit::In,
                FileUnit::Meter => Unit::M,
            };
            let microns = match u {
                Unit::Mm => 1e3,
                Unit::Cm => 1e4,
                Unit::In => 25_400.0,
                Unit::M => 1e6,
            };
            (u, Some(microns))
        }
    };
    if let Some(target) = target_microns {
        for part in &mut parts {
            let factor = part.unit().microns() / target;
            if factor != 1.0 {
                part.rescale(factor);
            }
        }
    }

    let scene = Scene {
        package: &package,
        parts: &parts,
        loaded: &loaded,
        root,
    };
    let objects = scene.flatten(options)?;
    Ok(RawScene {
        objects,
        unit: Some(unit),
    })
}

/// A package entry that may be read.
struct Entry {
    /// Its index in the zip.
    index: usize,
    /// Its name in the zip (no leading slash).
    name: String,
    /// Its declared inflated and compressed sizes.
    size: u64,
    compressed: u64,
}

/// The entries of a package that matter, from its central directory.
struct Package {
    entries: Vec<Entry>,
    /// `_rels/.rels`, if present (an index into `entries`).
    rels: Option<usize>,
    /// The `*.model` parts (indices into `entries`), in the zip's order.
    models: Vec<usize>,
    /// Each entry's name, ASCII lower-cased → its index into `entries` (the first of
    /// names that differ in case only).
    by_name: Map<String, usize>,
}

impl Package {
    fn survey(zip: &ZipArchive<Cursor<&[u8]>>) -> Result<Package, ImportError> {
        let mut package = Package {
            entries: Vec::new(),
            rels: None,
            models: Vec::new(),
            by_name: Map::default(),
        };
        for index in 0..zip.len() {
            let e = zip
                .by_index_data(index)
                .map_err(|e| parse_error(e.to_string()))?;
            let name = e
                .name()
                .map_err(|e| parse_error(e.to_string()))?
                .into_owned();
            if e.is_dir() {
                continue;
            }
            let is_rels = name.eq_ignore_ascii_case("_rels/.rels");
            let is_model = name.len() > ".model".len()
                && name
                    .get(name.len() - ".model".len()..)
                    .is_some_and(|end| end.eq_ignore_ascii_case(".model"));
            let k = package.entries.len();
            if is_rels {
                if package.rels.is_some() {
                    return Err(parse_error("the package has two _rels/.rels parts".into()));
                }
                package.rels = Some(k);
            } else if is_model {
                package.models.push(k);
            }
            package
                .by_name
                .entry(name.to_ascii_lowercase())
                .or_insert(k);
            package.entries.push(Entry {
                index,
                name,
                size: e.size(),
                compressed: e.compressed_size(),
            });
        }
        Ok(package)
    }

    /// The entry of part `name` (compared without regard to ASCII case, as OPC does).
    fn find(&self, name: &str) -> Option<usize> {
        self.by_name.get(&name.to_ascii_lowercase()).copied()
    }
}

/// A part name as a zip entry name: the leading `/` of an absolute OPC name dropped.
fn part_name(name: &str) -> &str {
    name.trim().trim_start_matches('/')
}

/// What may still be inflated from a package.
#[derive(Default)]
struct Budget {
    /// The declared sizes counted so far.
    declared: u64,
}

impl Budget {
    /// Counts an entry's declared size; refused when the total passes [`MAX_INFLATED`] or
    /// the entry's compression ratio passes [`MAX_RATIO`].
    fn declare(&mut self, e: &Entry) -> Result<(), ImportError> {
        self.declared = self.declared.saturating_add(e.size);
        if self.declared > MAX_INFLATED {
            return Err(ImportError::TooLarge {
                what: "bytes inflated from the 3MF package",
                count: self.declared,
                limit: MAX_INFLATED,
            });
        }
        if e.size > RATIO_FLOOR && e.size / MAX_RATIO >= e.compressed.max(1) {
            return Err(ImportError::TooLarge {
                what: "times inflation (declared over compressed size) of one 3MF part",
                count: e.size / e.compressed.max(1),
                limit: MAX_RATIO,
            });
        }
        Ok(())
    }

    /// Inflates an entry already declared. Precondition: its declared size was counted
    /// by [`Budget::declare`] (so it is at most [`MAX_INFLATED`]).
    ///
    /// Refused (TooLarge) when more comes out than the entry declares: reading stops one
    /// byte past it.
    fn inflate(
        &self,
        zip: &mut ZipArchive<Cursor<&[u8]>>,
        e: &Entry,
    ) -> Result<Vec<u8>, ImportError> {
        let too_large = |count: u64| ImportError::TooLarge {
            what: "bytes inflated from one 3MF part (more than its declared size)",
            count,
            limit: e.size,
        };
        let file = zip
            .by_index(e.index)
            .map_err(|err| parse_error(err.to_string()))?;
        let cap = e.size.min(MAX_INFLATED).saturating_add(1);
        // Room for what the part declares, but not more than its compressed bytes could
        // plausibly make (XML deflates some 5 to 20 times); the rest grows as it comes.
        let room = cap.min(e.compressed.saturating_mul(32).saturating_add(1 << 16));
        let mut buf = Vec::with_capacity(usize::try_from(room).unwrap_or(0));
        match file.take(cap).read_to_end(&mut buf) {
            Ok(_) if buf.len() as u64 > e.size => Err(too_large(buf.len() as u64)),
            Ok(_) => Ok(buf),
            // The zip reader itself stops at the declared size (with this message).
            Err(err) if err.to_string().contains("larger than its declared") => {
                Err(too_large(e.size.saturating_add(1)))
            }
            Err(err) => Err(parse_error(format!("{}: {err}", e.name))),
        }
    }
}

/// A part's bytes as text (UTF-8, a byte-order mark dropped).
fn text<'a>(bytes: &'a [u8], name: &str) -> Result<&'a str, ImportError> {
    let s =
        std::str::from_utf8(bytes).map_err(|e| parse_error(format!("{name} is not UTF-8: {e}")))?;
    Ok(s.strip_prefix('\u{feff}').unwrap_or(s))
}

/// The target of the package relationship to the root 3D model, if there is one.
fn root_target(xml: &str) -> Result<Option<String>, ImportError> {
    let mut reader = Reader::from_str(xml);
    loop {
        match reader.read_event() {
            Err(e) => return Err(parse_error(format!("_rels/.rels: {e}"))),
            Ok(Event::Eof) => return Ok(None),
            Ok(Event::Start(e) | Event::Empty(e)) if e.local_name().as_ref() == "Relationship" => {
                let (mut kind, mut target) = (None, None);
                for a in e.attributes() {
                    let a = a.map_err(|err| parse_error(format!("_rels/.rels: {err}")))?;
                    let value = a
                        .normalized_value(XmlVersion::Implicit1_0)
                        .map_err(|err| parse_error(format!("_rels/.rels: {err}")))?;
                    match a.key.0 {
                        "Type" => kind = Some(value.trim().to_owned()),
                        "Target" => target = Some(value.into_owned()),
                        _ => {}
                    }
                }
                if kind.as_deref() == Some(MODEL_RELATIONSHIP)
                    && let Some(t) = target
                {
                    return Ok(Some(t));
                }
            }
            Ok(_) => {}
        }
    }
}

/// The parsed parts, for following references.
struct Scene<'a> {
    package: &'a Package,
    parts: &'a [Part],
    /// Package entry → index into `parts`.
    loaded: &'a Map<usize, usize>,
    /// The root part's entry.
    root: usize,
}

/// What the instances an object reaches hold (saturating counts).
#[derive(Clone, Copy, Default)]
struct Tally {
    /// Triangles.
    faces: u64,
    /// Vertices.
    vertices: u64,
    /// Meshes with triangles, each one [`RawObject`].
    objects: u64,
}

impl Tally {
    fn add(self, o: Tally) -> Tally {
        Tally {
            faces: self.faces.saturating_add(o.faces),
            vertices: self.vertices.saturating_add(o.vertices),
            objects: self.objects.saturating_add(o.objects),
        }
    }
}

impl Scene<'_> {
    /// The part and object `r` (made in part `from`) refers to.
    fn resolve(&self, from: usize, r: &Ref) -> Result<(usize, usize), ImportError> {
        let part = match &r.path {
            None => from,
            Some(path) => self
                .package
                .find(part_name(path))
                .and_then(|entry| self.loaded.get(&entry).copied())
                .ok_or_else(|| {
                    parse_error(format!(
                        "a reference names the part {path:?}, which the package does not hold"
                    ))
                })?,
        };
        let object = self.parts[part]
            .ids
            .get(&r.object)
            .copied()
            .ok_or_else(|| {
                parse_error(format!(
                    "a reference names object {} of {}, which it does not define",
                    r.object,
                    self.package.entries[self.entry(part)].name
                ))
            })?;
        Ok((part, object))
    }

    /// The package entry of part `part`.
    fn entry(&self, part: usize) -> usize {
        self.loaded
            .iter()
            .find(|&(_, &p)| p == part)
            .map_or(self.root, |(&e, _)| e)
    }

    /// The faces and vertices every instance of object `(part, object)` holds, memoised.
    fn tally(
        &self,
        part: usize,
        object: usize,
        depth: usize,
        memo: &mut Map<(usize, usize), Tally>,
    ) -> Result<Tally, ImportError> {
        if let Some(&t) = memo.get(&(part, object)) {
            return Ok(t);
        }
        if depth > MAX_COMPONENT_DEPTH {
            return Err(too_deep());
        }
        let o = &self.parts[part].objects[object];
        let mut t = Tally::default();
        if o.solid {
            if !o.triangles.is_empty() {
                t.faces = o.triangles.len() as u64;
                t.vertices = o.positions.len() as u64;
                t.objects = 1;
            }
            for c in &o.components {
                let (p, k) = self.resolve(part, c)?;
                t = t.add(self.tally(p, k, depth + 1, memo)?);
            }
        }
        memo.insert((part, object), t);
        Ok(t)
    }

    /// The build's objects, refused before any is built when they would hold too much.
    fn flatten(&self, options: &ImportOptions) -> Result<Vec<RawObject>, ImportError> {
        let root = &self.parts[0];
        let mut memo = Map::default();
        let mut total = Tally::default();
        let mut items = Vec::with_capacity(root.build.len());
        for item in &root.build {
            let (p, k) = self.resolve(0, item)?;
            total = total.add(self.tally(p, k, 0, &mut memo)?);
            items.push((p, k));
        }
        let limit = options.max_file_faces as u64;
        if total.faces > limit {
            return Err(ImportError::TooLarge {
                what: "faces in the file (its build's instances)",
                count: total.faces,
                limit,
            });
        }
        // A mesh uses at most three vertices per triangle; more are dead weight that
        // instances would copy.
        let vertex_limit = limit.saturating_mul(3).saturating_add(3);
        if total.vertices > vertex_limit {
            return Err(ImportError::TooLarge {
                what: "vertices in the file (its build's instances)",
                count: total.vertices,
                limit: vertex_limit,
            });
        }
        if total.objects > MAX_OBJECTS {
            return Err(ImportError::TooLarge {
                what: "objects in the file (its build's instances)",
                count: total.objects,
                limit: MAX_OBJECTS,
            });
        }
        let mut out = Vec::with_capacity(total.objects as usize);
        for (item, &(p, k)) in root.build.iter().zip(&items) {
            self.expand(p, k, item.transform, 0, None, None, &memo, &mut out)?;
        }
        Ok(out)
    }

    /// Appends the objects `(part, object)` (at `depth` below a build item) reaches,
    /// placed by `transform`, with the name and colour they inherit. Precondition:
    /// [`Scene::tally`] has counted every object reached (in `memo`). Objects that reach
    /// no triangle are not entered, so the work is bounded by the objects made times
    /// [`MAX_COMPONENT_DEPTH`]; the depth is checked here on every path (the memoised
    /// tally sees each object once only).
    #[allow(clippy::too_many_arguments)]
    fn expand(
        &self,
        part: usize,
        object: usize,
        transform: DAffine3,
        depth: usize,
        name: Option<&str>,
        color: Option<Color>,
        memo: &Map<(usize, usize), Tally>,
        out: &mut Vec<RawObject>,
    ) -> Result<(), ImportError> {
        if memo.get(&(part, object)).is_none_or(|t| t.objects == 0) {
            return Ok(());
        }
        if depth > MAX_COMPONENT_DEPTH {
            return Err(too_deep());
        }
        let o = &self.parts[part].objects[object];
        let name = o.name.as_deref().or(o.partnumber.as_deref()).or(name);
        let color = self.color(part, o).or(color);
        if !o.triangles.is_empty() {
            let placed = place(&transform, &o.positions, &o.triangles)?;
            out.push(RawObject {
                name: name.map(str::to_owned),
                parent: None,
                pose: placed.pose,
                color,
                positions: placed.positions,
                faces: placed.faces,
                first_vertex: Some(0),
                first_face: 0,
            });
        }
        for c in &o.components {
            let (p, k) = self.resolve(part, c)?;
            self.expand(
                p,
                k,
                transform * c.transform,
                depth + 1,
                name,
                color,
                memo,
                out,
            )?;
        }
        Ok(())
    }

    /// An object's own colour: its `pid`/`pindex` base material's display colour.
    fn color(&self, part: usize, o: &model::Object) -> Option<Color> {
        let bases = self.parts[part].materials.get(&o.pid?)?;
        let index = usize::try_from(o.pindex.unwrap_or(0)).ok()?;
        bases.get(index).copied().flatten()
    }
}

fn too_deep() -> ImportError {
    parse_error(format!(
        "components nest more than {MAX_COMPONENT_DEPTH} deep (or refer to themselves)"
    ))
}

/// A mesh placed by a transform: the rigid pose, and the positions and faces with the
/// rest of the transform applied.
struct Placed {
    pose: Pose,
    positions: Vec<DVec3>,
    faces: Polygons,
}

/// Splits `transform` into a rigid pose and a residual linear map applied to
/// `positions` (see [`decompose`]); triangles are reversed when it mirrors.
fn place(
    transform: &DAffine3,
    positions: &[DVec3],
    triangles: &[[u32; 3]],
) -> Result<Placed, ImportError> {
    let (pose, residual) = decompose(transform)?;
    let positions = match residual {
        None => positions.to_vec(),
        Some(s) => positions.iter().map(|&p| s * p).collect(),
    };
    let mirror = residual.is_some_and(|s| s.determinant() < 0.0);
    let mut faces = Polygons::with_capacity(triangles.len(), 3 * triangles.len());
    for &[a, b, c] in triangles {
        faces.push(&if mirror { [a, c, b] } else { [a, b, c] });
    }
    Ok(Placed {
        pose,
        positions,
        faces,
    })
}

/// How far from orthonormal (largest entry of `MᵀM − I`) a 3×3 part may be and still be
/// taken as the rotation it nearly is.
const ROTATION_TOLERANCE: f64 = 1e-9;

/// Splits an affine map `x ↦ L x + t` into a rigid pose `x ↦ R x + t` and a residual
/// `S = Rᵀ L` (so `L = R S`): `None` when `L` is a rotation within
/// [`ROTATION_TOLERANCE`] (then `R` is `L` itself and the positions are left as they are),
/// else the polar decomposition's factor, symmetric, negative definite when `L` mirrors
/// (`R` is then the polar factor negated, a proper rotation).
///
/// Refused (Parse) when `L` is singular (or nearly: `|det L|` within 1e-12 of the cube
/// of its largest entry) or not finite.
fn decompose(transform: &DAffine3) -> Result<(Pose, Option<DMat3>), ImportError> {
    let l = transform.matrix3;
    let t = transform.translation;
    let det = l.determinant();
    let largest = l.abs().to_cols_array().into_iter().fold(0.0, f64::max);
    let singular = || parse_error("a transform is singular (it flattens its object)".into());
    if !det.is_finite() || !t.is_finite() || det.abs() <= 1e-12 * largest.powi(3) {
        return Err(singular());
    }
    if det > 0.0 && off_orthonormal(&l) <= ROTATION_TOLERANCE {
        let rotation = DQuat::from_mat3(&l).normalize();
        let pose = Pose::new(t, rotation).map_err(|_| singular())?;
        return Ok((pose, None));
    }
    // Higham's iteration Q ← (Q + Q⁻ᵀ)/2 converges (quadratically) to the orthogonal
    // polar factor of a nonsingular matrix.
    let mut q = l;
    for _ in 0..100 {
        let next = (q + q.inverse().transpose()) * 0.5;
        let step = frobenius(&(next - q));
        q = next;
        if !q.is_finite() {
            return Err(singular());
        }
        if step <= 1e-15 * frobenius(&q) {
            break;
        }
    }
    if off_orthonormal(&q) > ROTATION_TOLERANCE {
        return Err(singular());
    }
    let r = if det < 0.0 { -q } else { q };
    let rotation = DQuat::from_mat3(&r).normalize();
    let pose = Pose::new(t, rotation).map_err(|_| singular())?;
    // The residual is taken against the rotation the pose holds, so that R S = L as
    // nearly as rounding allows.
    let residual = DMat3::from_quat(pose.rotation).transpose() * l;
    Ok((pose, Some(residual)))
}

/// The largest entry of `MᵀM − I`.
fn off_orthonormal(m: &DMat3) -> f64 {
    (m.transpose() * *m - DMat3::IDENTITY)
        .abs()
        .to_cols_array()
        .into_iter()
        .fold(0.0, f64::max)
}

fn frobenius(m: &DMat3) -> f64 {
    m.to_cols_array().iter().map(|x| x * x).sum::<f64>().sqrt()
}
