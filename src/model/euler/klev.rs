//! KLEV and KLVE: kill an edge and a vertex, merging two vertices.

use super::EulerError;
use crate::model::body::Body;
use crate::model::ids::{EdgeId, Side, VertexId};
use crate::model::topology::EdgeUse;

impl Body {
    /// KLEV(V): kills vertex `v` and its edge PED(V). With one edge at `v` this removes
    /// a spur or a wire's end; with two it undoes an edge split, leaving the other edge
    /// spanning both neighbours. Returns the surviving neighbour vertex.
    ///
    /// Preconditions (refused otherwise): `v` is live with one or two edges, and its two
    /// neighbours (valence two) are not already joined by another edge.
    ///
    /// Inverse of [`Body::esplit`] (`klev(VNEW)` restores E exactly) and of
    /// [`Body::mkev`].
    pub fn klev(&mut self, v: VertexId) -> Result<VertexId, EulerError> {
        self.check_vertex(v)?;
        let k = self.vertex(v).ped;
        if k.is_none() {
            return Err(EulerError::NoEdges {
                vertex: self.vertex_serial(v),
            });
        }
        let valence = self.vertex_uses(v).take(3).count();
        if valence > 2 {
            return Err(EulerError::Valence {
                vertex: self.vertex_serial(v),
                valence: self.valence(v),
            });
        }
        let keep = self.other_vertex(k, v).unwrap_or(v);
        if let Some(loop_edge) = self.other_edge_joining(v, keep, k) {
            return Err(self.loop_error(v, keep, loop_edge));
        }
        if self.edge(k).vt[0] != v {
            self.invert(k);
        }
        self.contract(k);
        Ok(keep)
    }

    /// KLVE(E): kills edge `e` and its NVT, moving every other edge at NVT to PVT (the
    /// face–vertex dual of KLFE: it contracts the edge). Returns PVT(E), whose locus is
    /// kept.
    ///
    /// Preconditions (refused otherwise): `e` is live, and no other edge joins its two
    /// vertices (it would become a loop).
    ///
    /// Inverse: an [`Body::esplit`] of the right edge when NVT had valence two, or
    /// [`Body::mkev`] when it had one; in general a vertex split.
    pub fn klve(&mut self, e: EdgeId) -> Result<VertexId, EulerError> {
        self.check_edge(e)?;
        let r = *self.edge(e);
        let (keep, gone) = (r.vt[1], r.vt[0]);
        if let Some(loop_edge) = self.other_edge_joining(gone, keep, e) {
            return Err(self.loop_error(gone, keep, loop_edge));
        }
        self.contract(e);
        Ok(keep)
    }

    fn loop_error(&self, a: VertexId, b: VertexId, edge: EdgeId) -> EulerError {
        EulerError::WouldMakeLoop {
            a: self.vertex_serial(a),
            b: self.vertex_serial(b),
            edge: self.edge_serial(edge),
        }
    }

    /// Moves every edge at `gone` except `except` over to `keep` (sets its vertex there).
    /// Returns the first edge moved. Walks the fan without allocating: each step finds
    /// the next edge before changing the current one.
    fn move_fan(&mut self, gone: VertexId, keep: VertexId, except: EdgeId) -> Option<EdgeId> {
        let start = self.vertex_first_use(gone)?;
        let mut first = None;
        let mut u = start;
        loop {
            let next = self.ccw_about_origin(u);
            if u.edge != except {
                first.get_or_insert(u.edge);
                self.edge_mut(u.edge).vt[u.side.ix()] = keep;
            }
            // No loops: the fan is back at its start when it meets the start's edge.
            if next.edge == start.edge {
                break;
            }
            u = next;
        }
        first
    }

    /// Contracts edge `e` into its PVT: NVT and `e` die, NVT's other edges move to PVT.
    ///
    /// Precondition: checked by the callers (no other edge joins the two ends).
    fn contract(&mut self, e: EdgeId) {
        let r = *self.edge(e);
        let (keep, gone) = (r.vt[1], r.vt[0]);
        let (ep, en) = (EdgeUse::new(e, Side::P), EdgeUse::new(e, Side::N));
        let (pp, np) = (self.prev(ep), self.next(ep)); // arrives at keep / leaves gone
        let (pn, nn) = (self.prev(en), self.next(en)); // arrives at gone / leaves keep

        if np == en && pp == en {
            // The only edge of a wire: back to a seminal body.
            self.vertex_mut(keep).ped = EdgeId::NONE;
            self.face_mut(r.face[0]).ped = EdgeId::NONE;
            self.klv(gone);
            self.kle(e);
            return;
        }
        // Move the other edges at `gone` over to `keep` (walk before relinking).
        let first_moved = self.move_fan(gone, keep, e);
        if np == en {
            // `gone` was a spur tip.
            self.set_next(pp, nn);
        } else if nn == ep {
            // `keep` was a spur tip: its only edge was `e`.
            self.set_next(pn, np);
        } else {
            self.set_next(pp, np);
            self.set_next(pn, nn);
        }
        let alive_p = if np == en { nn.edge } else { np.edge };
        let alive_n = if nn == ep { np.edge } else { nn.edge };
        self.repoint_peds(e, alive_p, &[r.face[1]], &[]);
        self.repoint_peds(e, alive_n, &[r.face[0]], &[]);
        // Prefer an edge that came over from `gone`, so that KLEV after ESPLIT gives the
        // surviving vertex back its old PED.
        let keep_ped = first_moved.unwrap_or(alive_n);
        self.repoint_peds(e, keep_ped, &[], &[keep]);
        self.klv(gone);
        self.kle(e);
    }
}
