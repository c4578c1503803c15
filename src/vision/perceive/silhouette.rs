//! Silhouettes from masks: each region of a mask, widened by a tolerance, traced into a
//! polygon with holes and simplified within a fraction of a pixel.

use glam::DVec2;

use super::carve::Outline;
use crate::vision::image::{ContourOptions, Mask, trace_regions};

/// How far, in pixels, a traced outline may lie outside the widened mask's pixels. The
/// outline is simplified outward only, so it always holds every pixel of the widened
/// mask; a silhouette then spills over its mask by at most the widening and this.
pub const SIMPLIFY_PX: f64 = 1.25;

/// The most a mask may be widened, in pixels.
pub const MAX_WIDEN_PX: f64 = 16.0;

/// One silhouette region: its outline and its size.
#[derive(Clone, Debug, PartialEq)]
pub struct Silhouette {
    /// The rings, outer first, in pixels.
    pub outline: Outline,
    /// Pixels of the widened region.
    pub pixels: usize,
    /// `[u0, v0, u1, v1]` of the outer ring.
    pub bbox: [f64; 4],
}

/// `mask` widened by `widen_px` (a disc; at most [`MAX_WIDEN_PX`]), as silhouettes of at
/// least `min_area_px` pixels (before widening), largest first.
pub fn silhouettes(mask: &Mask, widen_px: f64, min_area_px: f64) -> Vec<Silhouette> {
    // Regions too small are dropped before widening, so that widening does not make
    // specks count.
    let kept = without_small(mask, min_area_px);
    let wide = widened(&kept, widen_px.clamp(0.0, MAX_WIDEN_PX));
    let options = ContourOptions {
        tolerance_px: SIMPLIFY_PX,
        min_area_px: 0.0,
        outward: true,
    };
    let mut out: Vec<Silhouette> = trace_regions(&wide, &options)
        .into_iter()
        .map(|r| {
            let mut rings = vec![to_points(&r.outer)];
            rings.extend(r.holes.iter().map(|h| to_points(h)));
            Silhouette {
                outline: Outline { rings },
                pixels: r.pixels,
                bbox: r.bbox,
            }
        })
        .collect();
    out.sort_by_key(|s| std::cmp::Reverse(s.pixels));
    out
}

fn to_points(ring: &[[f64; 2]]) -> Vec<DVec2> {
    ring.iter().map(|p| DVec2::new(p[0], p[1])).collect()
}

/// `mask` without its regions of fewer than `min_area_px` pixels.
fn without_small(mask: &Mask, min_area_px: f64) -> Mask {
    if min_area_px <= 1.0 || min_area_px.is_nan() {
        return mask.clone();
    }
    let exact = ContourOptions {
        tolerance_px: 0.0,
        min_area_px: 0.0,
        outward: false,
    };
    let regions = trace_regions(mask, &exact);
    if regions.iter().all(|r| r.pixels as f64 >= min_area_px) {
        return mask.clone();
    }
    // Keep the pixels of the regions big enough: fill each kept region's rings.
    let (w, h) = (mask.width(), mask.height());
    let mut out = Mask::new(w, h);
    for r in regions.iter().filter(|r| r.pixels as f64 >= min_area_px) {
        let [u0, v0, u1, v1] = r.bbox;
        for y in (v0 as u32)..(v1 as u32).min(h) {
            for x in (u0 as u32)..(u1 as u32).min(w) {
                if !mask.get(x, y) {
                    continue;
                }
                let c = [x as f64 + 0.5, y as f64 + 0.5];
                let mut inside = winding_odd(&r.outer, c);
                for hole in &r.holes {
                    inside ^= winding_odd(hole, c);
                }
                if inside {
                    out.set(x, y, true);
                }
            }
        }
    }
    out
}

/// Whether a ray from `c` toward +u crosses `ring` an odd number of times.
fn winding_odd(ring: &[[f64; 2]], c: [f64; 2]) -> bool {
    let mut odd = false;
    for k in 0..ring.len() {
        let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
        if (a[1] > c[1]) != (b[1] > c[1]) {
            let x = a[0] + (c[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if x > c[0] {
                odd = !odd;
            }
        }
    }
    odd
}

/// `mask` dilated by a disc of radius `r` pixels (centre to centre).
pub fn widened(mask: &Mask, r: f64) -> Mask {
    let reach = r.floor() as i64;
    if reach < 1 {
        return mask.clone();
    }
    let (w, h) = (mask.width() as i64, mask.height() as i64);
    let offsets: Vec<(i64, i64)> = (-reach..=reach)
        .flat_map(|dy| (-reach..=reach).map(move |dx| (dx, dy)))
        .filter(|&(dx, dy)| ((dx * dx + dy * dy) as f64) <= r * r)
        .collect();
    let mut out = mask.clone();
    for y in 0..h {
        for x in 0..w {
            if !mask.get(x as u32, y as u32) {
                continue;
            }
            // Only boundary pixels reach beyond the region.
            // (A neighbour beyond the mask reads as outside.)
            let interior = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .all(|&(dx, dy)| mask.get((x + dx) as u32, (y + dy) as u32));
            if interior {
                continue;
            }
            for &(dx, dy) in &offsets {
                let (px, py) = (x + dx, y + dy);
                if px >= 0 && py >= 0 && px < w && py < h {
                    out.set(px as u32, py as u32, true);
                }
            }
        }
    }
    out
}
