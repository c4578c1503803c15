//! A closed polyhedron as polygons, each face with what made it: the form perception
//! carves, before it becomes a winged-edge [`Body`].

use glam::DVec3;

use crate::model::body::Body;
use crate::model::boolean::Map;
use crate::model::geometry;
use crate::model::ids::{Serial, Serials, VertexId};
use crate::model::solids::BuildError;

pub use crate::model::perceived::Maker;

/// A closed polyhedron as polygons.
///
/// Invariants (where a carving produced it): closed, manifold and consistently oriented,
/// faces counter-clockwise seen from outside, one connected piece; `makers[i]` made face
/// `i`.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Mesh {
    /// Vertex loci.
    pub positions: Vec<DVec3>,
    /// Faces, each a ring of indices into `positions`.
    pub faces: Vec<Vec<u32>>,
    /// What made each face.
    pub makers: Vec<Maker>,
}

impl Mesh {
    /// The volume enclosed (see [`geometry::six_volume`]).
    pub fn volume(&self) -> f64 {
        geometry::six_volume(&self.positions, &self.faces) / 6.0
    }

    /// The winding number about `x`: 1 inside, 0 outside (see
    /// [`geometry::winding_number`]).
    pub fn winding(&self, x: DVec3) -> f64 {
        geometry::winding_number(&self.positions, &self.faces, x)
    }

    /// The faces of `body` (one ring each, counter-clockwise seen from outside), in the
    /// order of their serials, their vertices placed by `place` (e.g. into the world's
    /// frame), each face made by what `maker` says of its serial.
    pub fn of_body(
        body: &Body,
        place: impl Fn(DVec3) -> DVec3,
        maker: impl Fn(Serial) -> Maker,
    ) -> Mesh {
        let mut faces: Vec<_> = body.faces().collect();
        faces.sort_by_key(|&f| body.face_serial(f));
        let mut index: Map<VertexId, u32> = Map::default();
        let mut mesh = Mesh::default();
        for f in faces {
            let ring = body
                .face_vertices(f)
                .map(|v| {
                    *index.entry(v).or_insert_with(|| {
                        mesh.positions.push(place(body.position(v)));
                        (mesh.positions.len() - 1) as u32
                    })
                })
                .collect();
            mesh.faces.push(ring);
            mesh.makers.push(maker(body.face_serial(f)));
        }
        mesh
    }

    /// The winged-edge body of these polygons (refused as [`Body::from_polygons`]
    /// refuses); face `i` of the body is face `i` here.
    pub fn to_body(&self, serials: &mut Serials) -> Result<Body, BuildError> {
        Body::from_polygons(serials, &self.positions, &self.faces)
    }

    /// The least and greatest corner of the vertices' bounding box.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.positions.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        )
    }

    /// The same faces split into their connected pieces (faces joined across edges),
    /// each with only the vertices it uses, in order of each piece's first face.
    pub fn pieces(self) -> Vec<Mesh> {
        let n = self.faces.len();
        let mut parent: Vec<usize> = (0..n).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        let mut by_edge = Map::default();
        for (i, f) in self.faces.iter().enumerate() {
            for k in 0..f.len() {
                let (a, b) = (f[k], f[(k + 1) % f.len()]);
                if let Some(j) = by_edge.insert((a.min(b), a.max(b)), i) {
                    let (ri, rj) = (root(&mut parent, i), root(&mut parent, j));
                    parent[ri] = rj;
                }
            }
        }
        let mut order: Vec<usize> = Vec::new();
        let mut piece_of = vec![usize::MAX; n];
        let mut pieces: Vec<Mesh> = Vec::new();
        let mut index: Vec<Map<u32, u32>> = Vec::new();
        for i in 0..n {
            let r = root(&mut parent, i);
            if piece_of[r] == usize::MAX {
                piece_of[r] = pieces.len();
                order.push(r);
                pieces.push(Mesh::default());
                index.push(Default::default());
            }
            let p = piece_of[r];
            let ring = self.faces[i]
                .iter()
                .map(|&v| {
                    *index[p].entry(v).or_insert_with(|| {
                        pieces[p].positions.push(self.positions[v as usize]);
                        (pieces[p].positions.len() - 1) as u32
                    })
                })
                .collect();
            pieces[p].faces.push(ring);
            pieces[p].makers.push(self.makers[i]);
        }
        pieces
    }
}
