//! Spatial queries against a brute-force oracle.
//!
//! The oracle knows nothing of the index: it walks every vertex, edge and face of every
//! body in world coordinates, and tells inside from outside by the generalised winding
//! number (solid angles), not by ray parity. Worlds are random mixes of boxes, convex
//! and concave prisms, spheres and tetrahedra, some of them parts of others, turned
//! about random axes.

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::{DQuat, DVec2, DVec3};
use winged::model::solids::{box_solid, mktetra, prism_solid, sphere};
use winged::model::{BodyId, Pose, World, WorldError};
use winged::spatial::exact::{
    clip_segment_ball, clip_segment_box, drop_axis, in_polygon, segment_closest,
};
use winged::spatial::{
    BodyHit, BoxQuery, DEFAULT_MAX_FEATURES, Detail, QueryError, Spatial, SphereQuery,
};

/// A small deterministic generator (PCG-style LCG), so failures replay.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    fn vec(&mut self, lo: f64, hi: f64) -> DVec3 {
        DVec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
    fn rotation(&mut self) -> DQuat {
        let axis = self.vec(-1.0, 1.0).try_normalize().unwrap_or(DVec3::Z);
        DQuat::from_axis_angle(axis, self.range(-3.0, 3.0))
    }
}

fn random_world(seed: u64, bodies: usize) -> World {
    let mut rng = Rng(seed);
    let mut w = World::new();
    let mut ids: Vec<BodyId> = Vec::new();
    for i in 0..bodies {
        let supart = if i > 2 && rng.next() < 0.3 {
            ids[(rng.next() * ids.len() as f64) as usize]
        } else {
            w.root()
        };
        let spread = if supart == w.root() { 12.0 } else { 3.0 };
        let pose = Pose::new(rng.vec(-spread, spread), rng.rotation()).expect("unit rotation");
        let kind = (rng.next() * 5.0) as usize;
        let size = rng.vec(0.5, 3.0);
        let id = match kind {
            0 => w.insert_with(None, supart, pose, |s| box_solid(s, size)),
            1 => {
                // An L: concave.
                let (a, b) = (size.x, size.y);
                let l = [
                    DVec2::new(0.0, 0.0),
                    DVec2::new(a, 0.0),
                    DVec2::new(a, b * 0.4),
                    DVec2::new(a * 0.4, b * 0.4),
                    DVec2::new(a * 0.4, b),
                    DVec2::new(0.0, b),
                ];
                w.insert_with(None, supart, pose, |s| prism_solid(s, &l, size.z))
            }
            2 => {
                // A five-pointed star: concave with many reflex corners.
                let star: Vec<DVec2> = (0..10)
                    .map(|k| {
                        let a = std::f64::consts::TAU * k as f64 / 10.0;
                        let r = if k % 2 == 0 { size.x } else { size.x * 0.45 };
                        DVec2::new(r * a.cos(), r * a.sin())
                    })
                    .collect();
                w.insert_with(None, supart, pose, |s| prism_solid(s, &star, size.z))
            }
            3 => w.insert_with(None, supart, pose, |s| sphere(s, size.x, 12, 7)),
            _ => w.insert_with(None, supart, pose, |s| {
                mktetra(s, size.x).map_err(WorldError::from)
            }),
        };
        ids.push(id.expect("insert"));
    }
    w
}

/// What the oracle says of one body.
#[derive(Debug)]
struct Truth {
    inside: bool,
    distance: f64,
    faces: BTreeMap<u64, f64>,
    edges: BTreeMap<u64, [DVec3; 2]>,
    vertices: BTreeMap<u64, DVec3>,
}

/// The generalised winding number of a closed surface about `p` (1 inside, 0 outside).
fn winding(polys: &[Vec<DVec3>], p: DVec3) -> f64 {
    let mut total = 0.0;
    for poly in polys {
        for i in 1..poly.len().saturating_sub(1) {
            let (a, b, c) = (poly[0] - p, poly[i] - p, poly[i + 1] - p);
            let (la, lb, lc) = (a.length(), b.length(), c.length());
            let num = a.dot(b.cross(c));
            let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
            total += 2.0 * num.atan2(den);
        }
    }
    total / (4.0 * std::f64::consts::PI)
}

/// Each face of body `id` as (serial, world loci of its perimeter).
fn world_polys(w: &World, id: BodyId) -> Vec<(u64, Vec<DVec3>)> {
    let pose = w.world_pose(id).expect("live");
    let b = w.body(id).expect("live");
    b.faces()
        .map(|f| {
            let pts = b
                .face_uses(f)
                .map(|u| pose.transform_point(b.position(b.origin(u))))
                .collect();
            (b.face_serial(f).get(), pts)
        })
        .collect()
}

fn face_distance(pts: &[DVec3], p: DVec3) -> f64 {
    let mut n = DVec3::ZERO;
    for i in 0..pts.len() {
        n += pts[i].cross(pts[(i + 1) % pts.len()]);
    }
    let n = n.normalize();
    let mut best = f64::INFINITY;
    for i in 0..pts.len() {
        best = best.min(segment_closest(p, pts[i], pts[(i + 1) % pts.len()]).0);
    }
    let centre = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
    let pd = n.dot(p - centre);
    let foot = p - n * pd;
    if pd * pd < best && in_polygon(foot, pts.iter().copied(), drop_axis(n)) {
        best = pd * pd;
    }
    best.sqrt()
}

/// The oracle's answer for a ball.
fn ball_truth(w: &World, c: DVec3, r: f64) -> BTreeMap<u64, Truth> {
    let mut out = BTreeMap::new();
    for (id, node) in w.bodies() {
        if node.body.vertex_count() == 0 {
            continue;
        }
        let pose = w.world_pose(id).expect("live");
        let b = &node.body;
        let polys = world_polys(w, id);
        let mut t = Truth {
            inside: winding(&polys.iter().map(|p| p.1.clone()).collect::<Vec<_>>(), c) > 0.5,
            distance: f64::INFINITY,
            faces: BTreeMap::new(),
            edges: BTreeMap::new(),
            vertices: BTreeMap::new(),
        };
        for v in b.vertices() {
            let p = pose.transform_point(b.position(v));
            if (p - c).length_squared() <= r * r {
                t.vertices.insert(b.vertex_serial(v).get(), p);
            }
        }
        for e in b.edges() {
            let [n, p] = b.edge(e).vt;
            let (a, z) = (
                pose.transform_point(b.position(n)),
                pose.transform_point(b.position(p)),
            );
            if let Some((t0, t1)) = clip_segment_ball(a, z, c, r) {
                t.edges
                    .insert(b.edge_serial(e).get(), [a + (z - a) * t0, a + (z - a) * t1]);
            }
        }
        for (serial, pts) in &polys {
            let d = face_distance(pts, c);
            if d <= r {
                t.faces.insert(*serial, d);
                t.distance = t.distance.min(d);
            }
        }
        if t.inside {
            t.distance = 0.0;
        }
        if t.inside || !t.faces.is_empty() {
            out.insert(id.get(), t);
        }
    }
    out
}

fn close(a: DVec3, b: DVec3) -> bool {
    (a - b).length() <= 1e-9 * (1.0 + a.length())
}

/// Checks the index's sphere answer against the oracle's.
fn check_sphere(index: &Spatial, w: &World, c: DVec3, r: f64) -> usize {
    let answer = index
        .sphere(&SphereQuery::new(c, r).with_detail(Detail::Features))
        .expect("valid query");
    let truth = ball_truth(w, c, r);
    // Nearest first, ties by id.
    for pair in answer.bodies.windows(2) {
        let key = |b: &winged::spatial::BodyHit| (b.distance.expect("a distance"), b.id);
        assert!(
            key(&pair[0]).partial_cmp(&key(&pair[1])) == Some(std::cmp::Ordering::Less),
            "{:?} before {:?} at {c} r {r}",
            key(&pair[0]),
            key(&pair[1])
        );
    }
    let got: Vec<u64> = {
        let mut v: Vec<u64> = answer.bodies.iter().map(|b| b.id).collect();
        v.sort_unstable();
        v
    };
    let want: Vec<u64> = truth.keys().copied().collect();
    assert_eq!(got, want, "bodies in the ball at {c} r {r}");
    for hit in &answer.bodies {
        let t = &truth[&hit.id];
        assert_eq!(hit.inside, t.inside, "inside of {} at {c} r {r}", hit.id);
        let d = hit.distance.expect("sphere answers carry distances");
        assert!(
            (d - t.distance).abs() <= 1e-9,
            "distance of {}: {d} vs {}",
            hit.id,
            t.distance
        );
        let faces = listed(&hit.faces, |f| f.id);
        assert_eq!(
            faces,
            t.faces.keys().copied().collect::<Vec<_>>(),
            "faces of {}",
            hit.id
        );
        for f in hit.faces.as_ref().expect("features") {
            assert!((f.distance.expect("distance") - t.faces[&f.id]).abs() <= 1e-9);
        }
        let edges = hit.edges.as_ref().expect("features");
        assert_eq!(
            edges.iter().map(|e| e.id).collect::<Vec<_>>(),
            t.edges.keys().copied().collect::<Vec<_>>(),
            "edges of {}",
            hit.id
        );
        for e in edges {
            let s = t.edges[&e.id];
            assert!(
                close(e.segment[0], s[0]) && close(e.segment[1], s[1]),
                "edge {} clipped {:?} vs {:?}",
                e.id,
                e.segment,
                s
            );
        }
        let vertices = hit.vertices.as_ref().expect("features");
        assert_eq!(
            vertices.iter().map(|v| v.id).collect::<Vec<_>>(),
            t.vertices.keys().copied().collect::<Vec<_>>(),
            "vertices of {}",
            hit.id
        );
        for v in vertices {
            assert!(close(v.position, t.vertices[&v.id]));
        }
    }
    // At `bodies` detail (where small convex bodies take their own path): the same
    // bodies, inside flags and distances.
    let bodies = index
        .sphere(&SphereQuery::new(c, r).with_detail(Detail::Bodies))
        .expect("valid query");
    let mut got: Vec<(u64, bool, f64)> = bodies
        .bodies
        .iter()
        .map(|b| (b.id, b.inside, b.distance.expect("distance")))
        .collect();
    got.sort_unstable_by_key(|b| b.0);
    assert_eq!(
        got.iter().map(|b| b.0).collect::<Vec<_>>(),
        want,
        "bodies at `bodies` detail in the ball at {c} r {r}"
    );
    for (id, inside, d) in got {
        let t = &truth[&id];
        assert_eq!(inside, t.inside, "inside of {id} at `bodies` detail");
        assert!(
            (d - t.distance).abs() <= 1e-9,
            "distance of {id} at `bodies` detail: {d} vs {}",
            t.distance
        );
    }
    answer.bodies.len()
}

#[test]
fn sphere_queries_match_the_brute_force_oracle_on_random_worlds() {
    let mut hits = 0;
    let mut inside = 0;
    for seed in 1..=6u64 {
        let w = Arc::new(random_world(seed, 40));
        let index = Spatial::build(w.clone());
        let mut rng = Rng(seed * 7919);
        // Half the centres near a body's origin, so that many fall inside solids.
        let origins: Vec<DVec3> = w
            .bodies()
            .filter(|(_, n)| n.body.vertex_count() > 0)
            .filter_map(|(id, _)| w.world_pose(id).map(|p| p.position))
            .collect();
        for k in 0..150 {
            let c = if k % 2 == 0 {
                rng.vec(-14.0, 14.0)
            } else {
                origins[(rng.next() * origins.len() as f64) as usize] + rng.vec(-0.6, 0.6)
            };
            let r = rng.range(0.05, 4.0);
            hits += check_sphere(&index, &w, c, r);
            inside += index
                .sphere(&SphereQuery::new(c, r).with_detail(Detail::Bodies))
                .expect("valid")
                .bodies
                .iter()
                .filter(|b| b.inside)
                .count();
        }
    }
    // The worlds are dense enough that the test says something.
    assert!(hits > 300, "only {hits} body hits");
    assert!(inside > 20, "only {inside} centres inside bodies");
}

#[test]
fn detail_levels_agree_on_the_bodies() {
    let w = Arc::new(random_world(99, 40));
    let index = Spatial::build(w);
    let mut rng = Rng(5);
    for _ in 0..100 {
        let c = rng.vec(-14.0, 14.0);
        let r = rng.range(0.1, 4.0);
        let ids = |d: Detail| -> Vec<(u64, bool)> {
            index
                .sphere(&SphereQuery::new(c, r).with_detail(d))
                .expect("valid")
                .bodies
                .iter()
                .map(|b| (b.id, b.inside))
                .collect()
        };
        let bodies = ids(Detail::Bodies);
        assert_eq!(bodies, ids(Detail::Features));
        assert_eq!(bodies, ids(Detail::Portions));
    }
}

/// Checks a box query at `features` detail against the brute-force oracle; answers the
/// number of bodies hit.
fn check_box(index: &Spatial, w: &World, lo: DVec3, hi: DVec3) -> usize {
    let answer = index.aabb(&BoxQuery::new(lo, hi)).expect("valid");
    // The oracle: vertices inside, edges clipped by slabs, and bodies touched by
    // either or holding the box's centre.
    let centre = (lo + hi) * 0.5;
    let mut want: BTreeMap<u64, (Vec<u64>, Vec<u64>, bool)> = BTreeMap::new();
    for (id, node) in w.bodies() {
        if node.body.vertex_count() == 0 {
            continue;
        }
        let pose = w.world_pose(id).expect("live");
        let b = &node.body;
        let vs: Vec<u64> = b
            .vertices()
            .filter(|&v| {
                let p = pose.transform_point(b.position(v));
                p.cmpge(lo).all() && p.cmple(hi).all()
            })
            .map(|v| b.vertex_serial(v).get())
            .collect();
        let mut es: Vec<u64> = b
            .edges()
            .filter(|&e| {
                let [n, p] = b.edge(e).vt;
                clip_segment_box(
                    pose.transform_point(b.position(n)),
                    pose.transform_point(b.position(p)),
                    lo,
                    hi,
                )
                .is_some()
            })
            .map(|e| b.edge_serial(e).get())
            .collect();
        es.sort_unstable();
        let polys: Vec<Vec<DVec3>> = world_polys(w, id).into_iter().map(|p| p.1).collect();
        let inside = winding(&polys, centre) > 0.5;
        let mut vs = vs;
        vs.sort_unstable();
        want.insert(id.get(), (vs, es, inside));
    }
    for hit in &answer.bodies {
        let (vs, es, inside) = &want[&hit.id];
        assert_eq!(hit.inside, *inside, "inside of {}", hit.id);
        let got_v = listed(&hit.vertices, |v| v.id);
        let got_e = listed(&hit.edges, |e| e.id);
        assert_eq!(&got_v, vs, "vertices of {} in {lo}..{hi}", hit.id);
        assert_eq!(&got_e, es, "edges of {} in {lo}..{hi}", hit.id);
    }
    // Every body with an edge or a vertex in the box, or holding it, is answered.
    let answered: Vec<u64> = answer.bodies.iter().map(|b| b.id).collect();
    for (id, (vs, es, inside)) in &want {
        if !vs.is_empty() || !es.is_empty() || *inside {
            assert!(answered.contains(id), "body {id} missing from {lo}..{hi}");
        }
    }
    answer.bodies.len()
}

#[test]
fn box_queries_match_the_brute_force_oracle() {
    let mut hits = 0;
    for seed in 11..=14u64 {
        let w = Arc::new(random_world(seed, 40));
        let index = Spatial::build(w.clone());
        let mut rng = Rng(seed);
        for _ in 0..100 {
            let lo = rng.vec(-14.0, 12.0);
            let hi = lo + rng.vec(0.05, 5.0);
            hits += check_box(&index, &w, lo, hi);
        }
    }
    assert!(hits > 100, "only {hits} hits");
}

/// The ids of a list of features an answer at `features` detail gives.
fn listed<T>(list: &Option<Vec<T>>, id: impl Fn(&T) -> u64) -> Vec<u64> {
    list.as_ref().expect("features").iter().map(id).collect()
}

/// The faces, edges and vertices a body's answer lists.
fn feature_count(b: &BodyHit) -> usize {
    b.faces.as_ref().map_or(0, Vec::len)
        + b.edges.as_ref().map_or(0, Vec::len)
        + b.vertices.as_ref().map_or(0, Vec::len)
}

/// Queries that reach more bodies than the index reads ahead at once (64) answer as
/// the oracle does, and a budget of features that runs out past the first bodies still
/// refuses the query.
#[test]
fn queries_reaching_many_bodies_match_the_oracle_and_keep_their_budget() {
    let w = Arc::new(random_world(21, 200));
    let index = Spatial::build(w.clone());
    let mut rng = Rng(21);
    let mut most = 0;
    for _ in 0..8 {
        let c = rng.vec(-4.0, 4.0);
        most = most.max(check_sphere(&index, &w, c, rng.range(14.0, 30.0)));
        let lo = rng.vec(-30.0, -10.0);
        let hi = rng.vec(10.0, 30.0);
        most = most.max(check_box(&index, &w, lo, hi));
    }
    assert!(most > 2 * 64, "at most {most} bodies in one answer");

    let q = SphereQuery::new(DVec3::ZERO, 40.0).with_detail(Detail::Features);
    budget_holds(|max_features| {
        index
            .sphere(&SphereQuery { max_features, ..q })
            .map(|a| a.bodies)
    });
    let q = BoxQuery::new(DVec3::splat(-40.0), DVec3::splat(40.0));
    budget_holds(|max_features| {
        index
            .aabb(&BoxQuery { max_features, ..q })
            .map(|a| a.bodies)
    });
}

/// A query that `ask(budget)` runs, answered with more than 128 bodies within the
/// default budget, gives the same answer at a budget of exactly its features and is
/// refused one under it.
fn budget_holds(ask: impl Fn(usize) -> Result<Vec<BodyHit>, QueryError>) {
    let answer = ask(DEFAULT_MAX_FEATURES).expect("within the default budget");
    assert!(answer.len() > 2 * 64, "{} bodies", answer.len());
    let features: usize = answer.iter().map(feature_count).sum();
    assert_eq!(ask(features).as_ref(), Ok(&answer));
    assert_eq!(
        ask(features - 1),
        Err(QueryError::TooManyFeatures {
            limit: features - 1
        })
    );
}

#[test]
fn nearest_and_ray_match_the_brute_force_oracle() {
    let w = Arc::new(random_world(21, 40));
    let index = Spatial::build(w.clone());
    let mut rng = Rng(77);
    let all: Vec<(u64, Vec<Vec<DVec3>>)> = w
        .bodies()
        .filter(|(_, n)| n.body.vertex_count() > 0)
        .map(|(id, _)| {
            (
                id.get(),
                world_polys(&w, id).into_iter().map(|p| p.1).collect(),
            )
        })
        .collect();
    for _ in 0..200 {
        let p = rng.vec(-16.0, 16.0);
        let found = index
            .nearest(p, f64::INFINITY)
            .expect("valid")
            .hit
            .expect("a world has bodies");
        let mut best = (f64::INFINITY, 0u64);
        for (id, polys) in &all {
            let d = if winding(polys, p) > 0.5 {
                0.0
            } else {
                polys
                    .iter()
                    .map(|f| face_distance(f, p))
                    .fold(f64::INFINITY, f64::min)
            };
            if d < best.0 - 1e-12 {
                best = (d, *id);
            }
        }
        assert!(
            (found.distance - best.0).abs() <= 1e-9,
            "nearest to {p}: {} vs {}",
            found.distance,
            best.0
        );
        if !found.inside {
            assert!(((found.point - p).length() - found.distance).abs() <= 1e-9);
        }
        // A ray towards the nearest surface point hits a surface no farther than it.
        let d = rng.vec(-1.0, 1.0);
        let hit = index.ray(p, d, f64::INFINITY).expect("valid").hit;
        // The oracle: every face of every body.
        let dn = d.normalize();
        let mut first = f64::INFINITY;
        for (_, polys) in &all {
            for f in polys {
                let mut n = DVec3::ZERO;
                for i in 0..f.len() {
                    n += f[i].cross(f[(i + 1) % f.len()]);
                }
                let n = n.normalize();
                let centre = f.iter().copied().sum::<DVec3>() / f.len() as f64;
                let den = n.dot(dn);
                if den == 0.0 {
                    continue;
                }
                let t = n.dot(centre - p) / den;
                if t >= 0.0 && in_polygon(p + dn * t, f.iter().copied(), drop_axis(n)) {
                    first = first.min(t);
                }
            }
        }
        match hit {
            Some(h) => {
                assert!(
                    (h.distance - first).abs() <= 1e-9 * (1.0 + first),
                    "ray from {p}: {} vs {first}",
                    h.distance
                );
                assert!(close(h.point, p + dn * h.distance));
            }
            None => assert!(first.is_infinite(), "ray from {p} missed a face at {first}"),
        }
    }
}

#[test]
fn touching_and_tangent_spheres_are_found_with_their_single_points() {
    let mut w = World::new();
    let root = w.root();
    let id = w
        .insert_with(Some("cube"), root, Pose::default(), |s| {
            box_solid(s, DVec3::splat(2.0))
        })
        .expect("insert");
    let index = Spatial::build(Arc::new(w));
    let q = |c: DVec3, r: f64| {
        index
            .sphere(&SphereQuery::new(c, r))
            .expect("valid")
            .bodies
            .into_iter()
            .find(|b| b.id == id.get())
    };
    // Touching the face x = 1 at one point.
    let touch = q(DVec3::new(2.0, 0.0, 0.0), 1.0).expect("touching counts");
    assert_eq!(touch.distance, Some(1.0));
    assert!(!touch.inside);
    assert_eq!(touch.faces.as_ref().map(Vec::len), Some(1));
    assert!(touch.edges.as_ref().is_some_and(Vec::is_empty));
    // Just apart.
    assert!(q(DVec3::new(2.0, 0.0, 0.0), 0.999_999_999).is_none());
    // Tangent to the edge x = y = 1 at its midpoint (the segment–sphere quadratic has a
    // double root): the edge clips to that one point, and both its faces touch there.
    let tangent = q(DVec3::new(2.0, 1.0, 0.0), 1.0).expect("tangent counts");
    let edges = tangent.edges.expect("features");
    assert_eq!(edges.len(), 1);
    assert_eq!(edges[0].segment, [DVec3::new(1.0, 1.0, 0.0); 2]);
    assert_eq!(tangent.faces.as_ref().map(Vec::len), Some(2));
    assert!(tangent.vertices.as_ref().is_some_and(Vec::is_empty));
    // Touching the vertex (1, 1, 1) from straight above: the vertex, its three edges as
    // single points, its three faces.
    let corner = q(DVec3::new(1.0, 1.0, 2.0), 1.0).expect("touching a vertex counts");
    assert_eq!(corner.vertices.as_ref().map(Vec::len), Some(1));
    assert_eq!(corner.edges.as_ref().map(Vec::len), Some(3));
    assert_eq!(corner.faces.as_ref().map(Vec::len), Some(3));
    // A centre inside: distance 0 and inside, even with a ball too small to reach a face.
    let deep = q(DVec3::new(0.1, -0.2, 0.3), 0.01).expect("a ball inside the solid meets it");
    assert!(deep.inside);
    assert_eq!(deep.distance, Some(0.0));
    assert!(deep.faces.as_ref().is_some_and(Vec::is_empty));
    // On the surface counts as inside.
    let on = q(DVec3::new(1.0, 0.2, 0.3), 0.0).expect("a point on the surface");
    assert!(on.inside);
    assert_eq!(on.distance, Some(0.0));
}

#[test]
fn portions_lie_in_the_face_and_the_ball_within_the_tolerance() {
    let w = Arc::new(random_world(31, 30));
    let index = Spatial::build(w);
    let mut rng = Rng(3);
    let mut portions = 0;
    for _ in 0..60 {
        let c = rng.vec(-12.0, 12.0);
        let r = rng.range(0.5, 4.0);
        let mut q = SphereQuery::new(c, r).with_detail(Detail::Portions);
        q.tolerance = 1e-3;
        let answer = index.sphere(&q).expect("valid");
        assert_eq!(answer.tolerance, Some(1e-3));
        for b in &answer.bodies {
            for f in b.faces.as_ref().expect("faces") {
                for l in f.portion.as_ref().expect("portions") {
                    portions += 1;
                    for p in l {
                        // Inside the ball (chords lie inside the circle they follow).
                        assert!(
                            (*p - c).length() <= r * (1.0 + 1e-9) + 1e-9,
                            "{p} outside the ball"
                        );
                    }
                }
            }
        }
    }
    assert!(portions > 50, "only {portions} portions");
}

#[test]
fn moving_bodies_between_queries_the_answers_follow() {
    let mut w = random_world(41, 40);
    let mut index = Spatial::build(Arc::new(w.clone()));
    let mut rng = Rng(8);
    let ids: Vec<BodyId> = w
        .bodies()
        .filter(|(_, n)| n.body.vertex_count() > 0)
        .map(|(id, _)| id)
        .collect();
    for round in 0..30 {
        // Move a few bodies (parts follow their suparts), edit one's geometry, then
        // bring the index up by the list of touched bodies (odd rounds) or by a full
        // comparison (even rounds).
        let mut touched = Vec::new();
        for _ in 0..3 {
            let id = ids[(rng.next() * ids.len() as f64) as usize];
            if w.node(id).is_none() {
                continue;
            }
            let pose = Pose::new(rng.vec(-12.0, 12.0), rng.rotation()).expect("unit");
            w.set_pose(id, pose).expect("pose");
            touched.push(id);
        }
        if round % 5 == 4 {
            let id = ids[round];
            if w.node(id).is_some() {
                let dilate = winged::model::Transform::Dilate {
                    factor: 1.5,
                    center: DVec3::ZERO,
                };
                w.transform(
                    id,
                    winged::model::Entity::Body,
                    &dilate,
                    winged::model::Frame::Body,
                )
                .expect("dilate");
                touched.push(id);
            }
        }
        if round % 7 == 6 {
            let id = ids[round + 1];
            if w.node(id).is_some() {
                let killed = w.kill(id).expect("kill");
                touched.extend(killed.ids());
            }
        }
        let snapshot = Arc::new(w.clone());
        let stats = if round % 2 == 1 {
            index.sync(snapshot.clone(), Some(&touched))
        } else {
            index.sync(snapshot.clone(), None)
        };
        assert!(
            stats.moved + stats.shaped + stats.removed > 0,
            "round {round}: {stats:?}"
        );
        assert_eq!(index.revision(), snapshot.revision());
        let fresh = Spatial::build(snapshot.clone());
        for _ in 0..20 {
            let c = rng.vec(-14.0, 14.0);
            let r = rng.range(0.1, 4.0);
            check_sphere(&index, &snapshot, c, r);
            let q = SphereQuery::new(c, r);
            assert_eq!(index.sphere(&q), fresh.sphere(&q), "round {round}");
        }
    }
}

#[test]
fn bad_queries_are_refused() {
    let index = Spatial::build(Arc::new(random_world(1, 3)));
    let nan = f64::NAN;
    assert!(index.sphere(&SphereQuery::new(DVec3::ZERO, -1.0)).is_err());
    assert!(index.sphere(&SphereQuery::new(DVec3::ZERO, nan)).is_err());
    assert!(
        index
            .sphere(&SphereQuery::new(DVec3::new(nan, 0.0, 0.0), 1.0))
            .is_err()
    );
    assert!(index.aabb(&BoxQuery::new(DVec3::ONE, DVec3::ZERO)).is_err());
    assert!(index.ray(DVec3::ZERO, DVec3::ZERO, f64::INFINITY).is_err());
    assert!(index.nearest(DVec3::ZERO, -1.0).is_err());
    let mut q = SphereQuery::new(DVec3::ZERO, 100.0);
    q.max_features = 3;
    assert!(index.sphere(&q).is_err());
}

/// The area of a planar loop (by its vector area).
fn loop_area(l: &[DVec3]) -> f64 {
    let mut n = DVec3::ZERO;
    for i in 0..l.len() {
        n += l[i].cross(l[(i + 1) % l.len()]);
    }
    n.length() * 0.5
}

#[test]
fn a_face_cut_by_a_sphere_has_the_disc_or_half_disc_as_its_portion() {
    let mut w = World::new();
    let root = w.root();
    let id = w
        .insert_with(None, root, Pose::default(), |s| {
            box_solid(s, DVec3::splat(4.0))
        })
        .expect("insert");
    let index = Spatial::build(Arc::new(w));
    let rho2 = 1.0 - 0.25;
    let tol = 1e-5;
    // (centre, the share of the disc inside the face x = 2)
    for (c, share) in [
        (DVec3::new(2.5, 0.0, 0.0), 1.0),
        (DVec3::new(2.5, 2.0, 0.0), 0.5),
    ] {
        let mut q = SphereQuery::new(c, 1.0).with_detail(Detail::Portions);
        q.tolerance = tol;
        let answer = index.sphere(&q).expect("valid");
        let body = answer
            .bodies
            .iter()
            .find(|b| b.id == id.get())
            .expect("hit");
        // The face x = 2: the one whose portion lies in that plane.
        let on_plane = |l: &Vec<DVec3>| l.iter().all(|p| (p.x - 2.0).abs() < 1e-12);
        let faces = body.faces.as_ref().expect("faces");
        let mut in_plane = faces
            .iter()
            .filter(|f| f.portion.as_ref().is_some_and(|ls| ls.iter().all(on_plane)));
        let face = in_plane.next().expect("the face x = 2");
        assert!(in_plane.next().is_none());
        assert_eq!(face.distance, Some(0.5));
        let loops = face.portion.as_ref().expect("portion");
        assert_eq!(loops.len(), 1);
        let area = loop_area(&loops[0]);
        let want = std::f64::consts::PI * rho2 * share;
        // Chords inside the circle lose at most perimeter × tolerance.
        assert!(
            area <= want + 1e-12 && area >= want - 2.0 * std::f64::consts::PI * tol,
            "{area} vs {want}"
        );
    }
}

#[test]
fn a_body_limit_refuses_an_answer_over_it() {
    let w = Arc::new(random_world(2, 40));
    let index = Spatial::build(w);
    let mut q = SphereQuery::new(DVec3::ZERO, 30.0).with_detail(Detail::Bodies);
    let all = index.sphere(&q).expect("no limit").bodies.len();
    assert!(all > 10);
    q.max_bodies = all;
    assert_eq!(index.sphere(&q).expect("at the limit").bodies.len(), all);
    q.max_bodies = all - 1;
    assert_eq!(
        index.sphere(&q),
        Err(QueryError::TooManyBodies { limit: all - 1 })
    );
}
