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
        let uk = EdgeUse::new(k, self.side_at(k, v)); // v → keep along PED(v)
        let keep = self.dest(uk);
        let ue = self.ccw_about_origin(uk);
        if ue == uk {
            self.kill_spur_tip(uk);
            return Ok(keep);
        }
        if self.ccw_about_origin(ue) != uk {
            return Err(EulerError::Valence {
                vertex: self.vertex_serial(v),
                valence: self.valence(v),
            });
        }
        // Valence two: the only edge that could become a loop is the other one at v.
        if self.dest(ue) == keep {
            return Err(self.loop_error(v, keep, ue.edge));
        }
        self.unsplit(uk, ue);
        Ok(keep)
    }

    /// KLEV at a vertex of valence one: kills the spur (or wire end) `uk`, which runs
    /// from the tip to the vertex that stays.
    fn kill_spur_tip(&mut self, uk: EdgeUse) {
        let (k, tip, keep) = (uk.edge, self.origin(uk), self.dest(uk));
        let f = self.use_face(uk);
        let (before, after) = (self.prev(uk.twin()), self.next(uk));
        if before == uk {
            // The only edge of a wire: back to a seminal body.
            self.vertex_mut(keep).ped = EdgeId::NONE;
            self.face_mut(f).ped = EdgeId::NONE;
        } else {
            self.set_next(before, after);
            self.repoint_face_ped(f, k, after.edge);
            self.repoint_vertex_ped(keep, k, after.edge);
        }
        self.klv(tip);
        self.kle(k);
    }

    /// KLEV at a vertex of valence two: `uk` and `ue` leave it along its two edges; `uk`'s
    /// edge and the vertex die and `ue`'s edge takes over `uk`'s far end. Undoes ESPLIT
    /// exactly when `uk` is the split's new edge.
    fn unsplit(&mut self, uk: EdgeUse, ue: EdgeUse) {
        let (k, v, keep) = (uk.edge, self.origin(uk), self.dest(uk));
        let (face_a, face_b) = (self.use_face(uk), self.use_face(ue));
        let mut after = self.next(uk); // leaves keep in face A
        let mut before = self.prev(uk.twin()); // arrives at keep in face B
        // If keep is a spur tip, the turn at keep now goes round `ue`'s edge.
        if after == uk.twin() {
            after = ue;
        }
        if before == uk {
            before = ue.twin();
        }
        self.edge_mut(ue.edge).vt[ue.side.ix()] = keep;
        self.set_next(ue.twin(), after);
        self.set_next(before, ue);
        self.repoint_face_ped(face_a, k, ue.edge);
        self.repoint_face_ped(face_b, k, ue.edge);
        self.repoint_vertex_ped(keep, k, ue.edge);
        self.klv(v);
        self.kle(k);
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
        self.repoint_face_ped(r.face[1], e, alive_p);
        self.repoint_face_ped(r.face[0], e, alive_n);
        // Prefer an edge that came over from `gone`, so that KLEV after ESPLIT gives the
        // surviving vertex back its old PED.
        let keep_ped = first_moved.unwrap_or(alive_n);
        self.repoint_vertex_ped(keep, e, keep_ped);
        self.klv(gone);
        self.kle(e);
    }
}
