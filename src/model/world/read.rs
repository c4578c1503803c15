//! Reading the world: revision, bodies, poses, names, entities by serial.

use std::sync::Arc;

use glam::DVec3;

use crate::model::body::Body;
use crate::model::ids::{Serial, VertexId};
use crate::model::parts::{BodyId, BodyNode, Entity, PartsTree, Size};
use crate::model::pose::Pose;

use super::*;

impl World {
    /// The number of successful writes so far.
    #[inline]
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// The world body at the root of the parts tree.
    #[inline]
    pub fn root(&self) -> BodyId {
        self.tree.root()
    }

    /// The parts tree, for the questions it answers (subtrees, ancestors, checks).
    #[inline]
    pub fn tree(&self) -> &PartsTree {
        &self.tree
    }

    /// The serial number the next new entity will get.
    pub fn next_serial(&self) -> Serial {
        self.serials.peek()
    }

    /// Moves the revision forward to `revision` and the serial counter forward to
    /// `next_serial`, changing nothing else (each stays where it is if already past).
    ///
    /// For recovery that accepts a loss of acknowledged writes: the world continues at
    /// the revision and serial that clients were last told of, so that neither a
    /// revision nor an id is issued twice. Postcondition: `revision() >= revision` and
    /// `next_serial() >= next_serial`. There is no inverse.
    pub fn resume_at(&mut self, revision: u64, next_serial: Serial) {
        self.revision = self.revision.max(revision);
        if next_serial.0 > 0 {
            self.serials.skip_past(Serial(next_serial.0 - 1));
        }
    }

    /// The node of body `b`.
    pub fn node(&self, b: BodyId) -> Option<&BodyNode> {
        self.tree.get(b)
    }

    /// The polyhedron of body `b` (loci in its own frame).
    pub fn body(&self, b: BodyId) -> Option<&Body> {
        self.tree.get(b).map(|n| &*n.body)
    }

    /// The shared handle of body `b`'s polyhedron (for snapshots; see `Arc::ptr_eq`).
    pub fn body_arc(&self, b: BodyId) -> Option<&Arc<Body>> {
        self.tree.get(b).map(|n| &n.body)
    }

    /// The name of body `b`, if it has one.
    pub fn name(&self, b: BodyId) -> Option<&str> {
        self.tree.get(b).and_then(|n| n.name.as_deref())
    }

    /// SUPART(b).
    pub fn supart(&self, b: BodyId) -> Option<BodyId> {
        self.tree.supart(b)
    }

    /// The sub-parts of `b`, in attachment order.
    pub fn parts(&self, b: BodyId) -> Option<&imbl::Vector<BodyId>> {
        self.tree.parts(b)
    }

    /// `b`'s pose relative to its supart.
    pub fn pose(&self, b: BodyId) -> Option<Pose> {
        self.tree.get(b).map(|n| n.pose)
    }

    /// `b`'s pose in the world: its supart chain's poses composed, so turning a
    /// shoulder turns the whole arm.
    pub fn world_pose(&self, b: BodyId) -> Option<Pose> {
        self.tree.world_pose(b)
    }

    /// [`world_pose`](Self::world_pose) of `b` whose node, already looked up with
    /// [`node`](Self::node), is `node` (one lookup fewer). Precondition: `node` is
    /// `b`'s node.
    pub fn world_pose_of(&self, b: BodyId, node: &BodyNode) -> Pose {
        self.tree.world_pose_of(b, node)
    }

    /// The world locus of vertex `v` of body `b`.
    pub fn world_position(&self, b: BodyId, v: VertexId) -> Option<DVec3> {
        let node = self.tree.get(b)?;
        node.body
            .has_vertex(v)
            .then(|| self.tree.world_pose(b))
            .flatten()
            .map(|p| p.transform_point(node.body.position(v)))
    }

    /// FDNAME: the body with this name (the root is `"world"`).
    pub fn find_by_name(&self, name: &str) -> Option<BodyId> {
        self.tree.find_by_name(name)
    }

    /// Every body except the root, in id order.
    pub fn bodies(&self) -> impl Iterator<Item = (BodyId, &BodyNode)> + '_ {
        let root = self.root();
        self.tree.iter().filter(move |(id, _)| *id != root)
    }

    /// Number of bodies, not counting the root.
    pub fn body_count(&self) -> usize {
        self.tree.node_count() - 1
    }

    /// Faces, edges and vertices of all the bodies together. Constant time: kept as
    /// bodies are added, changed and removed.
    pub fn size(&self) -> Size {
        self.tree.size()
    }

    /// BGET by serial number: the live body, face, edge or vertex with serial `s`, and
    /// the body it belongs to. `None` for a serial never issued or whose entity was
    /// killed: serials are never reused, so a stale id never finds another entity.
    ///
    /// Cost: a map lookup, then a binary search in each body's serial index.
    pub fn find_entity(&self, s: Serial) -> Option<(BodyId, Entity)> {
        if s == Serial::NONE {
            return None;
        }
        if self.tree.contains(BodyId(s)) {
            return Some((BodyId(s), Entity::Body));
        }
        self.tree.iter().find_map(|(id, n)| {
            let b = &n.body;
            let e = if let Some(f) = b.face_by_serial(s) {
                Entity::Face(f)
            } else if let Some(e) = b.edge_by_serial(s) {
                Entity::Edge(e)
            } else {
                Entity::Vertex(b.vertex_by_serial(s)?)
            };
            Some((id, e))
        })
    }

    /// Many vertices by serial number at once: for each of `serials`, the body and
    /// vertex it names and the vertex's world locus, or `None` when it is no live vertex
    /// (never issued, killed, or a face, edge or body).
    ///
    /// Cost: one pass over the bodies, each passed over unless the range of its vertex
    /// serials holds a wanted one (a binary search), so O(bodies · log n + n · log V),
    /// where [`World::find_entity`] would be O(bodies) for each.
    pub fn find_vertices(&self, serials: &[Serial]) -> Vec<Option<(BodyId, VertexId, DVec3)>> {
        let mut out = vec![None; serials.len()];
        let mut wanted: Vec<(Serial, usize)> = serials
            .iter()
            .enumerate()
            .filter(|(_, s)| **s != Serial::NONE)
            .map(|(i, &s)| (s, i))
            .collect();
        wanted.sort_unstable();
        if wanted.is_empty() {
            return out;
        }
        for (id, node) in self.tree.iter() {
            let Some((lo, hi)) = node.body.vertex_serial_bounds() else {
                continue;
            };
            let start = wanted.partition_point(|(s, _)| *s < lo);
            let mut pose = None;
            for &(s, i) in wanted[start..].iter().take_while(|(s, _)| *s <= hi) {
                let Some(v) = node.body.vertex_by_serial(s) else {
                    continue;
                };
                let Some(p) = *pose.get_or_insert_with(|| self.tree.world_pose(id)) else {
                    continue;
                };
                out[i] = Some((id, v, p.transform_point(node.body.position(v))));
            }
        }
        out
    }
}
