//! A small ray caster for tests of vision: pictures of a world drawn by something other
//! than winged's renderer (rays cast through every sub-pixel against every triangle,
//! Möller–Trumbore, Lambert shading under one distant light, 3 × 3 samples a pixel for
//! anti-aliasing, Gaussian noise), with their depth images.
//!
//! It reads the triangles of a [`Scene`] (the world's geometry) and the camera's
//! projection (`to_opencv` and the intrinsics); everything that decides what a pixel
//! shows is its own.

#![allow(dead_code)]

use glam::{DMat3, DVec3};
use winged::model::Camera;
use winged::render::Scene;

/// A drawn picture: RGB samples and the depth (along the optical axis, meters) at each
/// pixel centre, infinite where no surface is.
pub struct Drawn {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
    pub depth: Vec<f64>,
}

/// One triangle with what shading needs.
struct Triangle {
    a: DVec3,
    e1: DVec3,
    e2: DVec3,
    normal: DVec3,
    colour: [f64; 3],
}

/// A body's triangles and their bounding box.
struct Group {
    min: DVec3,
    max: DVec3,
    triangles: Vec<Triangle>,
}

/// How the picture looks.
pub struct Look {
    /// Direction the light travels (unit).
    pub light: DVec3,
    /// Background colour, 0–255.
    pub background: [f64; 3],
    /// Share of the light that reaches every face whatever its turn.
    pub ambient: f64,
    /// Sub-pixel samples per side.
    pub samples: u32,
}

impl Default for Look {
    fn default() -> Self {
        Look {
            light: DVec3::new(0.4, 0.3, -1.0).normalize(),
            background: [70.0, 80.0, 95.0],
            ambient: 0.35,
            samples: 3,
        }
    }
}

fn groups(scene: &Scene) -> Vec<Group> {
    let mut groups: Vec<Group> = scene
        .bodies
        .iter()
        .map(|_| Group {
            min: DVec3::splat(f64::INFINITY),
            max: DVec3::splat(f64::NEG_INFINITY),
            triangles: Vec::new(),
        })
        .collect();
    for (t, &f) in scene.triangles.iter().zip(&scene.triangle_faces) {
        let face = &scene.faces[f as usize];
        let body = &scene.bodies[face.body as usize];
        let [a, b, c] = t.map(|i| scene.points[i as usize]);
        let g = &mut groups[face.body as usize];
        g.min = g.min.min(a).min(b).min(c);
        g.max = g.max.max(a).max(b).max(c);
        let colour = body.color.0.map(|c| c as f64);
        g.triangles.push(Triangle {
            a,
            e1: b - a,
            e2: c - a,
            normal: (b - a).cross(c - a).normalize_or_zero(),
            colour,
        });
    }
    groups
}

/// Whether the ray `o + s·d` (s > 0) meets the box.
fn meets_box(o: DVec3, inv: DVec3, min: DVec3, max: DVec3) -> bool {
    let t1 = (min - o) * inv;
    let t2 = (max - o) * inv;
    let lo = t1.min(t2).max_element();
    let hi = t1.max(t2).min_element();
    hi >= lo.max(0.0)
}

/// The nearest hit of the ray: its parameter and triangle.
fn nearest(groups: &[Group], o: DVec3, d: DVec3) -> Option<(f64, &Triangle)> {
    let inv = d.recip();
    let mut best: Option<(f64, &Triangle)> = None;
    for g in groups {
        if !meets_box(o, inv, g.min, g.max) {
            continue;
        }
        for t in &g.triangles {
            let p = d.cross(t.e2);
            let det = t.e1.dot(p);
            if det.abs() < 1e-15 {
                continue;
            }
            let inv_det = 1.0 / det;
            let s = o - t.a;
            let u = s.dot(p) * inv_det;
            if !(0.0..=1.0).contains(&u) {
                continue;
            }
            let q = s.cross(t.e1);
            let v = d.dot(q) * inv_det;
            if v < 0.0 || u + v > 1.0 {
                continue;
            }
            let hit = t.e2.dot(q) * inv_det;
            if hit > 1e-9 && best.is_none_or(|(h, _)| hit < h) {
                best = Some((hit, t));
            }
        }
    }
    best
}

/// Draws `scene` as `camera` sees it.
pub fn draw(scene: &Scene, camera: &Camera, look: &Look) -> Drawn {
    let groups = groups(scene);
    let k = camera.intrinsics;
    let (r, _t): (DMat3, DVec3) = camera.to_opencv();
    let back = r.transpose();
    let eye = camera.position();
    let (w, h) = (k.width, k.height);
    let n = look.samples.max(1);
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    let mut depth = vec![f64::INFINITY; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let mut sum = [0.0; 3];
            for sy in 0..n {
                for sx in 0..n {
                    let u = x as f64 + (sx as f64 + 0.5) / n as f64;
                    let v = y as f64 + (sy as f64 + 0.5) / n as f64;
                    let d_cam = DVec3::new((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
                    let d = back * d_cam;
                    let colour = match nearest(&groups, eye, d) {
                        Some((_, t)) => {
                            let lit = (-look.light.dot(t.normal)).max(0.0);
                            let f = look.ambient + (1.0 - look.ambient) * lit;
                            t.colour.map(|c| c * f)
                        }
                        None => look.background,
                    };
                    for c in 0..3 {
                        sum[c] += colour[c];
                    }
                }
            }
            let i = (y * w + x) as usize;
            for c in 0..3 {
                rgb[i * 3 + c] = (sum[c] / (n * n) as f64).round().clamp(0.0, 255.0) as u8;
            }
            let centre = DVec3::new(
                (x as f64 + 0.5 - k.cx) / k.fx,
                (y as f64 + 0.5 - k.cy) / k.fy,
                1.0,
            );
            if let Some((s, _)) = nearest(&groups, eye, back * centre) {
                depth[i] = s;
            }
        }
    }
    Drawn {
        width: w,
        height: h,
        rgb,
        depth,
    }
}

/// The picture with Gaussian noise of deviation `sigma` grey levels on every sample,
/// from a deterministic stream seeded by `seed`.
pub fn with_noise(rgb: &[u8], sigma: f64, seed: u64) -> Vec<u8> {
    let mut state = seed;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    rgb.iter()
        .map(|&v| {
            let (u1, u2) = (next().max(f64::MIN_POSITIVE), next());
            let g = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
            (v as f64 + sigma * g).round().clamp(0.0, 255.0) as u8
        })
        .collect()
}

/// The depth as 16-bit units of `scale` meters (0 where no surface is).
pub fn depth_units(depth: &[f64], scale: f64) -> Vec<u16> {
    depth
        .iter()
        .map(|&d| {
            if d.is_finite() {
                (d / scale).round().clamp(1.0, 65535.0) as u16
            } else {
                0
            }
        })
        .collect()
}
