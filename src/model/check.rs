//! The validator: layered checks of a body, reporting every violation found.
//!
//! 1. **Ids**: every link names a live entity; no edge is a loop.
//! 2. **Wings**: each wing is reciprocal (the next edge about a face starts where this
//!    one ends, names this edge as its clockwise wing, and is in the same face); walking
//!    from each face's and vertex's PED closes, and meets every edge use of that face or
//!    vertex (so PED is on the perimeter and perimeters are single rings).
//! 3. **Euler**: F − E + V = 2(B − H) over the body's connected polyhedra, each of which
//!    has an even characteristic of at most 2.
//! 4. **Geometry** (solids only, [`check_solid`]): closed (no edge with one face on both
//!    sides, no face of fewer than three edges), faces planar within a tolerance (some
//!    plane, the Newell plane or one through three spanning vertices, holds every
//!    vertex within it) and of
//!    non-zero area, edges of non-zero length, and the surface oriented outward
//!    (positive volume).
//!
//! A level is checked only when the levels before it passed: the walks of level 2 are
//! meaningless on dead links.

use super::body::Body;
use super::ids::{EdgeId, FaceId, Side, VertexId};
use super::topology::EdgeUse;

/// One broken rule, naming the entities involved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Violation {
    /// A face's PED is dead, or is not an edge of that face.
    #[error("face {face:?}: PED {ped:?} is not a live edge of this face")]
    FacePed {
        /// The face.
        face: FaceId,
        /// Its PED.
        ped: EdgeId,
    },
    /// A vertex's PED is dead, or is not an edge at that vertex.
    #[error("vertex {vertex:?}: PED {ped:?} is not a live edge at this vertex")]
    VertexPed {
        /// The vertex.
        vertex: VertexId,
        /// Its PED.
        ped: EdgeId,
    },
    /// A face or vertex without edges in a body that has edges.
    #[error("{what} has no PED although the body has edges")]
    MissingPed {
        /// "face f3" or "vertex v2".
        what: String,
    },
    /// An edge link names a dead entity.
    #[error("edge {edge:?}: {field} names a dead entity")]
    DeadLink {
        /// The edge.
        edge: EdgeId,
        /// NVT, PVT, NFACE, PFACE, NCW, PCW, NCCW or PCCW.
        field: &'static str,
    },
    /// An edge whose two vertices are the same.
    #[error("edge {edge:?} is a loop: both ends are vertex {vertex:?}")]
    LoopEdge {
        /// The edge.
        edge: EdgeId,
        /// Its vertex.
        vertex: VertexId,
    },
    /// A wing that is not reciprocal.
    #[error("edge {edge:?} side {side:?}: {what}")]
    Wing {
        /// The edge.
        edge: EdgeId,
        /// The side whose wing is wrong.
        side: Side,
        /// What is wrong.
        what: &'static str,
    },
    /// Walking a face's perimeter from its PED does not close.
    #[error("face {face:?}: perimeter walk from PED does not close")]
    FaceOpen {
        /// The face.
        face: FaceId,
    },
    /// An edge lists a face that the face's perimeter ring does not reach.
    #[error("face {face:?}: edge {edge:?} names it but is not on its perimeter ring")]
    FaceMissesEdge {
        /// The face.
        face: FaceId,
        /// The edge.
        edge: EdgeId,
    },
    /// Walking about a vertex from its PED does not close.
    #[error("vertex {vertex:?}: perimeter walk from PED does not close")]
    VertexOpen {
        /// The vertex.
        vertex: VertexId,
    },
    /// An edge ends at a vertex that the vertex's perimeter ring does not reach.
    #[error("vertex {vertex:?}: edge {edge:?} ends here but is not on its perimeter ring")]
    VertexMissesEdge {
        /// The vertex.
        vertex: VertexId,
        /// The edge.
        edge: EdgeId,
    },
    /// F − E + V differs from 2(B − H).
    #[error("F−E+V = {chi} but 2(B−H) = 2({components}−{handles}) = {expected}")]
    Euler {
        /// F − E + V.
        chi: i64,
        /// Connected polyhedra B.
        components: i64,
        /// Recorded handles H.
        handles: i64,
        /// 2(B − H).
        expected: i64,
    },
    /// A connected polyhedron whose characteristic is odd or above 2.
    #[error("a connected polyhedron has F−E+V = {chi}, which no closed orientable surface has")]
    ComponentCharacteristic {
        /// Its F − E + V.
        chi: i64,
    },
    /// An edge with the same face on both sides, in a body that should be a solid.
    #[error("edge {edge:?} has face {face:?} on both sides: the surface is not closed")]
    NotClosed {
        /// The edge.
        edge: EdgeId,
        /// The face.
        face: FaceId,
    },
    /// A face of fewer than three edges in a solid.
    #[error("face {face:?} has only {degree} edges")]
    FaceTooSmall {
        /// The face.
        face: FaceId,
        /// Its edge count.
        degree: usize,
    },
    /// A face of zero area.
    #[error("face {face:?} has zero area")]
    DegenerateFace {
        /// The face.
        face: FaceId,
    },
    /// A face whose vertices stray from its plane.
    #[error("face {face:?} is not planar: a vertex is {deviation:e} m from its plane")]
    NonPlanar {
        /// The face.
        face: FaceId,
        /// The largest distance of a vertex from the face's plane: the Newell plane,
        /// or, when that is farther, the plane through three widely spanning vertices
        /// ([`Body::face_plane_spanning`]); a face is planar when either holds it.
        deviation: f64,
    },
    /// An edge of zero length.
    #[error("edge {edge:?} has zero length")]
    ZeroLengthEdge {
        /// The edge.
        edge: EdgeId,
    },
    /// The surface is oriented inward (negative volume).
    #[error("the surface faces inward: volume {volume}")]
    Inward {
        /// The signed volume.
        volume: f64,
    },
}

/// The outcome of a check: every violation found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Report {
    /// The violations, in the order found.
    pub violations: Vec<Violation>,
}

impl Report {
    /// Whether nothing was found.
    pub fn is_ok(&self) -> bool {
        self.violations.is_empty()
    }
}

impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.is_ok() {
            return write!(f, "valid");
        }
        for (i, v) in self.violations.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{v}")?;
        }
        Ok(())
    }
}

/// Checks levels 1–3 (ids, wings, Euler): what every body must satisfy, including
/// seminal, wire, lamina and spurred stages of a construction.
pub fn check_topology(body: &Body) -> Report {
    let mut out = Vec::new();
    check_ids(body, &mut out);
    if out.is_empty() {
        check_wings(body, &mut out);
    }
    if out.is_empty() {
        check_euler(body, &mut out);
    }
    Report { violations: out }
}

/// Checks all four levels, for a body that should be a closed, outward-facing solid.
/// `planarity_tol` is the largest distance (meters) a vertex may lie off its face's plane.
pub fn check_solid(body: &Body, planarity_tol: f64) -> Report {
    let mut report = check_topology(body);
    if report.is_ok() {
        check_geometry(body, planarity_tol, &mut report.violations);
    }
    report
}

fn check_ids(b: &Body, out: &mut Vec<Violation>) {
    let has_edges = b.edge_count() > 0;
    for f in b.faces() {
        let ped = b.face(f).ped;
        if ped.is_none() {
            if has_edges {
                out.push(Violation::MissingPed {
                    what: format!("face {f:?}"),
                });
            }
        } else if !b.has_edge(ped) || !b.edge(ped).face.contains(&f) {
            out.push(Violation::FacePed { face: f, ped });
        }
    }
    for v in b.vertices() {
        let ped = b.vertex(v).ped;
        if ped.is_none() {
            if has_edges {
                out.push(Violation::MissingPed {
                    what: format!("vertex {v:?}"),
                });
            }
        } else if !b.has_edge(ped) || !b.edge(ped).vt.contains(&v) {
            out.push(Violation::VertexPed { vertex: v, ped });
        }
    }
    for e in b.edges() {
        let r = b.edge(e);
        let names = [
            ("NVT", !b.has_vertex(r.vt[0])),
            ("PVT", !b.has_vertex(r.vt[1])),
            ("NFACE", !b.has_face(r.face[0])),
            ("PFACE", !b.has_face(r.face[1])),
            ("NCW", !b.has_edge(r.cw[0])),
            ("PCW", !b.has_edge(r.cw[1])),
            ("NCCW", !b.has_edge(r.ccw[0])),
            ("PCCW", !b.has_edge(r.ccw[1])),
        ];
        for (field, dead) in names {
            if dead {
                out.push(Violation::DeadLink { edge: e, field });
            }
        }
        if r.vt[0] == r.vt[1] {
            out.push(Violation::LoopEdge {
                edge: e,
                vertex: r.vt[0],
            });
        }
    }
}

fn use_ix(u: EdgeUse) -> usize {
    u.edge.index() * 2 + u.side.ix()
}

fn check_wings(b: &Body, out: &mut Vec<Violation>) {
    let mut ok = true;
    for e in b.edges() {
        for s in Side::BOTH {
            let r = b.edge(e);
            let (here, there) = (r.vt[s.ix()], r.vt[(!s).ix()]);
            let n = r.ccw[s.ix()];
            let rn = b.edge(n);
            if !rn.vt.contains(&there) {
                out.push(Violation::Wing {
                    edge: e,
                    side: s,
                    what: "CCW wing does not meet this edge where its use ends",
                });
                ok = false;
                continue;
            }
            let ns = b.side_at(n, there);
            if rn.cw[ns.ix()] != e {
                out.push(Violation::Wing {
                    edge: e,
                    side: s,
                    what: "CCW wing's CW wing does not point back",
                });
                ok = false;
            }
            if rn.face[ns.ix()] != r.face[s.ix()] {
                out.push(Violation::Wing {
                    edge: e,
                    side: s,
                    what: "CCW wing is in another face",
                });
                ok = false;
            }
            let p = r.cw[s.ix()];
            let rp = b.edge(p);
            if !rp.vt.contains(&here) {
                out.push(Violation::Wing {
                    edge: e,
                    side: s,
                    what: "CW wing does not meet this edge where its use starts",
                });
                ok = false;
                continue;
            }
            let ps = !b.side_at(p, here);
            if rp.ccw[ps.ix()] != e {
                out.push(Violation::Wing {
                    edge: e,
                    side: s,
                    what: "CW wing's CCW wing does not point back",
                });
                ok = false;
            }
        }
    }
    if !ok {
        return;
    }
    let budget = 2 * b.edges.slots() + 2;
    let mut seen = vec![false; 2 * b.edges.slots()];
    for f in b.faces() {
        let Some(start) = b.face_first_use(f) else {
            continue;
        };
        let mut u = start;
        let mut steps = 0;
        loop {
            seen[use_ix(u)] = true;
            u = b.next(u);
            steps += 1;
            if u == start {
                break;
            }
            if steps > budget {
                out.push(Violation::FaceOpen { face: f });
                break;
            }
        }
    }
    for e in b.edges() {
        for s in Side::BOTH {
            if !seen[use_ix(EdgeUse::new(e, s))] {
                out.push(Violation::FaceMissesEdge {
                    face: b.edge(e).face[s.ix()],
                    edge: e,
                });
            }
        }
    }
    seen.iter_mut().for_each(|x| *x = false);
    for v in b.vertices() {
        let Some(start) = b.vertex_first_use(v) else {
            continue;
        };
        let mut u = start;
        let mut steps = 0;
        loop {
            seen[use_ix(u)] = true;
            u = b.ccw_about_origin(u);
            steps += 1;
            if u == start {
                break;
            }
            if steps > budget || b.origin(u) != v {
                out.push(Violation::VertexOpen { vertex: v });
                break;
            }
        }
    }
    for e in b.edges() {
        for s in Side::BOTH {
            if !seen[use_ix(EdgeUse::new(e, s))] {
                out.push(Violation::VertexMissesEdge {
                    vertex: b.edge(e).vt[s.ix()],
                    edge: e,
                });
            }
        }
    }
}

/// Union-find over vertex slots.
fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        parent[x as usize] = parent[parent[x as usize] as usize];
        x = parent[x as usize];
    }
    x
}

fn check_euler(b: &Body, out: &mut Vec<Violation>) {
    let n = b.vertices.slots();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    for e in b.edges() {
        let r = b.edge(e);
        let (x, y) = (find(&mut parent, r.vt[0].0), find(&mut parent, r.vt[1].0));
        if x != y {
            parent[x as usize] = y;
        }
    }
    // Per component: F, E, V. Faces and edges join their first vertex's component; a
    // seminal face joins the seminal vertex's (a seminal body has exactly one of each).
    let mut chi = vec![0i64; n];
    let mut roots = Vec::new();
    let mut listed = vec![false; n];
    for v in b.vertices() {
        let r = find(&mut parent, v.0) as usize;
        if !listed[r] {
            listed[r] = true;
            roots.push(r);
        }
        chi[r] += 1;
    }
    for e in b.edges() {
        let r = find(&mut parent, b.edge(e).vt[0].0) as usize;
        chi[r] -= 1;
    }
    let seminal_vertex = b.vertices().find(|&v| b.vertex(v).ped.is_none());
    for f in b.faces() {
        let ped = b.face(f).ped;
        let v = if ped.is_none() {
            match seminal_vertex {
                Some(v) => v,
                None => continue,
            }
        } else {
            b.edge(ped).vt[0]
        };
        let r = find(&mut parent, v.0) as usize;
        chi[r] += 1;
    }
    for &r in &roots {
        if chi[r] > 2 || chi[r] % 2 != 0 {
            out.push(Violation::ComponentCharacteristic { chi: chi[r] });
        }
    }
    let total = b.euler_characteristic();
    let components = roots.len() as i64;
    let handles = b.handles() as i64;
    let expected = 2 * (components - handles);
    if total != expected {
        out.push(Violation::Euler {
            chi: total,
            components,
            handles,
            expected,
        });
    }
}

/// The largest distance of a vertex of face `f` from `plane`.
fn deviation_from(b: &Body, f: FaceId, plane: super::geometry::Plane) -> f64 {
    b.face_vertices(f)
        .map(|v| plane.distance(b.position(v)).abs())
        .fold(0.0, f64::max)
}

fn check_geometry(b: &Body, tol: f64, out: &mut Vec<Violation>) {
    for e in b.edges() {
        let r = b.edge(e);
        if r.face[0] == r.face[1] {
            out.push(Violation::NotClosed {
                edge: e,
                face: r.face[0],
            });
        }
        if b.edge_length(e) <= 0.0 {
            out.push(Violation::ZeroLengthEdge { edge: e });
        }
    }
    for f in b.faces() {
        let degree = b.face_degree(f);
        if degree < 3 {
            out.push(Violation::FaceTooSmall { face: f, degree });
            continue;
        }
        match b.face_plane_accurate(f) {
            None => out.push(Violation::DegenerateFace { face: f }),
            Some(plane) => {
                let mut deviation = deviation_from(b, f, plane);
                if deviation > tol
                    && let Some(spanning) = b.face_plane_spanning(f)
                {
                    deviation = deviation.min(deviation_from(b, f, spanning));
                }
                if deviation > tol {
                    out.push(Violation::NonPlanar { face: f, deviation });
                }
            }
        }
    }
    if b.face_count() > 0 {
        let volume = b.volume();
        if volume <= 0.0 || volume.is_nan() {
            out.push(Violation::Inward { volume });
        }
    }
}

#[cfg(test)]
mod tests {
    //! Each rule, broken on purpose.

    use glam::DVec3;

    use super::*;
    use crate::model::ids::Serials;
    use crate::model::solids::mkcube;

    fn cube() -> Body {
        mkcube(&mut Serials::new(), 2.0, 2.0, 2.0).unwrap()
    }

    #[test]
    fn a_cube_is_valid_at_every_level() {
        let b = cube();
        assert!(check_solid(&b, 1e-12).is_ok());
    }

    #[test]
    fn a_dead_face_ped_is_reported() {
        let mut b = cube();
        let f = b.faces().next().unwrap();
        b.face_mut(f).ped = EdgeId::from_index(999);
        let r = check_topology(&b);
        assert!(matches!(r.violations[..], [Violation::FacePed { face, .. }] if face == f));
    }

    #[test]
    fn a_vertex_ped_off_the_vertex_is_reported() {
        let mut b = cube();
        let v = b.vertices().next().unwrap();
        let e = b.edges().find(|&e| !b.edge(e).vt.contains(&v)).unwrap();
        b.vertex_mut(v).ped = e;
        let r = check_topology(&b);
        assert!(matches!(r.violations[..], [Violation::VertexPed { vertex, .. }] if vertex == v));
    }

    #[test]
    fn a_loop_edge_and_a_dead_link_are_both_reported() {
        let mut b = cube();
        let es: Vec<EdgeId> = b.edges().collect();
        let (e1, e2) = (es[0], es[1]);
        let v = b.edge(e1).vt[0];
        b.edge_mut(e1).vt[1] = v;
        b.edge_mut(e2).cw[0] = EdgeId::NONE;
        let r = check_topology(&b);
        assert!(r.violations.contains(&Violation::LoopEdge {
            edge: e1,
            vertex: v
        }));
        assert!(r.violations.contains(&Violation::DeadLink {
            edge: e2,
            field: "NCW"
        }));
    }

    #[test]
    fn a_wing_that_does_not_point_back_is_reported() {
        let mut b = cube();
        let e = b.edges().next().unwrap();
        // Point PCCW at the edge's own PCW: it meets the edge at PVT, not at NVT.
        let wrong = b.edge(e).cw[1];
        b.edge_mut(e).ccw[1] = wrong;
        let r = check_topology(&b);
        assert!(
            r.violations
                .iter()
                .any(|v| matches!(v, Violation::Wing { edge, side: Side::P, .. } if *edge == e)),
            "{r}"
        );
    }

    #[test]
    fn a_wrong_face_on_an_edge_is_reported() {
        let mut b = cube();
        let e = b.edges().next().unwrap();
        let other = b.faces().find(|f| !b.edge(e).face.contains(f)).unwrap();
        b.edge_mut(e).face[0] = other;
        let r = check_topology(&b);
        assert!(!r.is_ok());
        assert!(
            r.violations.iter().any(
                |v| matches!(v, Violation::Wing { what, .. } if what.contains("another face"))
            )
        );
    }

    #[test]
    fn a_wrong_handle_count_breaks_euler() {
        let mut b = cube();
        b.handles = 1;
        let r = check_topology(&b);
        assert_eq!(
            r.violations,
            vec![Violation::Euler {
                chi: 2,
                components: 1,
                handles: 1,
                expected: 0
            }]
        );
    }

    #[test]
    fn two_bodies_in_one_arena_count_as_two_components() {
        let mut a = cube();
        let b = cube();
        a.absorb(b);
        // F−E+V = 4 = 2(B−H) with B = 2: consistent until a handle is claimed.
        assert!(check_topology(&a).is_ok());
        a.handles = 1;
        let r = check_topology(&a);
        assert!(
            r.violations
                .iter()
                .any(|v| matches!(v, Violation::Euler { components: 2, .. }))
        );
    }

    #[test]
    fn a_bent_face_is_not_planar() {
        let mut b = cube();
        let v = b.vertices().next().unwrap();
        let p = b.position(v);
        b.set_position(v, p * 1.1);
        let r = check_solid(&b, 1e-9);
        assert!(check_topology(&b).is_ok());
        assert_eq!(
            r.violations
                .iter()
                .filter(|v| matches!(v, Violation::NonPlanar { .. }))
                .count(),
            3,
            "the three faces at the moved corner: {r}"
        );
    }

    #[test]
    fn an_everted_cube_faces_inward() {
        let mut b = cube();
        b.evert();
        assert!(check_topology(&b).is_ok());
        let r = check_solid(&b, 1e-9);
        assert!(
            matches!(r.violations[..], [Violation::Inward { volume }] if (volume + 8.0).abs() < 1e-9)
        );
    }

    #[test]
    fn a_lamina_is_valid_topology_but_not_a_closed_solid() {
        let mut s = Serials::new();
        let (mut b, f, v1) = Body::seminal(&mut s, DVec3::ZERO);
        let (_, v2) = b.mkev(&mut s, f, v1, DVec3::X).unwrap();
        let (_, v3) = b.mkev(&mut s, f, v2, DVec3::new(1.0, 1.0, 0.0)).unwrap();
        b.mkfe(&mut s, v1, f, v3).unwrap();
        assert!(check_topology(&b).is_ok());
        let r = check_solid(&b, 1e-9);
        assert!(!r.is_ok());
        // A lamina encloses nothing: zero volume.
        assert!(
            r.violations
                .iter()
                .any(|v| matches!(v, Violation::Inward { .. }))
        );
    }

    #[test]
    fn a_spur_is_not_closed_and_a_collapsed_edge_has_zero_length() {
        let mut s = Serials::new();
        let mut b = cube();
        let f = b.faces().next().unwrap();
        let v = b.face_vertices(f).next().unwrap();
        let p = b.position(v);
        let (spur, _) = b.mkev(&mut s, f, v, p).unwrap();
        let r = check_solid(&b, 1e-9);
        assert!(r.violations.contains(&Violation::NotClosed {
            edge: spur,
            face: f
        }));
        assert!(
            r.violations
                .contains(&Violation::ZeroLengthEdge { edge: spur })
        );
    }

    #[test]
    fn the_report_reads_as_text() {
        let mut b = cube();
        b.handles = 3;
        let text = check_topology(&b).to_string();
        assert!(text.contains("F−E+V = 2"), "{text}");
        assert_eq!(check_topology(&cube()).to_string(), "valid");
    }
}
