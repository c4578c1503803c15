//! The data of the spatial-access benchmarks, shared by `benches/spatial.rs` (winged
//! alone, under criterion) and `bench/spatial` (winged, rstar and parry3d side by side):
//! a heightfield terrain of 1,000,000 triangles closed into one solid, a city of
//! 100,000 boxes, the query centres, the radius calibration, the exact tests the peers
//! run on their candidates, and percentiles.
//!
//! Everything is generated from fixed seeds, so every run and every program sees the
//! same triangles, boxes and queries.

#![allow(dead_code)]

use std::collections::HashMap;
use std::sync::Arc;

use glam::{DQuat, DVec3};
use winged::model::solids::{BuildError, box_solid};
use winged::model::{Body, BodyId, Pose, Serials, World};
use winged::spatial::exact::{clip_segment_ball, drop_axis, in_polygon};
use winged::spatial::{Detail, Spatial, SphereQuery};

/// A small deterministic generator (SplitMix64).
pub struct Rng(u64);

impl Rng {
    /// A generator from `seed`.
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

// ---------------------------------------------------------------------------- terrain

/// Grid cells of the terrain: 1000 × 500 cells of 1 m, two triangles each.
pub const TERRAIN_NX: u32 = 1000;
/// See [`TERRAIN_NX`].
pub const TERRAIN_NY: u32 = 500;
/// Query centres stay this far inside the terrain's edges, so that balls of the radii
/// used meet top triangles only (never the side walls or the bottom).
pub const TERRAIN_MARGIN: f64 = 20.0;

/// The terrain's height at `(x, y)`: rolling hills with a finer ripple.
pub fn terrain_height(x: f64, y: f64) -> f64 {
    12.0 * (x / 61.0).sin() * (y / 43.0).cos()
        + 4.0 * ((x + 2.0 * y) / 17.0).sin()
        + 0.6 * (x / 3.1).sin() * (y / 2.7).sin()
}

/// A closed terrain solid: a triangulated height grid on top, four vertical side walls
/// (each one polygon running along the grid's edge) and a flat bottom.
pub struct Terrain {
    /// Vertex loci: the grid's `(nx + 1) × (ny + 1)` vertices row by row, then the four
    /// bottom corners.
    pub positions: Vec<DVec3>,
    /// The top surface: `2 · nx · ny` triangles, counter-clockwise seen from above.
    /// Triangle `i` is face `i` of the solid.
    pub triangles: Vec<[u32; 3]>,
    /// The side walls (front, right, back, left) and the bottom, faces
    /// `triangles.len() ..` of the solid.
    pub walls: Vec<Vec<u32>>,
    /// The terrain's extent in x and y: `(x0, y0)` to `(x1, y1)`.
    pub min: DVec3,
    /// See [`Terrain::min`].
    pub max: DVec3,
}

impl Terrain {
    /// The benchmark terrain (1,000,000 triangles).
    pub fn new() -> Terrain {
        Terrain::grid(TERRAIN_NX, TERRAIN_NY)
    }

    /// A terrain of `nx × ny` cells of 1 m.
    pub fn grid(nx: u32, ny: u32) -> Terrain {
        let row = nx + 1;
        let top = |i: u32, j: u32| j * row + i;
        let mut positions = Vec::with_capacity(((nx + 1) * (ny + 1) + 4) as usize);
        let mut zmin = f64::INFINITY;
        for j in 0..=ny {
            for i in 0..=nx {
                let (x, y) = (f64::from(i), f64::from(j));
                let z = terrain_height(x, y);
                zmin = zmin.min(z);
                positions.push(DVec3::new(x, y, z));
            }
        }
        let (x1, y1) = (f64::from(nx), f64::from(ny));
        let zb = zmin - 10.0;
        let b = positions.len() as u32;
        positions.extend([
            DVec3::new(0.0, 0.0, zb),
            DVec3::new(x1, 0.0, zb),
            DVec3::new(x1, y1, zb),
            DVec3::new(0.0, y1, zb),
        ]);
        let (b00, b10, b11, b01) = (b, b + 1, b + 2, b + 3);
        let mut triangles = Vec::with_capacity((2 * nx * ny) as usize);
        for j in 0..ny {
            for i in 0..nx {
                let (a, bb, c, e) = (top(i, j), top(i + 1, j), top(i + 1, j + 1), top(i, j + 1));
                // Alternate the diagonal so that the grid has no preferred direction.
                if (i + j) % 2 == 0 {
                    triangles.push([a, bb, c]);
                    triangles.push([a, c, e]);
                } else {
                    triangles.push([a, bb, e]);
                    triangles.push([bb, c, e]);
                }
            }
        }
        // Each wall runs along the bottom from left to right seen from outside, then
        // back along the grid's edge.
        let mut front = vec![b00, b10];
        front.extend((0..=nx).rev().map(|i| top(i, 0)));
        let mut right = vec![b10, b11];
        right.extend((0..=ny).rev().map(|j| top(nx, j)));
        let mut back = vec![b11, b01];
        back.extend((0..=nx).map(|i| top(i, ny)));
        let mut left = vec![b01, b00];
        left.extend((0..=ny).map(|j| top(0, j)));
        let bottom = vec![b00, b01, b11, b10];
        Terrain {
            positions,
            triangles,
            walls: vec![front, right, back, left, bottom],
            min: DVec3::new(0.0, 0.0, zb),
            max: DVec3::new(x1, y1, zmin + 40.0),
        }
    }

    /// The solid (faces in the order of [`Terrain::triangles`] then
    /// [`Terrain::walls`]).
    pub fn body(&self, serials: &mut Serials) -> Result<Body, BuildError> {
        let faces: Vec<&[u32]> = self
            .triangles
            .iter()
            .map(|t| t.as_slice())
            .chain(self.walls.iter().map(|w| w.as_slice()))
            .collect();
        Body::from_polygons(serials, &self.positions, &faces)
    }

    /// A world holding the terrain solid alone, with the serial of its first face (face
    /// `i` has serial `first + i`).
    pub fn world(&self) -> (World, BodyId, u64) {
        let mut world = World::new();
        let root = world.root();
        let id = world
            .insert_with(Some("terrain"), root, Pose::IDENTITY, |s| self.body(s))
            .expect("the terrain");
        let body = &world.node(id).expect("inserted").body;
        let first = body
            .faces()
            .map(|f| body.face_serial(f).get())
            .min()
            .expect("faces");
        (world, id, first)
    }

    /// Triangle `i`'s corners.
    #[inline]
    pub fn corners(&self, i: u32) -> [DVec3; 3] {
        self.triangles[i as usize].map(|v| self.positions[v as usize])
    }

    /// Bytes of the triangle data the peers' exact tests read (loci and triangles).
    pub fn mesh_bytes(&self) -> usize {
        self.positions.len() * 24 + self.triangles.len() * 12
    }

    /// `n` query centres near the surface (within ±0.3 m of it), at least
    /// [`TERRAIN_MARGIN`] inside the edges.
    pub fn centers(&self, n: usize, seed: u64) -> Vec<DVec3> {
        let mut rng = Rng::new(seed);
        (0..n)
            .map(|_| {
                let x = rng.range(TERRAIN_MARGIN, self.max.x - TERRAIN_MARGIN);
                let y = rng.range(TERRAIN_MARGIN, self.max.y - TERRAIN_MARGIN);
                DVec3::new(x, y, terrain_height(x, y) + rng.range(-0.3, 0.3))
            })
            .collect()
    }
}

impl Default for Terrain {
    fn default() -> Self {
        Terrain::new()
    }
}

/// Whether the closed ball of centre `c` and radius `r` meets the closed triangle
/// `t`: one of its sides enters the ball, or the foot of `c` on its plane is inside it
/// and within `r`. The same test winged runs on each face (built from the same
/// [`winged::spatial::exact`] functions), so that every index answers the same hits.
#[inline]
pub fn ball_meets_triangle(t: &[DVec3; 3], c: DVec3, r: f64) -> bool {
    for k in 0..3 {
        if clip_segment_ball(t[k], t[(k + 1) % 3], c, r).is_some() {
            return true;
        }
    }
    let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
    if n == DVec3::ZERO {
        return false;
    }
    let pd = n.dot(c - t[0]);
    if pd * pd > r * r {
        return false;
    }
    let foot = c - n * pd;
    in_polygon(foot, t.iter().copied(), drop_axis(n))
}

/// The axis-aligned box of the ball of centre `c` and radius `r`.
#[inline]
pub fn ball_box(c: DVec3, r: f64) -> (DVec3, DVec3) {
    (c - DVec3::splat(r), c + DVec3::splat(r))
}

// ------------------------------------------------------------------------------- city

/// Blocks of the city: a 400 × 250 grid of 100,000 boxes.
pub const CITY_NX: usize = 400;
/// See [`CITY_NX`].
pub const CITY_NY: usize = 250;
/// Distance between block centres, in metres.
pub const CITY_PITCH: f64 = 20.0;
/// Query centres stay this far inside the city's edges.
pub const CITY_MARGIN: f64 = 150.0;

/// One building: a box standing on the ground, turned about z.
#[derive(Clone, Copy, Debug)]
pub struct Building {
    /// Centre of the box.
    pub center: DVec3,
    /// Half its size along its own axes.
    pub half: DVec3,
    /// Turn about z, in radians.
    pub angle: f64,
}

impl Building {
    /// Its pose in the world.
    pub fn pose(&self) -> Pose {
        Pose::new(self.center, DQuat::from_rotation_z(self.angle)).expect("a valid pose")
    }

    /// Its world axis-aligned bounds.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        let (s, c) = self.angle.sin_cos();
        let e = DVec3::new(
            c.abs() * self.half.x + s.abs() * self.half.y,
            s.abs() * self.half.x + c.abs() * self.half.y,
            self.half.z,
        );
        (self.center - e, self.center + e)
    }

    /// Whether the closed ball of centre `p` and radius `r` meets the solid box: the
    /// distance from `p` (taken into the box's frame) to the box is at most `r`.
    #[inline]
    pub fn meets_ball(&self, p: DVec3, r: f64) -> bool {
        let (s, c) = self.angle.sin_cos();
        let d = p - self.center;
        let local = DVec3::new(c * d.x + s * d.y, -s * d.x + c * d.y, d.z);
        let q = local.abs() - self.half;
        q.max(DVec3::ZERO).length_squared() <= r * r
    }
}

/// The benchmark city: 100,000 boxes of 4–14 m footprint and 6–60 m height on a 20 m
/// grid, jittered by up to 2 m, one in three turned about z.
pub fn city() -> Vec<Building> {
    let mut rng = Rng::new(7);
    let mut out = Vec::with_capacity(CITY_NX * CITY_NY);
    for j in 0..CITY_NY {
        for i in 0..CITY_NX {
            let half = DVec3::new(
                rng.range(2.0, 7.0),
                rng.range(2.0, 7.0),
                rng.range(3.0, 30.0),
            );
            let x = (i as f64 + 0.5) * CITY_PITCH + rng.range(-2.0, 2.0);
            let y = (j as f64 + 0.5) * CITY_PITCH + rng.range(-2.0, 2.0);
            let angle = if rng.unit() < 1.0 / 3.0 {
                rng.range(0.0, std::f64::consts::PI)
            } else {
                0.0
            };
            out.push(Building {
                center: DVec3::new(x, y, half.z),
                half,
                angle,
            });
        }
    }
    out
}

/// The city's world: one body per building (unnamed), in order, and the map from body
/// id to building index.
pub fn city_world(city: &[Building]) -> (World, Vec<BodyId>, HashMap<u64, u32>) {
    let mut world = World::new();
    let root = world.root();
    let mut ids = Vec::with_capacity(city.len());
    let mut index = HashMap::with_capacity(city.len());
    for (k, b) in city.iter().enumerate() {
        let id = world
            .insert_with(None, root, b.pose(), |s| box_solid(s, b.half * 2.0))
            .expect("a box");
        index.insert(id.get(), k as u32);
        ids.push(id);
    }
    (world, ids, index)
}

/// `n` query centres over the city, at least [`CITY_MARGIN`] inside its edges, 0–40 m
/// above the ground.
pub fn city_centers(n: usize, seed: u64) -> Vec<DVec3> {
    let mut rng = Rng::new(seed);
    let (w, h) = (CITY_NX as f64 * CITY_PITCH, CITY_NY as f64 * CITY_PITCH);
    (0..n)
        .map(|_| {
            DVec3::new(
                rng.range(CITY_MARGIN, w - CITY_MARGIN),
                rng.range(CITY_MARGIN, h - CITY_MARGIN),
                rng.range(0.0, 40.0),
            )
        })
        .collect()
}

/// `world` with body `id` placed at `pose`, as a new snapshot.
pub fn moved(world: &World, id: BodyId, pose: Pose) -> Arc<World> {
    let mut w = world.clone();
    w.set_pose(id, pose).expect("a live body");
    Arc::new(w)
}

// ------------------------------------------------------------------------ measurement

/// The radius at which balls at `centers` meet `target` things on average, by
/// bisection on `count(centre, radius)`, between `lo` and `hi`.
pub fn calibrate(
    target: f64,
    centers: &[DVec3],
    mut lo: f64,
    mut hi: f64,
    mut count: impl FnMut(DVec3, f64) -> usize,
) -> f64 {
    for _ in 0..24 {
        let mid = 0.5 * (lo + hi);
        let total: usize = centers.iter().map(|&c| count(c, mid)).sum();
        if (total as f64) / (centers.len() as f64) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The `p`-th percentile (0–100) of `samples` (sorted in place), nearest rank.
pub fn percentile(samples: &mut [f64], p: f64) -> f64 {
    samples.sort_unstable_by(f64::total_cmp);
    if samples.is_empty() {
        return f64::NAN;
    }
    let rank = ((p / 100.0) * samples.len() as f64).ceil() as usize;
    samples[rank.clamp(1, samples.len()) - 1]
}

/// Per-query timings: p50, p99 and mean, in microseconds.
#[derive(Clone, Copy, Debug)]
pub struct Timings {
    /// Median.
    pub p50: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Mean.
    pub mean: f64,
}

impl Timings {
    /// From per-query times in nanoseconds.
    pub fn of(ns: &mut [f64]) -> Timings {
        let mean = ns.iter().sum::<f64>() / ns.len() as f64;
        Timings {
            p50: percentile(ns, 50.0) / 1e3,
            p99: percentile(ns, 99.0) / 1e3,
            mean: mean / 1e3,
        }
    }
}

/// Runs `query` on every centre, timing each call alone: the timings and the mean
/// number of hits `query` answers. A first pass over up to 1,000 centres warms caches.
pub fn time_each(centers: &[DVec3], mut query: impl FnMut(DVec3) -> usize) -> (Timings, f64) {
    for &c in centers.iter().take(1000) {
        std::hint::black_box(query(c));
    }
    let mut ns = Vec::with_capacity(centers.len());
    let mut hits = 0usize;
    for &c in centers {
        let t = std::time::Instant::now();
        let h = query(std::hint::black_box(c));
        ns.push(t.elapsed().as_nanos() as f64);
        hits += h;
    }
    (Timings::of(&mut ns), hits as f64 / centers.len() as f64)
}

/// Faces a sphere query at `features` detail answers, over all bodies.
pub fn faces_answered(spatial: &Spatial, c: DVec3, r: f64) -> usize {
    let q = SphereQuery::new(c, r).with_detail(Detail::Features);
    let a = spatial.sphere(&q).expect("a valid query");
    a.bodies
        .iter()
        .map(|b| b.faces.as_ref().map_or(0, Vec::len))
        .sum()
}
