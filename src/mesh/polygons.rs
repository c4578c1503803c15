//! From a file's objects to bodies: weld, check, merge coplanar faces, split pieces.
//!
//! For each object of a [`RawScene`], in order:
//!
//! 1. **Units**: loci (and pose translations) are scaled to meters.
//! 2. **Checks on the list**: every coordinate finite, every index in range.
//! 3. **Weld**: vertices with equal coordinates (or, with `weld` > 0, within that
//!    distance of an earlier one) become one vertex.
//! 4. **Faces**: a face that lists a vertex twice after welding, or has no area, is
//!    degenerate.
//! 5. **Edges**: every edge must have exactly two faces, running along it in opposite
//!    directions; else the surface is open, non-manifold or inconsistently oriented.
//! 6. **Pieces**: faces joined by edges form pieces; each becomes one body (a body is
//!    one connected polyhedron).
//! 7. **Crossings**: no two faces of a piece may meet away from the vertices and edges
//!    they share (exact tests, [`crate::model::boolean::crossing`]).
//! 8. **Merge** (when asked): faces joined by edges whose normals are within
//!    [`MERGE_ANGLE`] of a seed face's and whose vertices lie within the tolerance of its
//!    plane become one polygon face, the seeds taken largest first. A region whose
//!    outline is not one simple ring (a face with a hole, or two faces touching at a
//!    corner) is not merged: its faces stay as they are, counted in
//!    [`MeshBody::unmerged`], since a winged-edge face is one ring and a hole is not
//!    faked with a bridge.
//! 9. **Build**: the polygons must make a valid closed polyhedron
//!    ([`Body::from_polygons`], then [`check_solid`]).
//!
//! Every refusal is an [`ImportError::Invalid`] naming the object and the faces and
//! vertices in the file's own numbering.

use glam::DVec3;
use unicode_normalization::UnicodeNormalization;

use super::error::{Defect, Where};
use super::{ImportError, ImportOptions, Map, Polygons, RawObject, RawScene, Unit};
use rayon::prelude::*;

use crate::model::boolean::crossing::Crossings;
use crate::model::parts::validate_name;
use crate::model::solids::BuildError;
use crate::model::triangulate::FaceTriangulator;
use crate::model::{Body, Built, Color, Pose, WorldError, check_solid};

/// The largest angle between a merged face's normal and the normal of a face merged
/// into it: 1°.
pub const MERGE_ANGLE: f64 = std::f64::consts::PI / 180.0;

/// The planarity tolerance the finished bodies are checked with, as a fraction of the
/// piece's bounding-box diagonal (loose enough for f32 files, whose faces merged within
/// [`ImportOptions::coplanar_tolerance`] stay within it).
const SOLID_TOLERANCE: f64 = 1e-5;

/// One body made from a file.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshBody {
    /// Its name (the object's, checked as a body name; a second piece of an object gets
    /// `name.2`, and so on).
    pub name: Option<String>,
    /// The body it is a part of, an index into [`Imported::bodies`] (lower than its own).
    pub parent: Option<usize>,
    /// Its pose in its parent's frame (in the world's, at the top level).
    pub pose: Pose,
    /// Its colour.
    pub color: Option<Color>,
    /// Vertex loci in meters, in the file's order (vertices only inside merged faces
    /// dropped).
    pub positions: Vec<DVec3>,
    /// Polygon faces, counter-clockwise seen from outside.
    pub faces: Polygons,
    /// The object of the file it came from (an index into [`RawScene::objects`]).
    pub object: usize,
    /// How many of the file's faces it was made from.
    pub faces_read: usize,
    /// Coplanar regions left unmerged because their outline is not one ring.
    pub unmerged: usize,
}

/// The bodies a file made.
#[derive(Clone, Debug, Default)]
pub struct Imported {
    /// The bodies, parents before their parts.
    pub bodies: Vec<MeshBody>,
    /// Each body built from its polygons and checked, numbered for a world whose next
    /// serial is 1 (see [`Built`]): what inserting them takes, so that the world's
    /// owner need not build them again.
    pub built: Vec<Built>,
}

impl PartialEq for Imported {
    /// The same bodies (the built ones follow from them).
    fn eq(&self, other: &Self) -> bool {
        self.bodies == other.bodies
    }
}

/// Why a piece did not build: the builder's refusal, or the world's checks of the loci.
enum Refusal {
    Build(BuildError),
    World(WorldError),
}

impl From<WorldError> for Refusal {
    fn from(e: WorldError) -> Self {
        Refusal::World(e)
    }
}

/// Makes bodies of `scene`'s objects (see the module's steps).
///
/// Refused with [`ImportError::Empty`] when no object has a face, and
/// [`ImportError::Invalid`] (naming the object, faces and vertices) for the first
/// object whose surface is not a closed polyhedron. Postcondition: each body's
/// polygons pass [`Body::from_polygons`] and [`check_solid`].
pub fn bodies(scene: RawScene, options: &ImportOptions) -> Result<Imported, ImportError> {
    if scene.face_count() == 0 {
        return Err(ImportError::Empty);
    }
    let scale = options.unit.or(scene.unit).unwrap_or(Unit::M).meters();
    let mut out = Imported::default();
    // The body each object became (its first piece), or the one its parent became.
    let mut body_of: Vec<Option<usize>> = Vec::with_capacity(scene.objects.len());
    // Each object's frame in the frame of the body it hangs under: the identity for an
    // object that became a body, its pose composed down from there for one without
    // faces (whose parts then hang under that body with the poses composed).
    let mut carry: Vec<Pose> = Vec::with_capacity(scene.objects.len());
    let mut names: Map<String, usize> = Map::default();
    for (index, object) in scene.objects.iter().enumerate() {
        let parent = object
            .parent
            .and_then(|p| body_of.get(p).copied().flatten());
        let base = object
            .parent
            .and_then(|p| carry.get(p).copied())
            .unwrap_or(Pose::IDENTITY);
        let mut own = object.pose;
        own.position *= scale;
        let placed = base.compose(&own);
        if object.faces.is_empty() {
            body_of.push(parent);
            carry.push(placed);
            continue;
        }
        carry.push(Pose::IDENTITY);
        let pieces = pieces(index, object, scale, options)?;
        let first = out.bodies.len();
        body_of.push(Some(first));
        let name = object.name.as_deref().and_then(clean_name);
        for (k, piece) in pieces.into_iter().enumerate() {
            let name = name.as_ref().map(|n| {
                let base = if k == 0 {
                    n.clone()
                } else {
                    format!("{n}.{}", k + 1)
                };
                unique(&mut names, base)
            });
            let (parent, pose) = if k == 0 {
                (parent, placed)
            } else {
                (Some(first), Pose::IDENTITY)
            };
            out.bodies.push(MeshBody {
                name,
                parent,
                pose,
                color: object.color,
                positions: piece.positions,
                faces: piece.faces,
                object: index,
                faces_read: piece.faces_read,
                unmerged: piece.unmerged,
            });
            out.built.push(piece.built);
        }
    }
    Ok(out)
}

/// `name` in normalization form C if it is a valid body name, else `None`.
fn clean_name(name: &str) -> Option<String> {
    let name: String = name.trim().nfc().collect();
    validate_name(&name).is_ok().then_some(name)
}

/// `base`, or `base.2`, `base.3`, ... if taken by an earlier body of the file.
fn unique(names: &mut Map<String, usize>, base: String) -> String {
    let count = names.entry(base.clone()).or_insert(0);
    *count += 1;
    if *count == 1 {
        return base;
    }
    let mut k = *count;
    loop {
        let candidate = format!("{base}.{k}");
        if !names.contains_key(&candidate) {
            names.insert(candidate.clone(), 1);
            return candidate;
        }
        k += 1;
    }
}

/// One connected piece of an object, built.
struct Piece {
    positions: Vec<DVec3>,
    faces: Polygons,
    faces_read: usize,
    unmerged: usize,
    built: Built,
}

/// The object's surface as welded faces with their edges matched.
struct Surface<'a> {
    object: &'a RawObject,
    index: usize,
    /// Loci in meters, one per raw vertex.
    points: Vec<DVec3>,
    /// Each raw vertex's representative after welding.
    rep: Vec<u32>,
    /// Faces in representatives.
    faces: Polygons,
    /// The face of each half-edge (half-edge `h` of face `f` is `ends[f-1] + k`).
    face_of: Vec<u32>,
    /// Each half-edge's twin.
    twin: Vec<u32>,
}

impl Surface<'_> {
    /// Where raw vertices `vs` and faces `fs` are, in the file's numbering.
    fn at(&self, fs: &[usize], vs: &[u32]) -> Box<Where> {
        let o = self.object;
        Box::new(Where {
            object: self.index,
            name: o.name.clone(),
            faces: fs.iter().map(|&f| o.first_face + f as u64).collect(),
            vertices: match o.first_vertex {
                Some(first) => vs.iter().map(|&v| first + u64::from(v)).collect(),
                None => Vec::new(),
            },
            points: vs
                .iter()
                .filter_map(|&v| o.positions.get(v as usize))
                .map(|p| p.to_array())
                .collect(),
        })
    }

    fn invalid(&self, defect: Defect, fs: &[usize], vs: &[u32], detail: String) -> ImportError {
        ImportError::Invalid {
            defect,
            at: self.at(fs, vs),
            detail,
        }
    }

    /// Half-edge `h`'s start vertex (a representative).
    fn start(&self, h: usize) -> u32 {
        self.faces.corners[h]
    }

    /// The half-edge after `h` in its face.
    fn next(&self, h: usize) -> usize {
        let f = self.face_of[h] as usize;
        let end = self.faces.ends[f] as usize;
        if h + 1 == end {
            if f == 0 {
                0
            } else {
                self.faces.ends[f - 1] as usize
            }
        } else {
            h + 1
        }
    }

    /// The range of face `f`'s half-edges.
    fn half_edges(&self, f: usize) -> std::ops::Range<usize> {
        let start = if f == 0 {
            0
        } else {
            self.faces.ends[f - 1] as usize
        };
        start..self.faces.ends[f] as usize
    }
}

/// Checks object `index` and cuts it into buildable pieces.
fn pieces(
    index: usize,
    object: &RawObject,
    scale: f64,
    options: &ImportOptions,
) -> Result<Vec<Piece>, ImportError> {
    let mut s = Surface {
        object,
        index,
        points: Vec::new(),
        rep: Vec::new(),
        faces: Polygons::default(),
        face_of: Vec::new(),
        twin: Vec::new(),
    };
    let clock = std::time::Instant::now();
    let lap = |stage: &str| {
        tracing::debug!(
            object = index,
            stage,
            ms = clock.elapsed().as_secs_f64() * 1e3,
            "mesh import"
        );
    };
    // 1–2. Units, finite numbers, indices.
    if let Some(v) = object.positions.iter().position(|p| !p.is_finite()) {
        return Err(s.invalid(Defect::NotFinite, &[], &[v as u32], String::new()));
    }
    s.points = if scale == 1.0 {
        object.positions.clone()
    } else {
        object.positions.iter().map(|&p| p * scale).collect()
    };
    let n = object.positions.len();
    for (f, face) in object.faces.iter().enumerate() {
        if let Some(&bad) = face.iter().find(|&&i| i as usize >= n) {
            return Err(s.invalid(
                Defect::BadIndex,
                &[f],
                &[],
                format!("it names vertex index {bad}, but the object has {n} vertices"),
            ));
        }
    }
    // 3. Weld.
    s.rep = weld(&s.points, options.weld);
    lap("welded");
    // 4. Faces, in representatives; degenerate ones refused.
    s.faces = Polygons::with_capacity(object.faces.len(), object.faces.corners.len());
    let mut face = Vec::new();
    for (f, raw) in object.faces.iter().enumerate() {
        face.clear();
        face.extend(raw.iter().map(|&v| s.rep[v as usize]));
        if face.len() < 3 {
            return Err(s.invalid(
                Defect::Degenerate,
                &[f],
                raw,
                format!("it has {} vertices; a face needs three", face.len()),
            ));
        }
        if let Some(k) = repeated(&face) {
            return Err(s.invalid(
                Defect::Degenerate,
                &[f],
                &[raw[k]],
                "it lists one vertex twice (after welding)".into(),
            ));
        }
        let (normal, longest) = newell_and_longest(&s.points, &face);
        if normal.length() <= 1e-12 * longest * longest {
            return Err(s.invalid(Defect::Degenerate, &[f], raw, "it has no area".into()));
        }
        s.faces.push(&face);
    }
    lap("faces checked");
    // 5. Edges.
    match_edges(&mut s)?;
    lap("edges matched");
    // 6. Pieces.
    let piece_of = components(&s);
    let count = piece_of.iter().map(|&p| p as usize + 1).max().unwrap_or(0);
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); count];
    for (f, &p) in piece_of.iter().enumerate() {
        members[p as usize].push(f as u32);
    }
    let mut out = Vec::with_capacity(count);
    for faces in &members {
        // 7–9. The crossing test beside merging and building: all three only read the
        // surface, and the build is kept only if nothing crosses.
        let (crossed, built) = rayon::join(
            || {
                if options.check_crossings {
                    check_crossings(&s, faces)
                } else {
                    Ok(())
                }
            },
            || {
                let (polygons, unmerged) = if options.merge_coplanar {
                    let (polygons, unmerged) = merge(&s, faces, options.coplanar_tolerance);
                    (
                        drop_collinear(&s, polygons, options.coplanar_tolerance),
                        unmerged,
                    )
                } else {
                    (faces.iter().map(|&f| Ring::Face(f)).collect(), 0)
                };
                lap("faces merged");
                if polygons.len() > options.max_faces {
                    return Err(ImportError::TooLarge {
                        what: "faces in one body",
                        count: polygons.len() as u64,
                        limit: options.max_faces as u64,
                    });
                }
                let built = build(&s, faces, &polygons, unmerged);
                lap("built");
                built
            },
        );
        crossed?;
        lap("crossings checked");
        out.push(built?);
    }
    Ok(out)
}

/// Each vertex's representative: the first vertex with its coordinates (`tol` = 0) or
/// within `tol` of it (a grid of cells `tol` wide; the first representative found in
/// the 27 cells about a vertex wins).
fn weld(points: &[DVec3], tol: f64) -> Vec<u32> {
    let mut rep = Vec::with_capacity(points.len());
    if tol > 0.0 && tol.is_finite() {
        let cell = |p: DVec3| (p / tol).floor().as_i64vec3().to_array();
        let mut grid: Map<[i64; 3], Vec<u32>> = Map::default();
        for (i, &p) in points.iter().enumerate() {
            let c = cell(p);
            let mut found = None;
            'search: for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let key = [c[0] + dx, c[1] + dy, c[2] + dz];
                        if let Some(list) = grid.get(&key) {
                            for &r in list {
                                if points[r as usize].distance(p) <= tol {
                                    found = Some(r);
                                    break 'search;
                                }
                            }
                        }
                    }
                }
            }
            let r = found.unwrap_or_else(|| {
                grid.entry(c).or_default().push(i as u32);
                i as u32
            });
            rep.push(r);
        }
    } else {
        let mut seen: Map<[u64; 3], u32> = Map::default();
        seen.reserve(points.len());
        for (i, &p) in points.iter().enumerate() {
            // -0.0 and 0.0 are one coordinate.
            let key = (p + DVec3::ZERO).to_array().map(f64::to_bits);
            rep.push(*seen.entry(key).or_insert(i as u32));
        }
    }
    rep
}

/// The position of a vertex listed a second time in `face`, if any.
fn repeated(face: &[u32]) -> Option<usize> {
    if face.len() <= 8 {
        return (1..face.len()).find(|&k| face[..k].contains(&face[k]));
    }
    let mut seen: Map<u32, ()> = Map::default();
    face.iter().position(|&v| seen.insert(v, ()).is_some())
}

/// The Newell normal (twice the vector area) of a face and its longest side.
fn newell_and_longest(points: &[DVec3], face: &[u32]) -> (DVec3, f64) {
    let mut n = DVec3::ZERO;
    let mut longest: f64 = 0.0;
    let origin = points[face[0] as usize];
    for k in 0..face.len() {
        let p = points[face[k] as usize] - origin;
        let q = points[face[(k + 1) % face.len()] as usize] - origin;
        n += p.cross(q);
        longest = longest.max(p.distance(q));
    }
    (n, longest)
}

/// Matches each half-edge with the one running the other way along the same edge.
fn match_edges(s: &mut Surface<'_>) -> Result<(), ImportError> {
    let nh = s.faces.corners.len();
    s.face_of = Vec::with_capacity(nh);
    for f in 0..s.faces.len() {
        let len = s.half_edges(f).len();
        s.face_of.extend(std::iter::repeat_n(f as u32, len));
    }
    // Half-edges ordered by edge (lower end, then higher end): a counting sort on the
    // lower end, then each vertex's few half-edges sorted in place.
    let key = |h: usize| {
        let (a, b) = (s.start(h), s.start(s.next(h)));
        (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
    };
    let nv = s.points.len();
    let mut at = vec![0u32; nv + 1];
    for h in 0..nh {
        at[(key(h) >> 32) as usize + 1] += 1;
    }
    for v in 0..nv {
        at[v + 1] += at[v];
    }
    let mut keyed: Vec<(u64, u32)> = vec![(0, 0); nh];
    let mut fill = at.clone();
    for h in 0..nh {
        let k = key(h);
        let slot = &mut fill[(k >> 32) as usize];
        keyed[*slot as usize] = (k, h as u32);
        *slot += 1;
    }
    drop(fill);
    for v in 0..nv {
        keyed[at[v] as usize..at[v + 1] as usize].sort_unstable();
    }
    s.twin = vec![u32::MAX; nh];
    let mut i = 0;
    let mut problem: Option<(Defect, usize, usize)> = None;
    let mut counts = [0usize; 3];
    while i < keyed.len() {
        let mut j = i + 1;
        while j < keyed.len() && keyed[j].0 == keyed[i].0 {
            j += 1;
        }
        let group = &keyed[i..j];
        let defect = match group.len() {
            1 => Some((Defect::Open, 0)),
            2 => {
                let (h, g) = (group[0].1 as usize, group[1].1 as usize);
                if s.start(h) == s.start(g) {
                    Some((Defect::InconsistentOrientation, 2))
                } else {
                    s.twin[h] = g as u32;
                    s.twin[g] = h as u32;
                    None
                }
            }
            _ => Some((Defect::NonManifoldEdge, 1)),
        };
        if let Some((d, slot)) = defect {
            counts[slot] += 1;
            if problem.is_none() {
                problem = Some((d, i, j));
            }
        }
        i = j;
    }
    let Some((defect, i, j)) = problem else {
        return Ok(());
    };
    let group = &keyed[i..j];
    let h = group[0].1 as usize;
    let (a, b) = (s.start(h), s.start(s.next(h)));
    let mut faces: Vec<usize> = group
        .iter()
        .map(|&(_, h)| s.face_of[h as usize] as usize)
        .collect();
    faces.dedup();
    let how_many = |n: usize, what: &str| {
        if n == 1 {
            format!("1 {what}")
        } else {
            format!("{n} {what}s; the first")
        }
    };
    let detail = match defect {
        Defect::Open => format!("{} belongs to one face only", how_many(counts[0], "edge")),
        Defect::NonManifoldEdge => format!(
            "{} is shared by {} faces",
            how_many(counts[1], "edge"),
            group.len()
        ),
        _ => format!(
            "{} is run along in the same direction by both its faces",
            how_many(counts[2], "edge")
        ),
    };
    Err(s.invalid(defect, &faces, &[a, b], detail))
}

/// Each face's piece: faces joined by matched edges, numbered in the order of their
/// lowest face.
fn components(s: &Surface<'_>) -> Vec<u32> {
    let nf = s.faces.len();
    let mut parent: Vec<u32> = (0..nf as u32).collect();
    fn root(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    for h in 0..s.twin.len() {
        let (f, g) = (s.face_of[h], s.face_of[s.twin[h] as usize]);
        let (x, y) = (root(&mut parent, f), root(&mut parent, g));
        if x != y {
            parent[x.max(y) as usize] = x.min(y);
        }
    }
    let mut number: Map<u32, u32> = Map::default();
    (0..nf as u32)
        .map(|f| {
            let r = root(&mut parent, f);
            let next = number.len() as u32;
            *number.entry(r).or_insert(next)
        })
        .collect()
}

/// Refuses a piece two of whose faces cross (its faces cut into triangles of their own
/// corners for the test).
fn check_crossings(s: &Surface<'_>, faces: &[u32]) -> Result<(), ImportError> {
    let mut triangles = Vec::with_capacity(faces.len());
    let mut owner = Vec::with_capacity(faces.len());
    let mut ear = FaceTriangulator::new();
    let mut tris = Vec::new();
    for &f in faces {
        let face = s.faces.face(f as usize);
        if face.len() == 3 {
            triangles.push([face[0], face[1], face[2]]);
            owner.push(f);
            continue;
        }
        let (normal, _) = newell_and_longest(&s.points, face);
        ear.triangulate(&s.points, face, normal.normalize(), &mut tris);
        for t in &tris {
            triangles.push(*t);
            owner.push(f);
        }
    }
    // Triangles of one face share its plane and never cross. The search runs in
    // chunks on rayon's threads; the least pair found wins, as a single search would.
    let index = Crossings::new(&s.points, &triangles);
    let parts = index.parts(64 * rayon::current_num_threads());
    let found = parts
        .into_par_iter()
        .filter_map(|part| index.first_in(part, |i, j| owner[i] == owner[j]))
        .min();
    if let Some((i, j)) = found {
        let (f, g) = (owner[i] as usize, owner[j] as usize);
        return Err(s.invalid(
            Defect::SelfIntersection,
            &[f, g],
            &[],
            "two faces meet away from the vertices and edges they share".into(),
        ));
    }
    Ok(())
}

/// One face of a piece after merging.
enum Ring {
    /// A face of the file, kept as it is.
    Face(u32),
    /// A merged face: its ring of representatives, and the lowest face merged into it.
    Merged(Vec<u32>, u32),
}

/// Merges coplanar neighbours among `faces`; returns the rings in the order of their
/// lowest face, and how many regions were left unmerged.
fn merge(s: &Surface<'_>, faces: &[u32], tolerance: f64) -> (Vec<Ring>, usize) {
    let (lo, hi) = faces.iter().flat_map(|&f| s.faces.face(f as usize)).fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &v| (lo.min(s.points[v as usize]), hi.max(s.points[v as usize])),
    );
    let tol = tolerance * lo.distance(hi);
    let cos_angle = MERGE_ANGLE.cos();
    // Indexed by face of the whole surface; only this piece's faces are filled.
    let nf = s.faces.len();
    let mut normal = vec![(DVec3::ZERO, 0.0f64); nf];
    for &f in faces {
        let (n, _) = newell_and_longest(&s.points, s.faces.face(f as usize));
        normal[f as usize] = (n.normalize(), n.length());
    }
    // Largest first, then by face: areas are not negative, so their bits order them.
    let mut keyed: Vec<(std::cmp::Reverse<u64>, u32)> = faces
        .iter()
        .map(|&f| (std::cmp::Reverse(normal[f as usize].1.to_bits()), f))
        .collect();
    keyed.par_sort_unstable();
    let seeds: Vec<u32> = keyed.into_iter().map(|(_, f)| f).collect();
    const NONE: u32 = u32::MAX;
    let mut region = vec![NONE; nf];
    // Region r's faces are members[starts[r]..starts[r + 1]].
    let mut members: Vec<u32> = Vec::with_capacity(faces.len());
    let mut starts: Vec<usize> = vec![0];
    let mut stack = Vec::new();
    for &seed in &seeds {
        if region[seed as usize] != NONE {
            continue;
        }
        let r = (starts.len() - 1) as u32;
        let n = normal[seed as usize].0;
        let origin = s.points[s.faces.face(seed as usize)[0] as usize];
        members.push(seed);
        region[seed as usize] = r;
        stack.push(seed);
        while let Some(f) = stack.pop() {
            for h in s.half_edges(f as usize) {
                let g = s.face_of[s.twin[h] as usize];
                if region[g as usize] != NONE || normal[g as usize].0.dot(n) < cos_angle {
                    continue;
                }
                let flat = s
                    .faces
                    .face(g as usize)
                    .iter()
                    .all(|&v| (s.points[v as usize] - origin).dot(n).abs() <= tol);
                if flat {
                    region[g as usize] = r;
                    members.push(g);
                    stack.push(g);
                }
            }
        }
        starts.push(members.len());
    }
    let mut rings: Vec<(u32, Ring)> = Vec::with_capacity(starts.len());
    let mut unmerged = 0;
    let mut scratch = Vec::new();
    for r in 0..starts.len() - 1 {
        let members = &members[starts[r]..starts[r + 1]];
        let lowest = members.iter().copied().min().unwrap_or(0);
        if members.len() == 1 {
            rings.push((lowest, Ring::Face(lowest)));
            continue;
        }
        match outline(s, members, &region, r as u32, &mut scratch) {
            Some(ring) => rings.push((lowest, Ring::Merged(ring, lowest))),
            None => {
                unmerged += 1;
                rings.extend(members.iter().map(|&f| (f, Ring::Face(f))));
            }
        }
    }
    rings.sort_unstable_by_key(|(lowest, _)| *lowest);
    (rings.into_iter().map(|(_, r)| r).collect(), unmerged)
}

/// The one simple ring around region `r`'s faces, `None` when the outline is several
/// rings (a hole) or passes a vertex twice. `scratch` is kept between calls.
fn outline(
    s: &Surface<'_>,
    members: &[u32],
    region: &[u32],
    r: u32,
    scratch: &mut Vec<(u32, usize)>,
) -> Option<Vec<u32>> {
    // The outline's half-edges by start vertex.
    scratch.clear();
    for &f in members {
        for h in s.half_edges(f as usize) {
            let g = s.face_of[s.twin[h] as usize];
            if region[g as usize] != r {
                scratch.push((s.start(h), h));
            }
        }
    }
    scratch.sort_unstable();
    if scratch.windows(2).any(|w| w[0].0 == w[1].0) {
        return None;
    }
    let count = scratch.len();
    let (first, h0) = *scratch.first()?;
    let from = |v: u32| -> Option<usize> {
        scratch
            .binary_search_by_key(&v, |&(start, _)| start)
            .ok()
            .map(|k| scratch[k].1)
    };
    let mut ring = Vec::with_capacity(count);
    let mut h = h0;
    loop {
        ring.push(s.start(h));
        let end = s.start(s.next(h));
        if end == first {
            break;
        }
        h = from(end)?;
        if ring.len() > count {
            return None;
        }
    }
    (ring.len() == count).then_some(ring)
}

/// Drops the vertices that merging left on a straight side between two faces: a
/// vertex in exactly two rings (so of degree two), in a run of such vertices that all
/// lie within `tolerance` × the piece's diagonal of the segment between the run's ends.
/// A ring that would keep fewer than three corners keeps them all (and so does the other
/// ring of those vertices), so both faces along a side always agree.
fn drop_collinear(s: &Surface<'_>, rings: Vec<Ring>, tolerance: f64) -> Vec<Ring> {
    fn corners<'a>(s: &'a Surface<'_>, ring: &'a Ring) -> &'a [u32] {
        match ring {
            Ring::Face(f) => s.faces.face(*f as usize),
            Ring::Merged(r, _) => r,
        }
    }
    let n = s.points.len();
    let mut count = vec![0u8; n];
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for ring in &rings {
        for &v in corners(s, ring) {
            count[v as usize] = count[v as usize].saturating_add(1);
            lo = lo.min(s.points[v as usize]);
            hi = hi.max(s.points[v as usize]);
        }
    }
    let tol = tolerance * lo.distance(hi);
    let candidate = |v: u32| count[v as usize] == 2;
    // Pass 1: vertices whose run is straight.
    let mut straight = vec![false; n];
    let mut any = false;
    for ring in &rings {
        let c = corners(s, ring);
        let Some(anchor) = c.iter().position(|&v| !candidate(v)) else {
            continue;
        };
        let len = c.len();
        let mut k = 0;
        while k < len {
            let start = (anchor + k) % len;
            if candidate(c[start]) {
                let mut end = k;
                while end < len && candidate(c[(anchor + end) % len]) {
                    end += 1;
                }
                let a = s.points[c[(anchor + k + len - 1) % len] as usize];
                let b = s.points[c[(anchor + end) % len] as usize];
                let run = (k..end).map(|j| c[(anchor + j) % len]);
                let ok = run
                    .clone()
                    .all(|v| distance_to_segment(s.points[v as usize], a, b) <= tol);
                if ok {
                    for v in run {
                        straight[v as usize] = true;
                        any = true;
                    }
                }
                k = end;
            } else {
                k += 1;
            }
        }
    }
    if !any {
        return rings;
    }
    // Pass 2: rings that would fall below three corners keep theirs.
    let mut keep = vec![false; n];
    for ring in &rings {
        let c = corners(s, ring);
        let left = c.iter().filter(|&&v| !straight[v as usize]).count();
        if left < 3 {
            for &v in c {
                keep[v as usize] = true;
            }
        }
    }
    rings
        .into_iter()
        .map(|ring| {
            let c = corners(s, &ring);
            if !c.iter().any(|&v| straight[v as usize] && !keep[v as usize]) {
                return ring;
            }
            let lowest = match ring {
                Ring::Face(f) => f,
                Ring::Merged(_, lowest) => lowest,
            };
            let kept: Vec<u32> = c
                .iter()
                .copied()
                .filter(|&v| !straight[v as usize] || keep[v as usize])
                .collect();
            Ring::Merged(kept, lowest)
        })
        .collect()
}

/// The distance from `p` to the segment `a`–`b`.
fn distance_to_segment(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

/// The piece's polygons with its vertices numbered in the file's order; checked by
/// building the body.
fn build(
    s: &Surface<'_>,
    faces: &[u32],
    rings: &[Ring],
    unmerged: usize,
) -> Result<Piece, ImportError> {
    let mut used = vec![false; s.points.len()];
    fn corners<'a>(s: &'a Surface<'_>, ring: &'a Ring) -> &'a [u32] {
        match ring {
            Ring::Face(f) => s.faces.face(*f as usize),
            Ring::Merged(r, _) => r,
        }
    }
    let ring_of = |ring| corners(s, ring);
    for ring in rings {
        for &v in ring_of(ring) {
            used[v as usize] = true;
        }
    }
    let mut local = vec![u32::MAX; s.points.len()];
    let mut raw = Vec::new();
    let mut positions = Vec::new();
    for (v, &u) in used.iter().enumerate() {
        if u {
            local[v] = positions.len() as u32;
            raw.push(v as u32);
            positions.push(s.points[v]);
        }
    }
    let corners: usize = rings.iter().map(|r| ring_of(r).len()).sum();
    let mut polygons = Polygons::with_capacity(rings.len(), corners);
    for ring in rings {
        polygons
            .corners
            .extend(ring_of(ring).iter().map(|&v| local[v as usize]));
        polygons.ends.push(polygons.corners.len() as u32);
    }
    let face_of_ring = |k: usize| -> usize {
        match &rings[k] {
            Ring::Face(f) => *f as usize,
            Ring::Merged(_, lowest) => *lowest as usize,
        }
    };
    let refs: Vec<&[u32]> = polygons.iter().collect();
    let built = Built::new(|serials| {
        Body::from_polygons(serials, &positions, &refs).map_err(Refusal::Build)
    })
    .map_err(|e| {
        let e = match e {
            Refusal::Build(e) => e,
            Refusal::World(e) => {
                return s.invalid(Defect::OutOfRange, &[], &[], e.to_string());
            }
        };
        let (defect, fs, vs): (Defect, Vec<usize>, Vec<u32>) = match &e {
            BuildError::NonManifoldVertex { vertex } => (
                Defect::NonManifoldVertex,
                vec![],
                vec![raw[*vertex as usize]],
            ),
            BuildError::Inward { .. } => (Defect::Inward, vec![], vec![]),
            BuildError::TooSmall { .. } => (Defect::OutOfRange, vec![], vec![]),
            BuildError::Open { a, b, face } => (
                Defect::Open,
                vec![face_of_ring(*face)],
                vec![raw[*a as usize], raw[*b as usize]],
            ),
            BuildError::Inconsistent { a, b, face1, face2 } => (
                Defect::InconsistentOrientation,
                vec![face_of_ring(*face1), face_of_ring(*face2)],
                vec![raw[*a as usize], raw[*b as usize]],
            ),
            BuildError::NonManifoldEdge { a, b } => (
                Defect::NonManifoldEdge,
                vec![],
                vec![raw[*a as usize], raw[*b as usize]],
            ),
            _ => (Defect::Other, vec![], vec![]),
        };
        s.invalid(defect, &fs, &vs, e.to_string())
    })?;
    let body = built.body();
    let diagonal = body.bounds().map_or(0.0, |b| b.diagonal());
    let report = check_solid(body, SOLID_TOLERANCE * diagonal.max(f64::MIN_POSITIVE));
    if !report.is_ok() {
        let first = report
            .violations
            .first()
            .map(ToString::to_string)
            .unwrap_or_default();
        return Err(s.invalid(Defect::Other, &[], &[], first));
    }
    drop(refs);
    Ok(Piece {
        positions,
        faces: polygons,
        faces_read: faces.len(),
        unmerged,
        built,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit tetrahedron's faces, counter-clockwise seen from outside.
    fn tetra() -> (Vec<DVec3>, Polygons) {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let mut f = Polygons::default();
        for face in [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]] {
            f.push(&face);
        }
        (p, f)
    }

    #[test]
    fn an_object_without_faces_passes_its_pose_to_its_parts() {
        let (positions, faces) = tetra();
        let scene = RawScene {
            objects: vec![
                RawObject {
                    name: Some("group".into()),
                    pose: Pose::from_translation(DVec3::new(1.0, 0.0, 0.0)),
                    ..RawObject::default()
                },
                RawObject {
                    name: Some("part".into()),
                    parent: Some(0),
                    pose: Pose::from_translation(DVec3::new(0.0, 2.0, 0.0)),
                    positions,
                    faces,
                    ..RawObject::default()
                },
            ],
            unit: None,
        };
        let got = bodies(scene, &ImportOptions::default()).expect("imports");
        assert_eq!(got.bodies.len(), 1);
        let b = &got.bodies[0];
        assert_eq!(b.parent, None);
        assert_eq!(b.pose.position, DVec3::new(1.0, 2.0, 0.0));
        assert_eq!(got.built.len(), 1);
        assert_eq!(got.built[0].body().face_count(), 4);
    }

    /// A 2 m box whose sides are `n × n` grids of squares, as triangles with their own
    /// corners (welded by the import).
    fn grid_box(n: usize) -> RawObject {
        let mut positions = Vec::new();
        let mut faces = Polygons::default();
        for axis in 0..3 {
            for sign in [-1.0, 1.0] {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                let p = |a: usize, b: usize| {
                    let mut x = [0.0; 3];
                    x[axis] = sign;
                    x[u] = -1.0 + 2.0 * a as f64 / n as f64;
                    x[v] = -1.0 + 2.0 * b as f64 / n as f64;
                    DVec3::from_array(x)
                };
                for a in 0..n {
                    for b in 0..n {
                        let q = [p(a, b), p(a + 1, b), p(a + 1, b + 1), p(a, b + 1)];
                        let tris = if sign > 0.0 {
                            [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
                        } else {
                            [[q[0], q[2], q[1]], [q[0], q[3], q[2]]]
                        };
                        for t in tris {
                            let k = positions.len() as u32;
                            positions.extend(t);
                            faces.push(&[k, k + 1, k + 2]);
                        }
                    }
                }
            }
        }
        RawObject {
            positions,
            faces,
            ..RawObject::default()
        }
    }

    #[test]
    fn a_box_of_grids_merges_to_six_quads_and_eight_vertices() {
        let scene = RawScene {
            objects: vec![grid_box(5)],
            unit: None,
        };
        let got = bodies(scene, &ImportOptions::default()).expect("imports");
        let b = &got.bodies[0];
        assert_eq!(b.faces.len(), 6);
        assert_eq!(
            b.positions.len(),
            8,
            "the grid points on the edges are dropped"
        );
        assert!(b.faces.iter().all(|f| f.len() == 4));
        assert!((got.built[0].body().volume() - 8.0).abs() < 1e-12);
        // Without merging, every triangle stays and every vertex with it.
        let scene = RawScene {
            objects: vec![grid_box(5)],
            unit: None,
        };
        let options = ImportOptions {
            merge_coplanar: false,
            ..ImportOptions::default()
        };
        let got = bodies(scene, &options).expect("imports");
        assert_eq!(got.bodies[0].faces.len(), 300);
        assert_eq!(got.bodies[0].positions.len(), 152);
    }
}
