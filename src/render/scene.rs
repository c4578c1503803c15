//! The world flattened for drawing: every live body's faces, edges and vertices in world
//! coordinates, in flat arrays, with the faces triangulated.
//!
//! A [`Scene`] is built once per world revision from a snapshot (it never touches the
//! shared world) and then serves any number of cameras. Building it composes each body's
//! parts-tree pose once, triangulates each face and records, for every face, edge and
//! vertex, the body and serial number it came from, so every pixel and every segment of a
//! drawing can be traced back to the model.
//!
//! Faces are triangulated in their own plane: convex faces as fans, others by ear clipping
//! (the `earcut` crate), which handles concave faces with any number of sides and faces
//! whose perimeter runs along a bridge edge twice. Every triangle is wound
//! counter-clockwise seen from outside the body, like its face. A face of zero area gets
//! no triangles; its edges are still drawn.

use std::ops::Range;

use glam::DVec3;
use rayon::prelude::*;

use crate::model::triangulate::FaceTriangulator;
use crate::model::{BodyId, Bounds, Color, FaceId, Light, Pose, World, default_color};

use super::cache::ShadowCache;

/// One body of the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneBody {
    /// The body's id.
    pub id: BodyId,
    /// Its name, if it has one.
    pub name: Option<String>,
    /// Its material colour (the body's own, or [`default_color`] of its id).
    pub color: Color,
    /// Whether perception made it: a visual hull, whose only edges that the object
    /// shows are its outline (see [`crate::model::Perceived`]).
    pub provisional: bool,
    /// For a provisional body, how far its outline may lie outside the object's, in
    /// pixels; 0 for an ordinary body.
    pub outline_px: f64,
}

/// One face: its body, serial, plane and perimeter.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneFace {
    /// Index into [`Scene::bodies`].
    pub body: u32,
    /// The face's serial number (its id in the API).
    pub serial: u64,
    /// Unit outward normal in world coordinates (zero for a face of zero area).
    pub normal: DVec3,
    /// Plane offset: `normal · p = offset` for points `p` of the face.
    pub offset: f64,
    /// The perimeter: a range of [`Scene::rings`], counter-clockwise seen from outside.
    pub ring: Range<u32>,
}

impl SceneFace {
    /// Whether the face's outside looks toward the point `eye` (a front face seen from
    /// there). False for a face of zero area.
    #[inline]
    pub fn faces_toward(&self, eye: DVec3) -> bool {
        self.normal.dot(eye) - self.offset > 0.0
    }
}

/// One edge: its body, serial, ends and faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneEdge {
    /// Index into [`Scene::bodies`].
    pub body: u32,
    /// The edge's serial number (its id in the API).
    pub serial: u64,
    /// `[NVT, PVT]` as indices into [`Scene::points`].
    pub ends: [u32; 2],
    /// `[NFACE, PFACE]` as indices into [`Scene::faces`].
    pub faces: [u32; 2],
}

/// The world flattened for drawing. See the [module documentation](self).
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// The world revision this scene shows.
    pub revision: u64,
    /// The bodies that have geometry, in id order.
    pub bodies: Vec<SceneBody>,
    /// Vertex loci in world coordinates.
    pub points: Vec<DVec3>,
    /// Each point's vertex serial number.
    pub point_serials: Vec<u64>,
    /// The faces.
    pub faces: Vec<SceneFace>,
    /// Face perimeters: indices into [`Scene::points`] (see [`SceneFace::ring`]).
    pub rings: Vec<u32>,
    /// Triangles: indices into [`Scene::points`], counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// The face (index into [`Scene::faces`]) of each triangle.
    pub triangle_faces: Vec<u32>,
    /// The edges.
    pub edges: Vec<SceneEdge>,
    /// The world's light sources, by name order.
    pub lights: Vec<(String, Light)>,
    /// The world bounds of every point, `None` for a scene without geometry.
    pub bounds: Option<Bounds>,
    /// Shadow maps of the lights, made by the first shaded picture that needs them and
    /// kept for the next ones.
    pub shadows: ShadowCache,
}

/// One body's part of a scene, with indices local to it.
#[derive(Default)]
struct Piece {
    body: Option<SceneBody>,
    points: Vec<DVec3>,
    point_serials: Vec<u64>,
    faces: Vec<SceneFace>,
    rings: Vec<u32>,
    triangles: Vec<[u32; 3]>,
    triangle_faces: Vec<u32>,
    edges: Vec<SceneEdge>,
}

impl Scene {
    /// The scene of `world` at its current revision. Bodies without faces (the root, a
    /// seminal body) contribute nothing. Runs in parallel over bodies.
    pub fn build(world: &World) -> Scene {
        let ids: Vec<BodyId> = world
            .bodies()
            .filter(|(_, n)| n.body.face_count() > 0 && n.body.edge_count() > 0)
            .map(|(id, _)| id)
            .collect();
        let pieces: Vec<Piece> = ids
            .par_iter()
            .with_min_len(64)
            .map_init(FaceTriangulator::new, |ear, &id| piece(world, id, ear))
            .collect();
        let mut scene = Scene {
            revision: world.revision(),
            lights: world
                .lights()
                .map(|(name, light)| (name.to_owned(), *light))
                .collect(),
            ..Scene::default()
        };
        let total = |f: fn(&Piece) -> usize| pieces.iter().map(f).sum::<usize>();
        scene.bodies.reserve(pieces.len());
        scene.points.reserve(total(|p| p.points.len()));
        scene.point_serials.reserve(total(|p| p.points.len()));
        scene.faces.reserve(total(|p| p.faces.len()));
        scene.rings.reserve(total(|p| p.rings.len()));
        scene.triangles.reserve(total(|p| p.triangles.len()));
        scene.triangle_faces.reserve(total(|p| p.triangles.len()));
        scene.edges.reserve(total(|p| p.edges.len()));
        for piece in pieces {
            scene.append(piece);
        }
        scene.bounds = bounds_of(&scene.points);
        scene
    }

    /// Appends one body's piece, shifting its local indices.
    fn append(&mut self, p: Piece) {
        let Some(body) = p.body else { return };
        let b = self.bodies.len() as u32;
        let (v0, f0, r0) = (
            self.points.len() as u32,
            self.faces.len() as u32,
            self.rings.len() as u32,
        );
        self.bodies.push(body);
        self.points.extend(p.points);
        self.point_serials.extend(p.point_serials);
        self.rings.extend(p.rings.iter().map(|&v| v + v0));
        self.faces.extend(p.faces.into_iter().map(|f| SceneFace {
            body: b,
            ring: f.ring.start + r0..f.ring.end + r0,
            ..f
        }));
        self.triangles
            .extend(p.triangles.iter().map(|t| t.map(|v| v + v0)));
        self.triangle_faces
            .extend(p.triangle_faces.iter().map(|&f| f + f0));
        self.edges.extend(p.edges.into_iter().map(|e| SceneEdge {
            body: b,
            ends: e.ends.map(|v| v + v0),
            faces: e.faces.map(|f| f + f0),
            ..e
        }));
    }

    /// Whether edge `e` borders at least one face turned toward `eye`: only such edges
    /// can show in a hidden-line drawing seen from there.
    pub fn edge_faces_toward(&self, e: &SceneEdge, eye: DVec3) -> bool {
        e.faces
            .iter()
            .any(|&f| self.faces[f as usize].faces_toward(eye))
    }

    /// The points of body `b` (an index into [`Scene::bodies`]): indices into
    /// [`Scene::points`], ascending, each once. Empty for no such body.
    pub fn body_points(&self, b: usize) -> Vec<u32> {
        let mut points: Vec<u32> = self
            .faces
            .iter()
            .filter(|f| f.body as usize == b)
            .flat_map(|f| self.ring(f).iter().copied())
            .collect();
        points.sort_unstable();
        points.dedup();
        points
    }

    /// A copy of the scene with body `b` moved by `motion` (world points `X ↦
    /// motion·X`): its `points` (as [`Scene::body_points`] gives them) and its faces'
    /// planes. Its inverse is the move by `motion.inverse()`, up to rounding. The bounds
    /// are those of the unmoved scene; the copy starts without shadow maps.
    pub fn with_body_moved(&self, b: usize, points: &[u32], motion: &Pose) -> Scene {
        let mut scene = self.clone();
        for &i in points {
            if let Some(p) = scene.points.get_mut(i as usize) {
                *p = motion.transform_point(*p);
            }
        }
        for face in scene.faces.iter_mut().filter(|f| f.body as usize == b) {
            let normal = motion.transform_vector(face.normal);
            face.offset += normal.dot(motion.position);
            face.normal = normal;
        }
        scene
    }

    /// A copy of the scene without the faces, triangles and edges of the bodies for
    /// which `drop` holds (their entries in [`Scene::bodies`] and their points stay, so
    /// that every index into those lists keeps its meaning).
    pub fn without_bodies(&self, drop: impl Fn(usize) -> bool) -> Scene {
        let mut renumber = vec![u32::MAX; self.faces.len()];
        let mut faces = Vec::with_capacity(self.faces.len());
        for (i, f) in self.faces.iter().enumerate() {
            if !drop(f.body as usize) {
                renumber[i] = faces.len() as u32;
                faces.push(f.clone());
            }
        }
        let (triangles, triangle_faces) = self
            .triangles
            .iter()
            .zip(&self.triangle_faces)
            .filter(|&(_, &f)| renumber[f as usize] != u32::MAX)
            .map(|(&t, &f)| (t, renumber[f as usize]))
            .unzip();
        let edges = self
            .edges
            .iter()
            .filter(|e| !drop(e.body as usize))
            .map(|e| SceneEdge {
                faces: e.faces.map(|f| renumber[f as usize]),
                ..*e
            })
            .collect();
        Scene {
            revision: self.revision,
            bodies: self.bodies.clone(),
            points: self.points.clone(),
            point_serials: self.point_serials.clone(),
            faces,
            rings: self.rings.clone(),
            triangles,
            triangle_faces,
            edges,
            lights: self.lights.clone(),
            bounds: self.bounds,
            shadows: ShadowCache::default(),
        }
    }

    /// The perimeter of face `f` as indices into [`Scene::points`].
    pub fn ring(&self, f: &SceneFace) -> &[u32] {
        &self.rings[f.ring.start as usize..f.ring.end as usize]
    }
}

/// The smallest box around `points`.
fn bounds_of(points: &[DVec3]) -> Option<Bounds> {
    let first = *points.first()?;
    let (min, max) = points
        .iter()
        .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    Some(Bounds { min, max })
}

/// Body `id`'s faces, edges and vertices in world coordinates, indices local.
fn piece(world: &World, id: BodyId, ear: &mut FaceTriangulator) -> Piece {
    let (Some(node), Some(pose)) = (world.node(id), world.world_pose(id)) else {
        return Piece::default();
    };
    let body = &*node.body;
    let slots = body.vertices().map(|v| v.index() + 1).max().unwrap_or(0);
    let mut local = vec![u32::MAX; slots];
    let mut piece = Piece {
        body: Some(SceneBody {
            id,
            name: node.name.clone(),
            color: node.color.unwrap_or_else(|| default_color(id)),
            provisional: node.perceived.is_some(),
            outline_px: node.perceived.as_ref().map_or(0.0, |p| p.outline_px),
        }),
        ..Piece::default()
    };
    for v in body.vertices() {
        local[v.index()] = piece.points.len() as u32;
        piece.points.push(pose.transform_point(body.position(v)));
        piece.point_serials.push(body.vertex_serial(v).get());
    }
    let face_slots = body.faces().map(|f| f.index() + 1).max().unwrap_or(0);
    let mut face_local = vec![u32::MAX; face_slots];
    let mut tris = Vec::new();
    for f in body.faces() {
        let fi = piece.faces.len() as u32;
        face_local[f.index()] = fi;
        let start = piece.rings.len() as u32;
        piece
            .rings
            .extend(body.face_vertices(f).map(|v| local[v.index()]));
        let ring = start..piece.rings.len() as u32;
        let normal = pose.transform_vector(body.newell(f)).normalize_or_zero();
        let corners = &piece.rings[ring.start as usize..ring.end as usize];
        let offset = if corners.is_empty() {
            0.0
        } else {
            let sum: DVec3 = corners.iter().map(|&v| piece.points[v as usize]).sum();
            normal.dot(sum / corners.len() as f64)
        };
        if normal != DVec3::ZERO && corners.len() >= 3 {
            ear.triangulate(&piece.points, corners, normal, &mut tris);
            for t in &tris {
                piece.triangles.push(*t);
                piece.triangle_faces.push(fi);
            }
        }
        piece.faces.push(SceneFace {
            body: 0,
            serial: body.face_serial(f).get(),
            normal,
            offset,
            ring,
        });
    }
    let face_of = |f: FaceId| face_local[f.index()];
    for e in body.edges() {
        let edge = body.edge(e);
        piece.edges.push(SceneEdge {
            body: 0,
            serial: body.edge_serial(e).get(),
            ends: edge.vt.map(|v| local[v.index()]),
            faces: edge.face.map(face_of),
        });
    }
    piece
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Pose;
    use crate::model::solids;

    fn area(scene: &Scene) -> f64 {
        scene
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| scene.points[i as usize]);
                (b - a).cross(c - a).length() / 2.0
            })
            .sum()
    }

    #[test]
    fn a_cube_has_twelve_outward_triangles() {
        let mut w = World::new();
        let root = w.root();
        let pose = Pose::from_translation(DVec3::new(5.0, 0.0, 0.0));
        w.insert_with(Some("cube"), root, pose, |s| {
            solids::mkcube(s, 2.0, 2.0, 2.0)
        })
        .unwrap();
        let s = Scene::build(&w);
        assert_eq!(s.bodies.len(), 1);
        assert_eq!((s.faces.len(), s.edges.len(), s.points.len()), (6, 12, 8));
        assert_eq!(s.triangles.len(), 12);
        assert!((area(&s) - 24.0).abs() < 1e-9);
        let b = s.bounds.unwrap();
        assert!((b.min - DVec3::new(4.0, -1.0, -1.0)).length() < 1e-12);
        for (t, &f) in s.triangles.iter().zip(&s.triangle_faces) {
            let [a, b, c] = t.map(|i| s.points[i as usize]);
            let n = (b - a).cross(c - a);
            assert!(
                n.dot(s.faces[f as usize].normal) > 0.0,
                "triangle wound inward"
            );
        }
    }

    #[test]
    fn a_concave_face_is_triangulated_exactly() {
        // An L-shaped prism: its caps are concave hexagons of area 3.
        let l = crate::render::sample::L_SHAPE;
        let mut w = World::new();
        let root = w.root();
        w.insert_with(None, root, Pose::IDENTITY, |s| {
            solids::prism_solid(s, &l, 1.0)
        })
        .unwrap();
        let s = Scene::build(&w);
        // Two caps of area 3, sides 2+1+1+1+1+2 = 8 long and 1 high.
        assert!((area(&s) - (2.0 * 3.0 + 8.0)).abs() < 1e-9, "{}", area(&s));
        assert_eq!(s.triangles.len(), 2 * 4 + 6 * 2);
    }

    #[test]
    fn default_colours_are_stable_and_differ() {
        let a = default_color(BodyId(crate::model::Serial(2)));
        assert_eq!(a, default_color(BodyId(crate::model::Serial(2))));
        assert_ne!(a, default_color(BodyId(crate::model::Serial(3))));
    }
}
