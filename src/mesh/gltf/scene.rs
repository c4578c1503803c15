//! The node hierarchy: which nodes become objects, their rigid poses, and whatever
//! scale, shear or mirror the file's transforms hold besides, applied to the positions.

use std::collections::HashMap;
use std::collections::hash_map::Entry;

use ::gltf::json;
use glam::{DAffine3, DMat3, DQuat, DVec3};
use json::mesh::{Mode, Semantic};
use json::validation::Checked;

use super::linear_to_srgb8;
use super::source::{Data, parse_error};
use crate::mesh::{ImportError, ImportOptions, Polygons, RawObject, RawScene};
use crate::model::{Color, Pose};

/// Reads the objects of a parsed, validated document (see [`super::read`]).
pub(super) fn objects(
    root: &json::Root,
    blob: Option<&[u8]>,
    file_len: usize,
    options: &ImportOptions,
) -> Result<RawScene, ImportError> {
    let visits = walk(root)?;
    let mut faces = 0u64;
    let mut used = vec![false; root.meshes.len()];
    for v in &visits {
        if let Some(m) = mesh_of(root, v.node) {
            faces = faces.saturating_add(triangle_bound(root, m));
            used[m] = true;
        }
    }
    if faces > options.max_file_faces as u64 {
        return Err(ImportError::TooLarge {
            what: "faces in the file",
            count: faces,
            limit: options.max_file_faces as u64,
        });
    }
    let mut wanted = Vec::new();
    for (m, _) in used.iter().enumerate().filter(|(_, u)| **u) {
        for p in &root.meshes[m].primitives {
            if !is_triangles(&p.mode) {
                continue;
            }
            let accessors = p
                .attributes
                .get(&Checked::Valid(Semantic::Positions))
                .into_iter()
                .chain(p.indices.as_ref());
            for a in accessors {
                wanted.extend(Data::accessor_buffers(root, a.value()));
            }
        }
    }
    let data = Data::resolve(root, blob, wanted, file_len)?;
    let mut meshes: Vec<Option<MeshData>> = Vec::new();
    meshes.resize_with(root.meshes.len(), || None);
    let mut cache = PositionCache::new();
    let mut build = Build::default();
    for visit in &visits {
        let mesh = match mesh_of(root, visit.node) {
            Some(m) => {
                if meshes[m].is_none() {
                    meshes[m] = Some(read_mesh(root, &data, &mut cache, m)?);
                }
                meshes[m].as_ref().filter(|d| !d.triangles.is_empty())
            }
            None => None,
        };
        build.visit(root, visit, mesh)?;
    }
    Ok(RawScene {
        objects: build.objects,
        unit: None,
    })
}

/// A node's own transform.
#[derive(Clone, Copy, Debug)]
enum Local {
    /// Translation and rotation only: TRS with a scale of exactly 1 (or none), or an
    /// identity matrix.
    Rigid(Pose),
    /// TRS with another scale.
    Scaled(Pose, DVec3),
    /// A matrix (affine).
    Matrix(DAffine3),
}

/// A node reached from the scene's roots.
struct Visit {
    /// The node's index.
    node: usize,
    /// The visit of its parent node (lower than its own), `None` for a root.
    parent: Option<usize>,
    /// Its own transform.
    local: Local,
}

/// The nodes of the scene in depth-first order (parents before children, children in
/// the file's order). The scene is the default one, else scene 0, else (no scene) every
/// node that is no node's child.
///
/// Refused with [`ImportError::Parse`] when a node is reached twice (the hierarchy is
/// not a tree) or a node's transform is bad ([`local`]).
fn walk(root: &json::Root) -> Result<Vec<Visit>, ImportError> {
    let roots: Vec<usize> = match root
        .scene
        .and_then(|s| root.scenes.get(s.value()))
        .or(root.scenes.first())
    {
        Some(scene) => scene.nodes.iter().map(|n| n.value()).collect(),
        None => {
            let mut child = vec![false; root.nodes.len()];
            for n in &root.nodes {
                for c in n.children.iter().flatten() {
                    if let Some(slot) = child.get_mut(c.value()) {
                        *slot = true;
                    }
                }
            }
            (0..root.nodes.len()).filter(|&n| !child[n]).collect()
        }
    };
    let mut seen = vec![false; root.nodes.len()];
    let mut visits = Vec::new();
    let mut stack: Vec<(usize, Option<usize>)> = roots.iter().rev().map(|&n| (n, None)).collect();
    while let Some((n, parent)) = stack.pop() {
        let Some(node) = root.nodes.get(n) else {
            return Err(parse_error(format!("there is no node {n}")));
        };
        if std::mem::replace(&mut seen[n], true) {
            return Err(parse_error(format!(
                "node {n} is reached twice in the node hierarchy, which must be a tree"
            )));
        }
        let at = visits.len();
        visits.push(Visit {
            node: n,
            parent,
            local: local(n, node)?,
        });
        for c in node.children.iter().flatten().rev() {
            stack.push((c.value(), Some(at)));
        }
    }
    Ok(visits)
}

/// Node `n`'s transform: its `matrix` if it has one (which must be affine and finite),
/// else its translation, rotation (renormalised) and scale.
fn local(n: usize, node: &json::Node) -> Result<Local, ImportError> {
    let bad = |what: &str| parse_error(format!("node {n}: {what}"));
    if let Some(m) = node.matrix {
        let m = m.map(f64::from);
        if m.iter().any(|x| !x.is_finite()) {
            return Err(bad(
                "its matrix has a component that is not a finite number",
            ));
        }
        let bottom = [m[3], m[7], m[11], m[15]];
        if bottom
            .iter()
            .zip([0.0, 0.0, 0.0, 1.0])
            .any(|(a, b)| (a - b).abs() > 1e-6)
        {
            return Err(bad(
                "its matrix is not affine (its last row is not 0, 0, 0, 1)",
            ));
        }
        let affine = DAffine3::from_cols(
            DVec3::new(m[0], m[1], m[2]),
            DVec3::new(m[4], m[5], m[6]),
            DVec3::new(m[8], m[9], m[10]),
            DVec3::new(m[12], m[13], m[14]),
        );
        if affine == DAffine3::IDENTITY {
            return Ok(Local::Rigid(Pose::IDENTITY));
        }
        return Ok(Local::Matrix(affine));
    }
    let t = node.translation.unwrap_or([0.0; 3]).map(f64::from);
    let r = node
        .rotation
        .map_or([0.0, 0.0, 0.0, 1.0], |q| q.0)
        .map(f64::from);
    let pose = Pose::new(
        DVec3::from_array(t),
        DQuat::from_xyzw(r[0], r[1], r[2], r[3]),
    )
    .map_err(|e| bad(&e.to_string()))?;
    match node.scale {
        None | Some([1.0, 1.0, 1.0]) => Ok(Local::Rigid(pose)),
        Some(s) if s.iter().all(|x| x.is_finite()) => {
            Ok(Local::Scaled(pose, DVec3::from_array(s.map(f64::from))))
        }
        Some(_) => Err(bad("its scale has a component that is not a finite number")),
    }
}

/// The mesh node `n` holds, if any.
fn mesh_of(root: &json::Root, n: usize) -> Option<usize> {
    let m = root.nodes.get(n)?.mesh?.value();
    (m < root.meshes.len()).then_some(m)
}

/// Whether a primitive's mode makes triangles.
fn is_triangles(mode: &Checked<Mode>) -> bool {
    matches!(
        mode,
        Checked::Valid(Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan)
    )
}

/// The most triangles mesh `m` can make, from its accessors' counts alone.
fn triangle_bound(root: &json::Root, m: usize) -> u64 {
    let count = |a: Option<&json::Index<json::Accessor>>| {
        a.and_then(|a| root.accessors.get(a.value()))
            .map_or(0, |a| a.count.0)
    };
    let mut total = 0u64;
    for p in &root.meshes[m].primitives {
        let n = match p.indices.as_ref() {
            Some(i) => count(Some(i)),
            None => count(p.attributes.get(&Checked::Valid(Semantic::Positions))),
        };
        let t = match p.mode {
            Checked::Valid(Mode::Triangles) => n / 3,
            Checked::Valid(Mode::TriangleStrip | Mode::TriangleFan) => n.saturating_sub(2),
            _ => 0,
        };
        total = total.saturating_add(t);
    }
    total
}

/// A mesh's triangles, its primitives concatenated.
struct MeshData {
    /// The vertices its triangles use (each POSITION accessor's used vertices in its own
    /// order, the accessors in the order the primitives first name them).
    positions: Vec<[f32; 3]>,
    /// Triangles as indices into `positions`, wound as the file winds them.
    triangles: Vec<[u32; 3]>,
    /// The base colour of its first triangle primitive with a material.
    color: Option<Color>,
}

/// Each POSITION accessor read so far, by index: read once however many meshes use it.
type PositionCache = HashMap<usize, Vec<[f32; 3]>>;

/// Reads mesh `m`: every primitive of mode TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN
/// (strips and fans cut into triangles of the same winding, those naming a vertex
/// twice dropped); points and lines are skipped. Primitives that share a POSITION
/// accessor share its vertices; vertices no triangle uses are dropped (so the work is
/// in the number of triangles, not in the size of an accessor many meshes share).
///
/// Refused with [`ImportError::Parse`] for a bad accessor, an index past the
/// primitive's vertices, or a TRIANGLES index count that is not a multiple of 3.
fn read_mesh(
    root: &json::Root,
    data: &Data,
    cache: &mut PositionCache,
    m: usize,
) -> Result<MeshData, ImportError> {
    /// The primitives of one POSITION accessor.
    struct Group {
        accessor: usize,
        /// The vertices the triangles use (sorted and deduplicated at the end).
        used: Vec<u32>,
    }
    let mesh = &root.meshes[m];
    let mut groups: Vec<Group> = Vec::new();
    let mut primitives: Vec<(usize, Vec<[u32; 3]>)> = Vec::new();
    let mut color = None;
    let mut corners = 0u64;
    for (p, primitive) in mesh.primitives.iter().enumerate() {
        let at = |what: String| parse_error(format!("mesh {m} primitive {p}: {what}"));
        let mode = match primitive.mode {
            Checked::Valid(mode) => mode,
            Checked::Invalid => return Err(at("its mode is not one glTF defines".into())),
        };
        if !is_triangles(&primitive.mode) {
            continue;
        }
        let Some(a) = primitive
            .attributes
            .get(&Checked::Valid(Semantic::Positions))
            .map(|a| a.value())
        else {
            return Err(at("it has no POSITION".into()));
        };
        let vertices = match cache.entry(a) {
            Entry::Occupied(e) => e.get().len(),
            Entry::Vacant(e) => e.insert(data.vec3_f32(a)?).len(),
        };
        if vertices > u32::MAX as usize {
            return Err(at(format!("{vertices} vertices are too many")));
        }
        let indices: Vec<u32> = match primitive.indices {
            Some(i) => data.indices(i.value())?,
            // At most u32::MAX vertices, checked above.
            None => (0..vertices as u32).collect(),
        };
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= vertices) {
            return Err(at(format!(
                "an index names vertex {bad}, but POSITION has {vertices} vertices"
            )));
        }
        let triangles = cut(mode, &indices).map_err(at)?;
        corners = corners.saturating_add(3 * triangles.len() as u64);
        if corners > u32::MAX as u64 {
            return Err(ImportError::TooLarge {
                what: "triangle corners in one mesh",
                count: corners,
                limit: u32::MAX as u64,
            });
        }
        let g = match groups.iter().position(|g| g.accessor == a) {
            Some(g) => g,
            None => {
                groups.push(Group {
                    accessor: a,
                    used: Vec::new(),
                });
                groups.len() - 1
            }
        };
        groups[g].used.extend(triangles.iter().flatten());
        if color.is_none()
            && let Some(material) = primitive.material
            && let Some(material) = root.materials.get(material.value())
        {
            let [r, g, b, _] = material.pbr_metallic_roughness.base_color_factor.0;
            color = Some(Color([r, g, b].map(linear_to_srgb8)));
        }
        primitives.push((g, triangles));
    }
    let mut positions = Vec::new();
    let mut first = Vec::with_capacity(groups.len());
    for group in &mut groups {
        group.used.sort_unstable();
        group.used.dedup();
        first.push(positions.len() as u32);
        let source = cache.get(&group.accessor).map_or(&[][..], Vec::as_slice);
        // Every used vertex is below the accessor's count, checked above.
        positions.extend(group.used.iter().filter_map(|&v| source.get(v as usize)));
    }
    let mut triangles = Vec::with_capacity(corners as usize / 3);
    for (g, ts) in primitives {
        let used = &groups[g].used;
        // Every corner is in `used`: the search finds it.
        let renumber = |v: u32| first[g] + used.binary_search(&v).unwrap_or_else(|k| k) as u32;
        triangles.extend(ts.iter().map(|t| t.map(renumber)));
    }
    Ok(MeshData {
        positions,
        triangles,
        color,
    })
}

/// The triangles of a primitive of `mode` (a triangle mode) with these indices.
fn cut(mode: Mode, indices: &[u32]) -> Result<Vec<[u32; 3]>, String> {
    let distinct = |t: &[u32; 3]| t[0] != t[1] && t[1] != t[2] && t[0] != t[2];
    let n = indices.len();
    Ok(match mode {
        Mode::TriangleStrip => (0..n.saturating_sub(2))
            .map(|i| {
                let (a, b, c) = (indices[i], indices[i + 1], indices[i + 2]);
                if i % 2 == 0 { [a, b, c] } else { [a, c, b] }
            })
            .filter(distinct)
            .collect(),
        Mode::TriangleFan => (1..n.saturating_sub(1))
            .map(|i| [indices[0], indices[i], indices[i + 1]])
            .filter(distinct)
            .collect(),
        _ => {
            if !n.is_multiple_of(3) {
                return Err(format!(
                    "{n} triangle indices, which is not a multiple of 3"
                ));
            }
            indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect()
        }
    })
}

/// A visit's place in the world.
#[derive(Clone, Copy, Debug)]
struct Frame {
    /// The node's world matrix.
    affine: DAffine3,
    /// Its world pose, when every transform on its path is rigid (then no arithmetic
    /// touches the positions).
    exact: Option<Pose>,
    /// With `exact`: its pose in the frame of its nearest ancestor that is an object
    /// (the world's, if none), composed from the transforms in between.
    relative: Option<Pose>,
    /// The product of the rotations on its path, when no matrix is on it.
    rotation: Option<DQuat>,
}

impl Frame {
    const WORLD: Frame = Frame {
        affine: DAffine3::IDENTITY,
        exact: Some(Pose::IDENTITY),
        relative: Some(Pose::IDENTITY),
        rotation: Some(DQuat::IDENTITY),
    };
}

/// The objects as the visits make them, in the visits' order.
#[derive(Default)]
struct Build {
    objects: Vec<RawObject>,
    /// Each object's world pose.
    world: Vec<Pose>,
    /// Each visit's frame.
    frames: Vec<Frame>,
    /// Each visit's object (its own, or its nearest ancestor's).
    owner: Vec<Option<usize>>,
    /// Whether each visit made an object.
    is_object: Vec<bool>,
}

impl Build {
    /// Takes the next visit (its parent's already taken): its frame, and an object if it has
    /// a mesh with triangles.
    fn visit(
        &mut self,
        root: &json::Root,
        visit: &Visit,
        mesh: Option<&MeshData>,
    ) -> Result<(), ImportError> {
        let (parent, parent_object) = match visit.parent {
            Some(p) => (self.frames[p], self.owner[p]),
            None => (Frame::WORLD, None),
        };
        // Relative poses restart below an object.
        let base = match visit.parent {
            Some(p) if self.is_object[p] => Some(Pose::IDENTITY),
            _ => parent.relative,
        };
        let frame = match visit.local {
            Local::Rigid(pose) => Frame {
                affine: parent.affine * pose.to_affine(),
                exact: parent.exact.map(|w| w.compose(&pose)),
                relative: base.map(|r| r.compose(&pose)),
                rotation: parent.rotation.map(|q| (q * pose.rotation).normalize()),
            },
            Local::Scaled(pose, scale) => Frame {
                affine: parent.affine
                    * DAffine3::from_scale_rotation_translation(
                        scale,
                        pose.rotation,
                        pose.position,
                    ),
                exact: None,
                relative: None,
                rotation: parent.rotation.map(|q| (q * pose.rotation).normalize()),
            },
            Local::Matrix(m) => Frame {
                affine: parent.affine * m,
                exact: None,
                relative: None,
                rotation: None,
            },
        };
        self.frames.push(frame);
        let Some(mesh) = mesh else {
            self.owner.push(parent_object);
            self.is_object.push(false);
            return Ok(());
        };
        let node = &root.nodes[visit.node];
        let (world, pose, positions, flip) = match (frame.exact, frame.relative) {
            (Some(world), Some(relative)) => {
                let positions = mesh
                    .positions
                    .iter()
                    .map(|p| DVec3::from_array(p.map(f64::from)))
                    .collect();
                (world, relative, positions, false)
            }
            _ => {
                let (world, residual, flip) = rigid_part(visit.node, &frame)?;
                let pose = match parent_object {
                    Some(o) => self.world[o].inverse().compose(&world),
                    None => world,
                };
                let positions = mesh
                    .positions
                    .iter()
                    .map(|p| residual * DVec3::from_array(p.map(f64::from)))
                    .collect();
                (world, pose, positions, flip)
            }
        };
        let mut faces = Polygons::with_capacity(mesh.triangles.len(), 3 * mesh.triangles.len());
        for &[a, b, c] in &mesh.triangles {
            faces.push(&if flip { [a, c, b] } else { [a, b, c] });
        }
        let name = node.name.clone().or_else(|| {
            node.mesh
                .and_then(|m| root.meshes.get(m.value()))
                .and_then(|m| m.name.clone())
        });
        self.owner.push(Some(self.objects.len()));
        self.is_object.push(true);
        self.world.push(world);
        self.objects.push(RawObject {
            name,
            parent: parent_object,
            pose,
            color: mesh.color,
            positions,
            faces,
            first_vertex: None,
            first_face: 0,
        });
        Ok(())
    }
}

/// The rigid part of a frame's world matrix and what is left: `(pose, residual, flip)`
/// with `affine = pose ∘ residual` (the residual a linear map: scale, shear, mirror) and
/// `flip` when the residual mirrors (so faces must be rewound).
///
/// The rotation is the product of the rotations on the path when that leaves a
/// symmetric residual (scales only on the mesh node, or uniform ones), else the polar
/// decomposition's. Refused with [`ImportError::Parse`] for a matrix that is not finite
/// or is singular (a scale of 0).
fn rigid_part(node: usize, frame: &Frame) -> Result<(Pose, DMat3, bool), ImportError> {
    let bad = |what: &str| parse_error(format!("node {node}: its world transform {what}"));
    let l = frame.affine.matrix3;
    let t = frame.affine.translation;
    if !l.is_finite() || !t.is_finite() {
        return Err(bad("has a component that is not a finite number"));
    }
    let det = l.determinant();
    let size = frobenius(l);
    let regular = det.abs() > 1e-12 * size * size * size;
    if !regular {
        return Err(bad("is singular (a scale of 0?)"));
    }
    let symmetric = |q: &DQuat| {
        let s = DMat3::from_quat(*q).transpose() * l;
        frobenius(s - s.transpose()) <= 1e-9 * frobenius(s)
    };
    let rotation = frame
        .rotation
        .filter(symmetric)
        .or_else(|| polar_rotation(l, det))
        .ok_or_else(|| bad("has no rotation part that could be found"))?;
    let pose = Pose::new(t, rotation).map_err(|e| bad(&e.to_string()))?;
    let residual = DMat3::from_quat(pose.rotation).transpose() * l;
    Ok((pose, residual, det < 0.0))
}

/// The rotation of the polar decomposition of `l` (after a mirror in x when `det` < 0,
/// so that it is a proper rotation), by Newton's iteration with Higham's scaling.
/// `None` if it does not converge. Precondition: `l` is finite and not singular.
fn polar_rotation(l: DMat3, det: f64) -> Option<DQuat> {
    let mut x = if det < 0.0 {
        l * DMat3::from_diagonal(DVec3::new(-1.0, 1.0, 1.0))
    } else {
        l
    };
    for _ in 0..100 {
        let inverse_t = x.inverse().transpose();
        let gamma = (frobenius(inverse_t) / frobenius(x)).sqrt();
        if !gamma.is_finite() || gamma <= 0.0 {
            return None;
        }
        let next = (x * gamma + inverse_t * (1.0 / gamma)) * 0.5;
        let step = frobenius(next - x);
        x = next;
        if step <= 1e-14 {
            break;
        }
    }
    let error = frobenius(x.transpose() * x - DMat3::IDENTITY);
    (error <= 1e-9 && x.determinant() > 0.0).then(|| DQuat::from_mat3(&x).normalize())
}

fn frobenius(m: DMat3) -> f64 {
    (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()).sqrt()
}
