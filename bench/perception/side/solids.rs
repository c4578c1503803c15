//! The bodies the perception benchmark looks at, their masks by ray casting pixel
//! centres (independent of winged's renderer), and the cameras that see them.

use std::f64::consts::PI;

use glam::{DQuat, DVec2, DVec3};
use rayon::prelude::*;
use winged::model::camera::{Camera, Intrinsics};
use winged::model::geometry::fibonacci_sphere as fibonacci;
use winged::vision::image::Mask;

use crate::rng::Rng;

/// Image width, pixels.
pub const WIDTH: u32 = 640;
/// Image height, pixels.
pub const HEIGHT: u32 = 480;
/// Focal length, pixels: a body's bounding sphere seen from 5 radii is 204 px in radius.
pub const FOCAL: f64 = 1000.0;
/// Cameras stand this many bounding radii from the body's centre.
pub const DISTANCE: f64 = 5.0;
/// How far sample points of a body's surface are pulled into it, metres.
pub const PULL: f64 = 1e-9;

/// A body's shape in its own frame, centred on its bounding box's centre.
#[derive(Clone, Debug)]
pub enum Shape {
    /// Disjoint axis-aligned boxes (least and greatest corners).
    Boxes(Vec<(DVec3, DVec3)>),
    /// A convex polyhedron of triangles, counter-clockwise seen from outside.
    Convex {
        /// Vertex loci.
        positions: Vec<DVec3>,
        /// Triangles.
        triangles: Vec<[usize; 3]>,
    },
    /// A ball about the origin, of this radius.
    Ball(f64),
}

/// A body placed in the world: its shape turned by `rotation` about the origin.
#[derive(Clone, Debug)]
pub struct Solid {
    /// The scene's name.
    pub name: String,
    /// The shape.
    pub shape: Shape,
    /// The body's turn about the origin.
    pub rotation: DQuat,
    /// Distances from the origin to the nearest face plane and to the farthest vertex,
    /// for a convex polyhedron (rays through the inner sphere hit; rays past the outer
    /// sphere miss).
    spheres: (f64, f64),
}

impl Solid {
    /// A body of `shape` turned by `rotation`.
    pub fn new(name: &str, shape: Shape, rotation: DQuat) -> Solid {
        let spheres = match &shape {
            Shape::Convex {
                positions,
                triangles,
            } => {
                let inner = triangles
                    .iter()
                    .map(|t| {
                        let [a, b, c] = t.map(|i| positions[i]);
                        (b - a).cross(c - a).normalize().dot(a)
                    })
                    .fold(f64::INFINITY, f64::min);
                let outer = positions.iter().map(|p| p.length()).fold(0.0, f64::max);
                (inner, outer)
            }
            _ => (0.0, 0.0),
        };
        Solid {
            name: name.to_string(),
            shape,
            rotation,
            spheres,
        }
    }

    /// The radius of the sphere about the origin that holds the body.
    pub fn radius(&self) -> f64 {
        match &self.shape {
            Shape::Boxes(boxes) => boxes
                .iter()
                .flat_map(|&(lo, hi)| corners(lo, hi))
                .map(DVec3::length)
                .fold(0.0, f64::max),
            Shape::Convex { .. } => self.spheres.1,
            Shape::Ball(r) => *r,
        }
    }

    /// The body's volume.
    pub fn volume(&self) -> f64 {
        match &self.shape {
            Shape::Boxes(boxes) => boxes
                .iter()
                .map(|(lo, hi)| (*hi - *lo).element_product())
                .sum(),
            Shape::Convex {
                positions,
                triangles,
            } => {
                triangles
                    .iter()
                    .map(|t| {
                        let [a, b, c] = t.map(|i| positions[i]);
                        a.dot(b.cross(c))
                    })
                    .sum::<f64>()
                    / 6.0
            }
            Shape::Ball(r) => 4.0 / 3.0 * PI * r * r * r,
        }
    }

    /// Whether the ray from `o` along `d` (world) meets the body in front of `o`.
    pub fn hit(&self, o: DVec3, d: DVec3) -> bool {
        let turn = self.rotation.inverse();
        let (o, d) = (turn * o, turn * d);
        // Every shape lies in the sphere of its radius: a ray that misses it misses.
        let radius = self.radius();
        let (b, c) = (o.dot(d) / d.length_squared(), o.length_squared());
        let gap = c - b * b * d.length_squared();
        if gap > radius * radius || (b > 0.0 && c > radius * radius) {
            return false;
        }
        match &self.shape {
            Shape::Boxes(boxes) => boxes.iter().any(|&(lo, hi)| {
                let inv = d.recip();
                let (a, b) = ((lo - o) * inv, (hi - o) * inv);
                let t0 = a.min(b).max_element();
                let t1 = a.max(b).min_element();
                t1 >= t0.max(0.0)
            }),
            Shape::Convex {
                positions,
                triangles,
            } => {
                if gap < self.spheres.0 * self.spheres.0 {
                    return true;
                }
                triangles
                    .iter()
                    .any(|t| ray_meets_triangle(o, d, t.map(|i| positions[i])))
            }
            Shape::Ball(r) => gap <= r * r,
        }
    }

    /// Whether the world point `p` is inside the body.
    pub fn contains(&self, p: DVec3) -> bool {
        let p = self.rotation.inverse() * p;
        match &self.shape {
            Shape::Boxes(boxes) => boxes
                .iter()
                .any(|&(lo, hi)| p.cmpge(lo).all() && p.cmple(hi).all()),
            Shape::Convex {
                positions,
                triangles,
            } => triangles.iter().all(|t| {
                let [a, b, c] = t.map(|i| positions[i]);
                (b - a).cross(c - a).dot(p - a) <= 0.0
            }),
            Shape::Ball(r) => p.length_squared() <= r * r,
        }
    }

    /// Points of the body's surface pulled into it by [`PULL`], in the world: for boxes
    /// a 5 × 5 grid on each face of each box (corners and edge midpoints among them);
    /// for a convex polyhedron its vertices, edge midpoints and face centroids; for a
    /// ball 2,000 points spread evenly over its sphere.
    pub fn surface_samples(&self) -> Vec<DVec3> {
        let body: Vec<DVec3> = match &self.shape {
            Shape::Boxes(boxes) => boxes
                .iter()
                .flat_map(|&(lo, hi)| {
                    let (lo, hi) = (lo + PULL, hi - PULL);
                    let mut out = Vec::new();
                    let steps = [0.0, 0.25, 0.5, 0.75, 1.0];
                    for axis in 0..3 {
                        for side in [lo[axis], hi[axis]] {
                            for s in steps {
                                for t in steps {
                                    let mut p = lo + (hi - lo) * 0.5;
                                    let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
                                    p[axis] = side;
                                    p[a] = lo[a] + (hi[a] - lo[a]) * s;
                                    p[b] = lo[b] + (hi[b] - lo[b]) * t;
                                    out.push(p);
                                }
                            }
                        }
                    }
                    out
                })
                .collect(),
            Shape::Convex {
                positions,
                triangles,
            } => {
                let mut out = Vec::new();
                for t in triangles {
                    let [a, b, c] = t.map(|i| positions[i]);
                    let inward = -(b - a).cross(c - a).normalize();
                    for p in [a, (a + b) * 0.5, (a + b + c) / 3.0] {
                        out.push(p + inward * PULL);
                    }
                }
                // Vertices and edge midpoints are pulled in along every face they
                // touch, which is inside all of them.
                out
            }
            Shape::Ball(r) => fibonacci(2000)
                .into_iter()
                .map(|d| d * (r - PULL))
                .collect(),
        };
        body.into_iter().map(|p| self.rotation * p).collect()
    }

    /// `n` points drawn uniformly inside the body (rejection in its bounding cube).
    pub fn interior_samples(&self, n: usize, rng: &mut Rng) -> Vec<DVec3> {
        let r = self.radius();
        let mut out = Vec::with_capacity(n);
        while out.len() < n {
            let p = DVec3::new(rng.range(-r, r), rng.range(-r, r), rng.range(-r, r));
            if self.contains(p) {
                out.push(p);
            }
        }
        out
    }
}

/// The eight corners of a box.
fn corners(lo: DVec3, hi: DVec3) -> [DVec3; 8] {
    std::array::from_fn(|i| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// Whether the ray from `o` along `d` meets the triangle in front of `o` (Möller and
/// Trumbore), edges included.
fn ray_meets_triangle(o: DVec3, d: DVec3, [a, b, c]: [DVec3; 3]) -> bool {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return false;
    }
    let s = (o - a) / det;
    let u = s.dot(p);
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = s.cross(e1);
    let v = d.dot(q);
    v >= 0.0 && u + v <= 1.0 && e2.dot(q) > 0.0
}

/// The benchmark's scenes: a box, an L-prism, a square frame, a 320-triangle sphere
/// and a ball, each centred on the origin.
pub fn scenes() -> Vec<Solid> {
    let still = DQuat::IDENTITY;
    vec![
        Solid::new(
            "box",
            Shape::Boxes(vec![(
                DVec3::new(-0.1, -0.07, -0.05),
                DVec3::new(0.1, 0.07, 0.05),
            )]),
            still,
        ),
        Solid::new("l_prism", l_prism(0.1, 0.1, 0.05, 0.5, 0.5), still),
        Solid::new("frame", frame(0.1, 0.05, 0.02), still),
        Solid::new("sphere320", icosphere(0.1, 2), still),
        Solid::new("ball", Shape::Ball(0.1), still),
    ]
}

/// The scene of this name.
pub fn scene(name: &str) -> Option<Solid> {
    scenes().into_iter().find(|s| s.name == name)
}

/// An L-prism in the box of half-sizes `sx`, `sy`, `sz`: the full slab below the
/// fraction `b` of its height in y, and the part left of the fraction `a` of its width
/// in x above it (the notch is the upper right).
pub fn l_prism(sx: f64, sy: f64, sz: f64, a: f64, b: f64) -> Shape {
    let ym = -sy + 2.0 * sy * b;
    let xm = -sx + 2.0 * sx * a;
    Shape::Boxes(vec![
        (DVec3::new(-sx, -sy, -sz), DVec3::new(sx, ym, sz)),
        (DVec3::new(-sx, ym, -sz), DVec3::new(xm, sy, sz)),
    ])
}

/// A square frame in the z = 0 plane: outer half-size `outer`, a square hole of
/// half-size `hole`, half-thickness `half_thick`.
pub fn frame(outer: f64, hole: f64, half_thick: f64) -> Shape {
    let (o, h, t) = (outer, hole, half_thick);
    Shape::Boxes(vec![
        (DVec3::new(-o, -o, -t), DVec3::new(o, -h, t)),
        (DVec3::new(-o, h, -t), DVec3::new(o, o, t)),
        (DVec3::new(-o, -h, -t), DVec3::new(-h, h, t)),
        (DVec3::new(h, -h, -t), DVec3::new(o, h, t)),
    ])
}

/// An icosahedron of circumradius `radius` with each triangle cut into four
/// `subdivisions` times, new vertices pushed out onto the sphere (20 · 4ⁿ triangles).
pub fn icosphere(radius: f64, subdivisions: u32) -> Shape {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut positions: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize() * radius)
    .collect();
    let mut triangles: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut middle = std::collections::HashMap::new();
        let mut mid = |a: usize, b: usize, positions: &mut Vec<DVec3>| {
            *middle.entry((a.min(b), a.max(b))).or_insert_with(|| {
                positions.push((positions[a] + positions[b]).normalize() * radius);
                positions.len() - 1
            })
        };
        let mut next = Vec::with_capacity(triangles.len() * 4);
        for [a, b, c] in triangles {
            let (ab, bc, ca) = (
                mid(a, b, &mut positions),
                mid(b, c, &mut positions),
                mid(c, a, &mut positions),
            );
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = next;
    }
    for t in &mut triangles {
        let [a, b, c] = t.map(|i| positions[i]);
        if (b - a).cross(c - a).dot(a + b + c) < 0.0 {
            t.swap(1, 2);
        }
    }
    Shape::Convex {
        positions,
        triangles,
    }
}

/// A camera at `distance` from the origin along `direction`, looking at the origin
/// (image up toward +z, or +x when the view is within 26° of the z axis).
pub fn camera_toward(direction: DVec3, distance: f64) -> Camera {
    let intrinsics = Intrinsics::centered(WIDTH, HEIGHT, FOCAL).expect("intrinsics");
    let up = if direction.z.abs() > 0.9 {
        DVec3::X
    } else {
        DVec3::Z
    };
    Camera::look_at(direction * distance, DVec3::ZERO, up, intrinsics).expect("camera")
}

/// `n` cameras on the Fibonacci sphere of radius [`DISTANCE`] × `solid`'s radius.
pub fn cameras(solid: &Solid, n: usize) -> Vec<Camera> {
    let distance = DISTANCE * solid.radius();
    fibonacci(n)
        .into_iter()
        .map(|d| camera_toward(d, distance))
        .collect()
}

/// The mask of `solid` seen by `camera`: a pixel is inside when the ray through its
/// centre meets the solid.
pub fn draw(solid: &Solid, camera: &Camera) -> Mask {
    let k = camera.intrinsics;
    let o = camera.position();
    let bits: Vec<bool> = (0..k.height)
        .into_par_iter()
        .flat_map_iter(|y| {
            (0..k.width).map(move |x| {
                let d = camera.pixel_ray(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
                solid.hit(o, d)
            })
        })
        .collect();
    Mask::from_bits(k.width, k.height, bits).expect("a mask of the image's size")
}
