//! A closed polyhedron from vertex and face lists.

use glam::DVec3;

use crate::model::body::{Body, Edge};
use crate::model::ids::{EdgeId, FaceId, Serials, Side, VertexId};
use crate::model::topology::EdgeUse;

/// Why a vertex and face list is not a closed, consistently oriented polyhedron.
/// Vertices and faces are named by their index in the input lists.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BuildError {
    /// No faces were given.
    #[error("no faces were given")]
    NoFaces,
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} has a coordinate that is not a finite number")]
    NonFinite {
        /// The vertex index.
        vertex: usize,
    },
    /// A face names a vertex index past the end of the vertex list.
    #[error("face {face} names vertex {index}, but there are only {count} vertices")]
    IndexOutOfRange {
        /// The face index.
        face: usize,
        /// The index it names.
        index: u32,
        /// The number of vertices.
        count: usize,
    },
    /// A face with fewer than three vertices.
    #[error("face {face} has {degree} vertices; a face needs at least 3")]
    FaceTooSmall {
        /// The face index.
        face: usize,
        /// Its vertex count.
        degree: usize,
    },
    /// A face that lists a vertex twice.
    #[error("face {face} lists vertex {vertex} more than once")]
    RepeatedVertex {
        /// The face index.
        face: usize,
        /// The vertex index.
        vertex: u32,
    },
    /// An edge that only one face uses: the surface has a hole.
    #[error("the surface is open: edge {a}-{b} belongs to one face only (face {face})")]
    Open {
        /// One end.
        a: u32,
        /// The other end.
        b: u32,
        /// The face that uses it.
        face: usize,
    },
    /// Two faces run along the same edge in the same direction.
    #[error(
        "faces {face1} and {face2} both run from vertex {a} to {b}: their orientations disagree (faces must be counter-clockwise seen from outside)"
    )]
    Inconsistent {
        /// Start of the edge.
        a: u32,
        /// End of the edge.
        b: u32,
        /// One face.
        face1: usize,
        /// The other face.
        face2: usize,
    },
    /// More than two faces meet at an edge.
    #[error("edge {a}-{b} is shared by more than two faces: the surface is not a manifold")]
    NonManifoldEdge {
        /// One end.
        a: u32,
        /// The other end.
        b: u32,
    },
    /// The faces around a vertex do not form a single fan.
    #[error(
        "the faces around vertex {vertex} form more than one fan: the surface is not a manifold there"
    )]
    NonManifoldVertex {
        /// The vertex index.
        vertex: u32,
    },
    /// A vertex that no face uses.
    #[error("vertex {vertex} is used by no face")]
    UnusedVertex {
        /// The vertex index.
        vertex: usize,
    },
    /// The faces form several separate pieces.
    #[error("the faces form {pieces} separate pieces; give each piece as its own body")]
    Disconnected {
        /// How many pieces.
        pieces: usize,
    },
    /// Every face is clockwise seen from outside.
    #[error(
        "the surface faces inward (volume {volume}): list each face's vertices counter-clockwise seen from outside"
    )]
    Inward {
        /// The signed volume.
        volume: f64,
    },
    /// Too many vertices or faces for 32-bit ids.
    #[error("too many elements: {what}")]
    TooLarge {
        /// What overflowed.
        what: &'static str,
    },
    /// The vertices span less than the smallest length (see [`crate::model::range`]).
    #[error(
        "the polyhedron is {extent:e} m across, below the smallest length of {min:e} m",
        min = crate::model::range::MIN_LENGTH
    )]
    TooSmall {
        /// The largest side of the vertices' bounding box.
        extent: f64,
    },
}

impl BuildError {
    /// Whether the refusal is about the world's range (see [`crate::model::range`]).
    pub fn is_out_of_range(&self) -> bool {
        matches!(self, BuildError::TooSmall { .. })
    }
}

impl Body {
    /// Builds a closed polyhedron from vertex loci and faces, each face a list of vertex
    /// indices counter-clockwise seen from outside. Serial numbers are taken for the
    /// vertices (in list order), then the faces (in list order), then the edges.
    ///
    /// Postconditions: one connected, closed, consistently and outward oriented body,
    /// whose handle count follows from its Euler characteristic; face `i` of the input is
    /// the face with the `i`-th face serial, vertex `j` the one with the `j`-th vertex
    /// serial. Faces need not be planar or convex; geometry is not checked beyond the
    /// sign of the volume.
    ///
    /// Refused with a [`BuildError`] (and no serials taken) for open, non-manifold,
    /// inconsistently oriented, disconnected or inward input, bad indices or numbers, or
    /// vertices that span less than [`crate::model::range::MIN_LENGTH`]. (Loci beyond the
    /// world's range are refused when the body enters a world.)
    pub fn from_polygons<F: AsRef<[u32]>>(
        serials: &mut Serials,
        positions: &[DVec3],
        faces: &[F],
    ) -> Result<Body, BuildError> {
        let plan = Plan::new(positions, faces)?;
        Ok(plan.build(serials, positions, faces))
    }
}

/// Everything checked and matched, before any serial is taken.
struct Plan {
    /// First half-edge of each face (prefix sums of face degrees).
    face_start: Vec<u32>,
    /// For each half-edge, its twin.
    twin: Vec<u32>,
    handles: u32,
}

impl Plan {
    fn new<F: AsRef<[u32]>>(positions: &[DVec3], faces: &[F]) -> Result<Plan, BuildError> {
        let nv = positions.len();
        if faces.is_empty() {
            return Err(BuildError::NoFaces);
        }
        if nv >= u32::MAX as usize / 2 {
            return Err(BuildError::TooLarge { what: "vertices" });
        }
        if let Some(vertex) = positions.iter().position(|p| !p.is_finite()) {
            return Err(BuildError::NonFinite { vertex });
        }
        // Half-edge h of face f runs from verts[h] to the next vertex of f.
        let mut face_start = Vec::with_capacity(faces.len() + 1);
        let mut total: usize = 0;
        for (fi, f) in faces.iter().enumerate() {
            let f = f.as_ref();
            face_start.push(total as u32);
            if f.len() < 3 {
                return Err(BuildError::FaceTooSmall {
                    face: fi,
                    degree: f.len(),
                });
            }
            for &i in f {
                if i as usize >= nv {
                    return Err(BuildError::IndexOutOfRange {
                        face: fi,
                        index: i,
                        count: nv,
                    });
                }
            }
            if f.len() <= 8 {
                for (k, &i) in f.iter().enumerate() {
                    if f[k + 1..].contains(&i) {
                        return Err(BuildError::RepeatedVertex {
                            face: fi,
                            vertex: i,
                        });
                    }
                }
            } else {
                let mut s = f.to_vec();
                s.sort_unstable();
                if let Some(w) = s.windows(2).find(|w| w[0] == w[1]) {
                    return Err(BuildError::RepeatedVertex {
                        face: fi,
                        vertex: w[0],
                    });
                }
            }
            total += f.len();
            if total >= u32::MAX as usize / 2 {
                return Err(BuildError::TooLarge {
                    what: "face corners",
                });
            }
        }
        face_start.push(total as u32);
        let nh = total;
        let mut face_of = Vec::with_capacity(nh);
        let mut src = Vec::with_capacity(nh);
        let mut dst = Vec::with_capacity(nh);
        for (fi, f) in faces.iter().enumerate() {
            let f = f.as_ref();
            for k in 0..f.len() {
                face_of.push(fi as u32);
                src.push(f[k]);
                dst.push(f[(k + 1) % f.len()]);
            }
        }
        // Outgoing half-edges of each vertex, as compressed rows.
        let mut out_start = vec![0u32; nv + 1];
        for &a in &src {
            out_start[a as usize + 1] += 1;
        }
        for i in 0..nv {
            out_start[i + 1] += out_start[i];
        }
        if let Some(vertex) = (0..nv).find(|&i| out_start[i] == out_start[i + 1]) {
            return Err(BuildError::UnusedVertex { vertex });
        }
        let mut fill = out_start.clone();
        let mut outgoing = vec![0u32; nh];
        for (h, &a) in src.iter().enumerate() {
            outgoing[fill[a as usize] as usize] = h as u32;
            fill[a as usize] += 1;
        }
        drop(fill);
        // Match each half-edge a→b with the one half-edge b→a.
        let mut twin = vec![u32::MAX; nh];
        for h in 0..nh {
            let (a, b) = (src[h], dst[h]);
            let row = &outgoing[out_start[a as usize] as usize..out_start[a as usize + 1] as usize];
            for &o in row {
                if o as usize != h && dst[o as usize] == b {
                    return Err(BuildError::Inconsistent {
                        a,
                        b,
                        face1: face_of[h] as usize,
                        face2: face_of[o as usize] as usize,
                    });
                }
            }
            if twin[h] != u32::MAX {
                continue;
            }
            let row = &outgoing[out_start[b as usize] as usize..out_start[b as usize + 1] as usize];
            let mut found = None;
            for &o in row {
                if dst[o as usize] == a {
                    if found.is_some() {
                        return Err(BuildError::NonManifoldEdge { a, b });
                    }
                    found = Some(o);
                }
            }
            match found {
                Some(o) => {
                    twin[h] = o;
                    twin[o as usize] = h as u32;
                }
                None => {
                    return Err(BuildError::Open {
                        a,
                        b,
                        face: face_of[h] as usize,
                    });
                }
            }
        }
        // Each vertex's fan: walking twin-then-next about the vertex must meet all of its
        // outgoing half-edges.
        let next_in_face = |h: usize| -> usize {
            let f = face_of[h] as usize;
            if h + 1 == face_start[f + 1] as usize {
                face_start[f] as usize
            } else {
                h + 1
            }
        };
        for v in 0..nv {
            let first = outgoing[out_start[v] as usize] as usize;
            let want = (out_start[v + 1] - out_start[v]) as usize;
            let mut h = first;
            let mut count = 0;
            loop {
                count += 1;
                h = next_in_face(twin[h] as usize);
                if h == first || count > want {
                    break;
                }
            }
            if count != want {
                return Err(BuildError::NonManifoldVertex { vertex: v as u32 });
            }
        }
        // One piece.
        let mut parent: Vec<u32> = (0..nv as u32).collect();
        fn root(p: &mut [u32], mut x: u32) -> u32 {
            while p[x as usize] != x {
                p[x as usize] = p[p[x as usize] as usize];
                x = p[x as usize];
            }
            x
        }
        for h in 0..nh {
            let (x, y) = (root(&mut parent, src[h]), root(&mut parent, dst[h]));
            if x != y {
                parent[x as usize] = y;
            }
        }
        let pieces = (0..nv as u32)
            .filter(|&i| root(&mut parent, i) == i)
            .count();
        if pieces != 1 {
            return Err(BuildError::Disconnected { pieces });
        }
        let chi = faces.len() as i64 - (nh / 2) as i64 + nv as i64;
        let handles = ((2 - chi) / 2) as u32;
        // Orientation: the signed volume of the fans.
        let six_vol = crate::model::geometry::six_volume(positions, faces);
        if six_vol < 0.0 {
            return Err(BuildError::Inward {
                volume: six_vol / 6.0,
            });
        }
        let (lo, hi) = positions.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let extent = (hi - lo).max_element();
        if nv > 0 && extent < crate::model::range::MIN_LENGTH {
            return Err(BuildError::TooSmall {
                extent: extent.max(0.0),
            });
        }
        Ok(Plan {
            face_start,
            twin,
            handles,
        })
    }

    fn build<F: AsRef<[u32]>>(
        self,
        serials: &mut Serials,
        positions: &[DVec3],
        faces: &[F],
    ) -> Body {
        let nh = self.twin.len();
        let mut b = Body::empty();
        b.reserve(faces.len(), nh / 2, positions.len());
        let vids: Vec<VertexId> = positions
            .iter()
            .map(|&p| b.mkv(serials, p, EdgeId::NONE))
            .collect();
        let fids: Vec<FaceId> = (0..faces.len())
            .map(|_| b.mkf(serials, EdgeId::NONE))
            .collect();
        // The use each half-edge becomes: the lower-numbered half of a pair is the P use.
        let mut use_of = vec![EdgeUse::new(EdgeId::NONE, Side::P); nh];
        for (fi, f) in faces.iter().enumerate() {
            let f = f.as_ref();
            let start = self.face_start[fi] as usize;
            for k in 0..f.len() {
                let h = start + k;
                let t = self.twin[h] as usize;
                if h < t {
                    let (a, bb) = (vids[f[k] as usize], vids[f[(k + 1) % f.len()] as usize]);
                    let e = b.mke(serials, Edge::unlinked([bb, a], [FaceId::NONE, fids[fi]]));
                    use_of[h] = EdgeUse::new(e, Side::P);
                    use_of[t] = EdgeUse::new(e, Side::N);
                }
            }
        }
        for (fi, f) in faces.iter().enumerate() {
            let f = f.as_ref();
            let start = self.face_start[fi] as usize;
            let n = f.len();
            b.face_mut(fids[fi]).ped = use_of[start].edge;
            for k in 0..n {
                let u = use_of[start + k];
                let w = use_of[start + (k + 1) % n];
                b.edge_mut(u.edge).face[u.side.ix()] = fids[fi];
                b.set_next(u, w);
                b.vertex_mut(vids[f[k] as usize]).ped = u.edge;
            }
        }
        b.handles = self.handles;
        b
    }
}
