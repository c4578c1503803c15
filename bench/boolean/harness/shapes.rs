//! The bodies and rigid places the case generators draw from: boxes on an integer
//! grid, a square frame (a box with a square hole, genus 1), the outlines of concave
//! prisms (L, comb, star), and exact quarter turns.

use glam::{DAffine3, DMat3, DQuat, DVec2, DVec3, IVec3};
use winged::model::solids::{SolidError, box_solid};
use winged::model::{Body, Serials};

/// An axis-aligned box from `lo` to `hi` (integers, `lo < hi` on every axis): a
/// `box_solid` centred on the origin and its place, a translation by the centre. Every
/// coordinate is a multiple of 1/2, so the placed loci are exact.
pub fn grid_box(
    serials: &mut Serials,
    lo: IVec3,
    hi: IVec3,
) -> Result<(Body, DAffine3), SolidError> {
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    let body = box_solid(serials, hi - lo)?;
    Ok((body, DAffine3::from_translation((lo + hi) * 0.5)))
}

/// An axis-aligned box from `lo` to `hi` built with `Body::from_polygons` at its own
/// coordinates (its place is the identity).
pub fn box_at(serials: &mut Serials, lo: DVec3, hi: DVec3) -> Result<Body, SolidError> {
    // Vertex i has x from bit 0, y from bit 1, z from bit 2 (0: lo, 1: hi).
    let positions: Vec<DVec3> = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    let faces: [[u32; 4]; 6] = [
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 2, 3, 1],
        [4, 5, 7, 6],
    ];
    Ok(Body::from_polygons(serials, &positions, &faces)?)
}

/// A square frame centred on the origin: the box `2·outer × 2·outer × height` with the
/// square hole `2·inner × 2·inner` through it along z (`0 < inner < outer`). Sixteen
/// quadrilaterals (four on top, four below, four outer and four inner walls), one
/// handle.
pub fn frame(
    serials: &mut Serials,
    outer: f64,
    inner: f64,
    height: f64,
) -> Result<Body, SolidError> {
    let h = height / 2.0;
    let square = |s: f64| [(-s, -s), (s, -s), (s, s), (-s, s)];
    let mut positions = Vec::with_capacity(16);
    // 0..4 outer bottom, 4..8 inner bottom, 8..12 outer top, 12..16 inner top.
    for z in [-h, h] {
        for s in [outer, inner] {
            positions.extend(square(s).iter().map(|&(x, y)| DVec3::new(x, y, z)));
        }
    }
    let mut faces = Vec::with_capacity(16);
    for k in 0..4u32 {
        let k1 = (k + 1) % 4;
        faces.push(vec![8 + k, 8 + k1, 12 + k1, 12 + k]); // top
        faces.push(vec![k, 4 + k, 4 + k1, k1]); // bottom
        faces.push(vec![k, k1, 8 + k1, 8 + k]); // outer wall
        faces.push(vec![4 + k, 12 + k, 12 + k1, 4 + k1]); // inner wall
    }
    Ok(Body::from_polygons(serials, &positions, &faces)?)
}

/// An L: the `w × h` rectangle at the origin less the `(w − t) × (h − t)` rectangle at
/// its far corner, counter-clockwise.
pub fn l_outline(w: f64, h: f64, t: f64) -> Vec<DVec2> {
    [(0.0, 0.0), (w, 0.0), (w, t), (t, t), (t, h), (0.0, h)]
        .iter()
        .map(|&(x, y)| DVec2::new(x, y))
        .collect()
}

/// A comb: a bar `base` thick along x with `teeth` teeth of width `tooth` and length
/// `length` standing on it in +y, `gap` apart, starting at x = 0. Counter-clockwise.
pub fn comb_outline(teeth: usize, tooth: f64, gap: f64, length: f64, base: f64) -> Vec<DVec2> {
    let width = teeth as f64 * tooth + (teeth as f64 - 1.0) * gap;
    let mut p = vec![DVec2::new(0.0, 0.0), DVec2::new(width, 0.0)];
    // Along the top from right to left: each tooth's right side up, top, left side down.
    for i in (0..teeth).rev() {
        let x0 = i as f64 * (tooth + gap);
        let x1 = x0 + tooth;
        if i + 1 < teeth {
            p.push(DVec2::new(x1, base));
        }
        p.push(DVec2::new(x1, base + length));
        p.push(DVec2::new(x0, base + length));
        if i > 0 {
            p.push(DVec2::new(x0, base));
        }
    }
    p
}

/// A star of `points` points about the origin: tips on the circle of `outer`, notches
/// on the circle of `inner` (`inner < outer`), the first tip on +x. Counter-clockwise.
pub fn star_outline(points: usize, outer: f64, inner: f64) -> Vec<DVec2> {
    (0..2 * points)
        .map(|i| {
            let r = if i % 2 == 0 { outer } else { inner };
            let (s, c) = (std::f64::consts::PI * i as f64 / points as f64).sin_cos();
            DVec2::new(r * c, r * s)
        })
        .collect()
}

/// `k` quarter turns counter-clockwise about coordinate axis `axis` (0 x, 1 y, 2 z),
/// as an exact matrix (entries 0 and ±1 only).
pub fn quarter_turns(axis: usize, k: i32) -> DMat3 {
    let (c, s) = match k.rem_euclid(4) {
        0 => (1.0, 0.0),
        1 => (0.0, 1.0),
        2 => (-1.0, 0.0),
        _ => (0.0, -1.0),
    };
    match axis {
        0 => DMat3::from_cols(DVec3::X, DVec3::new(0.0, c, s), DVec3::new(0.0, -s, c)),
        1 => DMat3::from_cols(DVec3::new(c, 0.0, -s), DVec3::Y, DVec3::new(s, 0.0, c)),
        _ => DMat3::from_cols(DVec3::new(c, s, 0.0), DVec3::new(-s, c, 0.0), DVec3::Z),
    }
}

/// The rigid map turning by `rotation` about `pivot`, then moving by `shift`.
pub fn turn_about(pivot: DVec3, rotation: DQuat, shift: DVec3) -> DAffine3 {
    let m = DMat3::from_quat(rotation);
    DAffine3::from_mat3_translation(m, pivot - m * pivot + shift)
}

/// A right prism over a counter-clockwise `outline`, `height` tall and centred in
/// height, built with `Body::from_polygons` so that its loci are the outline's points
/// at ±height/2 exactly (`prism_solid` sweeps about the face's mean point, which
/// rounds).
pub fn extrude(serials: &mut Serials, outline: &[DVec2], height: f64) -> Result<Body, SolidError> {
    let n = outline.len() as u32;
    let h = height / 2.0;
    let positions: Vec<DVec3> = [-h, h]
        .iter()
        .flat_map(|&z| outline.iter().map(move |p| p.extend(z)))
        .collect();
    let mut faces: Vec<Vec<u32>> = vec![(0..n).rev().collect(), (n..2 * n).collect()];
    for i in 0..n {
        let i1 = (i + 1) % n;
        faces.push(vec![i, i1, n + i1, n + i]);
    }
    Ok(Body::from_polygons(serials, &positions, &faces)?)
}
