//! Regions of a binary mask as polygons with holes: each region's boundary followed along
//! the cracks between pixels, then simplified.
//!
//! # Conventions
//!
//! Pixel `(x, y)` covers `[x, x+1) × [y, y+1)` in image coordinates `(u, v)`: u to the
//! right and v down from the top-left corner of the top-left pixel (the camera's pixel
//! convention, [`crate::model::camera`]).
//!
//! A *region* is a 4-connected set of inside pixels (pixels sharing a side). A *hole* of a
//! region is an 8-connected set of outside pixels (sharing a side or a corner) that the
//! region encloses, so that it does not reach the border of the mask. The two
//! connectivities are each other's complement, which makes every boundary a closed curve
//! between exactly one region and exactly one set of outside pixels: two inside pixels
//! that touch only at a corner are in two regions (unless joined elsewhere), and the
//! outside passes between them. An inside region within a hole (an island) is a region of
//! its own.
//!
//! A *ring* is a sequence of points, closed implicitly (the last point is not repeated).
//! Its orientation is the sign of its area `A = ½ Σ (u_i v_{i+1} − u_{i+1} v_i)`. An
//! outer ring has `A > 0`: it turns from +u toward +v, which is counter-clockwise in the
//! (u, v) frame and clockwise as drawn on a screen with v pointing down. A hole has
//! `A < 0`. Either way the region is on the left of every edge, "left" meaning the edge's
//! direction turned from +u toward +v.
//!
//! # Method
//!
//! 1. **Regions.** Inside pixels are labelled region by region with a fill that keeps its
//!    own stack (nothing recurses on pixels), regions numbered in raster order of their
//!    first pixel.
//! 2. **Cracks.** Each ring is followed along the sides of pixels with the region on its
//!    left. At each grid corner it turns left if the pixel ahead on the left is outside,
//!    else right if the pixel ahead on the right is inside, else goes straight on; where
//!    two inside pixels meet only at that corner, this turns around the pixel being
//!    followed, which is what keeps 4-connected regions apart. Only the corners where the
//!    direction changes are kept. The ring is the exact boundary of the union of the
//!    region's pixel squares, so with no simplification a region's area (outer ring less
//!    holes) is its pixel count. Every ring is found by one raster scan of the horizontal
//!    pixel sides: the first side of a ring met in that scan has the region below it for
//!    an outer ring (the top of the region's first pixel) and above it for a hole (the top
//!    of the hole's first pixel).
//! 3. **Outline.** Wherever a boundary is not axis-aligned its crack ring is a staircase
//!    that zigzags about the digitised line by up to half a pixel, so simplifying the
//!    staircase itself within half a pixel would keep nearly every step. The outline
//!    smooths it. A *run* is a straight stretch of cracks between two corners; each
//!    corner next to a run of a single crack (a step of the staircase) is replaced by two
//!    points on its two runs, each `min(r, run/2)` from it, with `r = t/√(1 − 4t²)` for
//!    a tolerance `t < ½` and `r = ∞` from `t = ½` on. At `t ≥ ½` the points are the
//!    midpoints of the runs, through which a digitised straight line passes exactly when
//!    its runs are of one length (slopes 1/n and n) and nearly otherwise. A corner
//!    between two runs of at least two cracks is kept: the steps across a digitised
//!    straight line are single cracks, so such a corner is one of the shape's own (a
//!    rectangle keeps its four corners). A corner cut at `p` and `q` along its runs is
//!    `pq/√(p² + q²)` from the outline, which the choice of `r` keeps at most
//!    `min(t, ½)`.
//! 4. **Simplification.** Douglas–Peucker on the closed outline, with a stack of its own:
//!    the anchors are the ring's first point in raster order (least v, then least u) and
//!    the point farthest from it, and each chain between kept points is split at its
//!    point farthest from the chord (as a segment) while that is more than `t` away. The
//!    simplified ring is within `t` of the outline both ways (Hausdorff distance), so
//!    within `t + min(t, ½)` of the cracks; its points are points of the outline, which
//!    lie on cracks.
//! 5. **Validity.** A simplified ring gives way to its crack ring when it has fewer than
//!    three points or a repeated point, when its area changed sign or fell below half
//!    the crack ring's, or when it touches or crosses itself or another ring of its region
//!    (a sort-and-sweep of the region's edges along u, with exact orientation tests from
//!    `robust`); this repeats until nothing conflicts. Crack rings never cross, though one
//!    may touch itself at a grid corner where two of its region's pixels meet diagonally.
//!    Regions are simplified independently: an island and the hole around it may come
//!    closer than the tolerance, or overlap.

use robust::{Coord, orient2d};

use super::ImageError;

/// The most pixels a [`Mask`] may have (region labels are 32-bit).
const MAX_PIXELS: u64 = u32::MAX as u64;
/// The label of an outside pixel.
const NO_REGION: u32 = u32::MAX;

/// Directions along the grid, in turning order from +u toward +v: east (+u), south (+v),
/// west (−u), north (−v). Turning left is `d + 1`, right `d + 3` (mod 4).
const EAST: usize = 0;
const WEST: usize = 2;
const STEP: [[i64; 2]; 4] = [[1, 0], [0, 1], [-1, 0], [0, -1]];
/// For each direction, the pixels ahead on the left and ahead on the right of a grid
/// corner `(X, Y)` as offsets: the pixel `(X + dx, Y + dy)`.
const AHEAD: [[[i64; 2]; 2]; 4] = [
    [[0, 0], [0, -1]],   // east: south-east, north-east
    [[-1, 0], [0, 0]],   // south: south-west, south-east
    [[-1, -1], [-1, 0]], // west: north-west, south-west
    [[0, -1], [-1, -1]], // north: north-east, north-west
];

/// A binary mask of `width × height` pixels, row-major from the top-left pixel; `true` is
/// inside. Pixel `(x, y)` covers `[x, x+1) × [y, y+1)`; see the
/// [module documentation](self).
///
/// Invariant: `bits.len() == width × height ≤ u32::MAX`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mask {
    width: u32,
    height: u32,
    bits: Vec<bool>,
}

impl Mask {
    /// A mask with every pixel outside; a zero width or height gives a mask of no pixels.
    ///
    /// # Panics
    ///
    /// When `width × height` exceeds `u32::MAX` (4.29 gigapixels).
    pub fn new(width: u32, height: u32) -> Mask {
        let Some(n) = mask_len(width, height) else {
            panic!("a {width} × {height} mask has more than u32::MAX pixels");
        };
        Mask {
            width,
            height,
            bits: vec![false; n],
        }
    }

    /// The mask whose pixel `(x, y)` is inside when `inside(x, y)`, called once per pixel
    /// in raster order.
    ///
    /// # Panics
    ///
    /// As [`Mask::new`].
    pub fn from_fn(width: u32, height: u32, mut inside: impl FnMut(u32, u32) -> bool) -> Mask {
        let mut mask = Mask::new(width, height);
        let pixels = (0..height).flat_map(|y| (0..width).map(move |x| (x, y)));
        for (bit, (x, y)) in mask.bits.iter_mut().zip(pixels) {
            *bit = inside(x, y);
        }
        mask
    }

    /// The mask of `bits`, row-major from the top-left pixel.
    ///
    /// Refused with [`ImageError::BadParameter`] when `width × height` exceeds
    /// `u32::MAX`, and with [`ImageError::Samples`] unless `bits.len() == width × height`.
    pub fn from_bits(width: u32, height: u32, bits: Vec<bool>) -> Result<Mask, ImageError> {
        let Some(n) = mask_len(width, height) else {
            return Err(ImageError::BadParameter {
                what: "the number of mask pixels",
                value: width as f64 * height as f64,
            });
        };
        if bits.len() != n {
            return Err(ImageError::Samples {
                expected: n,
                got: bits.len(),
            });
        }
        Ok(Mask {
            width,
            height,
            bits,
        })
    }

    /// Width, pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height, pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The pixels, row-major from the top-left, `width × height` of them.
    pub fn bits(&self) -> &[bool] {
        &self.bits
    }

    /// Whether pixel `(x, y)` is inside; `false` beyond the mask, which is outside.
    pub fn get(&self, x: u32, y: u32) -> bool {
        x < self.width && y < self.height && self.bits[self.index(x, y)]
    }

    /// Sets pixel `(x, y)` inside (`true`) or outside.
    ///
    /// # Panics
    ///
    /// When `(x, y)` is beyond the mask.
    pub fn set(&mut self, x: u32, y: u32, inside: bool) {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) is beyond the {} × {} mask",
            self.width,
            self.height
        );
        let i = self.index(x, y);
        self.bits[i] = inside;
    }

    /// The number of inside pixels.
    pub fn count(&self) -> usize {
        self.bits.iter().filter(|&&b| b).count()
    }

    fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }

    /// Whether pixel `(x, y)` is inside, for any integers (outside beyond the mask).
    #[inline]
    fn at(&self, x: i64, y: i64) -> bool {
        x >= 0
            && y >= 0
            && x < self.width as i64
            && y < self.height as i64
            && self.bits[y as usize * self.width as usize + x as usize]
    }
}

/// `width × height` when it is at most `MAX_PIXELS`.
fn mask_len(width: u32, height: u32) -> Option<usize> {
    let n = width as u64 * height as u64;
    (n <= MAX_PIXELS).then_some(n as usize)
}

/// One region of a mask (a 4-connected set of inside pixels) as a polygon with holes, in
/// pixel coordinates. See the [module documentation](self) for the conventions.
///
/// Invariants: every ring has at least 3 points, no two consecutive ones equal, and starts
/// at its first point in raster order (least v, then least u); `outer` has positive area
/// and every hole negative; a simplified ring neither touches nor crosses itself or
/// another ring of the region.
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    /// The outer boundary, turning from +u toward +v (positive area).
    pub outer: Vec<[f64; 2]>,
    /// The boundaries of the holes, each turning from +v toward +u (negative area), in
    /// raster order of each hole's first pixel.
    pub holes: Vec<Vec<[f64; 2]>>,
    /// The area of `outer` less the areas of `holes`, px²: the pixel count exactly when
    /// nothing was simplified (tolerance 0).
    pub area: f64,
    /// The number of pixels of the region, exactly.
    pub pixels: usize,
    /// `[u0, v0, u1, v1]`: the least and greatest u and v of the points of `outer`.
    pub bbox: [f64; 4],
}

/// How regions are simplified and which are kept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContourOptions {
    /// How far, px, a simplified ring may depart from the region's outline (see the
    /// [module documentation](self)). Zero, a negative value or NaN keeps the exact crack
    /// boundary.
    pub tolerance_px: f64,
    /// Regions whose `area` is less than this, px², are left out; zero, a negative value
    /// or NaN keeps every region.
    pub min_area_px: f64,
    /// Simplify outward only: each ring is simplified from its crack corners (no
    /// smoothed outline) so that every crack corner stays on the region's side of the
    /// simplified ring, which then holds the union of the region's pixel squares and is
    /// within `tolerance_px` of its crack boundary. Used where a region must not lose
    /// area (silhouettes that carve solids).
    pub outward: bool,
}

impl Default for ContourOptions {
    /// Half a pixel of tolerance; every region kept.
    fn default() -> Self {
        ContourOptions {
            tolerance_px: 0.5,
            min_area_px: 0.0,
            outward: false,
        }
    }
}

/// The regions of `mask` as polygons with holes, in raster order of each region's first
/// pixel, those whose area is below `options.min_area_px` left out. Any options are
/// accepted (see [`ContourOptions`]).
///
/// Postconditions: each region satisfies the [`Region`] invariants; its rings' points lie
/// on its crack boundary (the boundary of the union of its pixel squares), which is
/// within `t + min(t, ½)` px of them (`t` the tolerance); with `t = 0` the rings are
/// the crack boundary itself, corners only, and `area == pixels`.
pub fn trace_regions(mask: &Mask, options: &ContourOptions) -> Vec<Region> {
    let (labels, pixels) = label_regions(mask);
    let mut rings: Vec<Vec<Vec<[f64; 2]>>> = vec![Vec::new(); pixels.len()];
    trace_rings(mask, &labels, |region, hole, ring| {
        let rings = &mut rings[region as usize];
        if hole {
            rings.push(ring);
        } else {
            // The outer ring is met first (its first pixel precedes its holes'): index 0.
            rings.insert(0, ring);
        }
    });
    let tolerance = options.tolerance_px;
    rings
        .into_iter()
        .zip(pixels)
        .filter_map(|(rings, pixels)| {
            let rings = if tolerance > 0.0 {
                simplify_region(rings, tolerance, options.outward)
            } else {
                rings
            };
            let area = rings.iter().map(|ring| signed_area(ring)).sum::<f64>();
            let mut rings = rings.into_iter();
            let outer = rings.next()?;
            let bbox = bounding_box(&outer);
            // NaN keeps every region.
            let small = area < options.min_area_px;
            (!small).then(|| Region {
                outer,
                holes: rings.collect(),
                area,
                pixels,
                bbox,
            })
        })
        .collect()
}

/// Labels the 4-connected regions of inside pixels (`NO_REGION` outside), numbered in
/// raster order of their first pixel, and counts the pixels of each.
fn label_regions(mask: &Mask) -> (Vec<u32>, Vec<usize>) {
    let w = mask.width as usize;
    let bits = &mask.bits;
    let mut labels = vec![NO_REGION; bits.len()];
    let mut pixels = Vec::new();
    let mut stack = Vec::new();
    for first in 0..bits.len() {
        if !bits[first] || labels[first] != NO_REGION {
            continue;
        }
        // At most ⌈n/2⌉ < u32::MAX regions in n ≤ u32::MAX pixels.
        let id = pixels.len() as u32;
        labels[first] = id;
        stack.push(first);
        let mut count = 0;
        while let Some(i) = stack.pop() {
            count += 1;
            let (x, y) = (i % w, i / w);
            let mut visit = |j: usize| {
                if bits[j] && labels[j] == NO_REGION {
                    labels[j] = id;
                    stack.push(j);
                }
            };
            if x > 0 {
                visit(i - 1);
            }
            if x + 1 < w {
                visit(i + 1);
            }
            if y > 0 {
                visit(i - w);
            }
            if i + w < bits.len() {
                visit(i + w);
            }
        }
        pixels.push(count);
    }
    (labels, pixels)
}

/// Follows every ring of the mask once, handing each to `found` with its region's label,
/// whether it is a hole, and its corners.
fn trace_rings(mask: &Mask, labels: &[u32], mut found: impl FnMut(u32, bool, Vec<[f64; 2]>)) {
    let (w, h) = (mask.width as usize, mask.height as usize);
    if w == 0 || h == 0 {
        return;
    }
    // The horizontal pixel side (x, y), above pixel (x, y), is `visited[y·w + x]`.
    let mut visited = vec![false; w * (h + 1)];
    for y in 0..=h {
        for x in 0..w {
            let above = y > 0 && mask.bits[(y - 1) * w + x];
            let below = y < h && mask.bits[y * w + x];
            if above == below || visited[y * w + x] {
                continue;
            }
            let (xi, yi) = (x as i64, y as i64);
            if below {
                let ring = follow(mask, &mut visited, [xi, yi], EAST);
                found(labels[y * w + x], false, ring);
            } else {
                let ring = follow(mask, &mut visited, [xi + 1, yi], WEST);
                found(labels[(y - 1) * w + x], true, ring);
            }
        }
    }
}

/// The corners of the ring through the pixel side leaving grid corner `start` in
/// direction `dir` (with an inside pixel on its left), marking its horizontal sides in
/// `visited`.
fn follow(mask: &Mask, visited: &mut [bool], start: [i64; 2], dir: usize) -> Vec<[f64; 2]> {
    let w = mask.width as i64;
    let mut corners = Vec::new();
    let (mut p, mut d) = (start, dir);
    loop {
        match d {
            EAST => visited[(p[1] * w + p[0]) as usize] = true,
            WEST => visited[(p[1] * w + p[0] - 1) as usize] = true,
            _ => {}
        }
        p = [p[0] + STEP[d][0], p[1] + STEP[d][1]];
        let [left, right] = AHEAD[d];
        let next = if !mask.at(p[0] + left[0], p[1] + left[1]) {
            (d + 1) % 4
        } else if mask.at(p[0] + right[0], p[1] + right[1]) {
            (d + 3) % 4
        } else {
            d
        };
        if next != d {
            corners.push([p[0] as f64, p[1] as f64]);
        }
        d = next;
        if p == start && d == dir {
            let first = first_in_raster_order(&corners);
            corners.rotate_left(first);
            return corners;
        }
    }
}

/// The index of the point of least v, then least u (0 for no points).
fn first_in_raster_order(ring: &[[f64; 2]]) -> usize {
    let raster = |a: &[f64; 2], b: &[f64; 2]| a[1].total_cmp(&b[1]).then(a[0].total_cmp(&b[0]));
    (0..ring.len())
        .min_by(|&i, &j| raster(&ring[i], &ring[j]))
        .unwrap_or(0)
}

/// The rings of one region (outer first) simplified within `tolerance` > 0, each replaced
/// by its crack ring where simplifying would make it invalid.
///
/// With `outward`, each ring is simplified by [`outward_douglas_peucker`] from its crack
/// corners, and kept only where it does not lose area.
fn simplify_region(exact: Vec<Vec<[f64; 2]>>, tolerance: f64, outward: bool) -> Vec<Vec<[f64; 2]>> {
    let reach = if tolerance < 0.5 {
        tolerance / (1.0 - 4.0 * tolerance * tolerance).sqrt()
    } else {
        f64::INFINITY
    };
    let mut simple: Vec<Option<Vec<[f64; 2]>>> = exact
        .iter()
        .map(|ring| {
            let s = if outward {
                outward_douglas_peucker(ring, tolerance)
            } else {
                douglas_peucker(&outline(ring, reach), tolerance)
            };
            let (a, a0) = (signed_area(&s), signed_area(ring));
            let distinct = (0..s.len()).all(|i| s[i] != s[(i + 1) % s.len()]);
            // Outward, an outer ring may only grow and a hole only shrink.
            let kept_area = if outward {
                a >= a0
            } else {
                a.abs() >= 0.5 * a0.abs()
            };
            let valid = s.len() >= 3 && distinct && a * a0 > 0.0 && kept_area;
            (valid && s != *ring).then_some(s)
        })
        .collect();
    while simple.iter().any(Option::is_some) {
        let bad = conflicting_rings(&exact, &simple);
        if bad.is_empty() {
            break;
        }
        for r in bad {
            simple[r] = None;
        }
    }
    simple
        .into_iter()
        .zip(exact)
        .map(|(s, e)| s.unwrap_or(e))
        .collect()
}

/// The outline of a crack ring: each corner with a run of one crack on either side cut
/// to the two points `min(reach, run/2)` from it along its runs; consecutive duplicates
/// merged.
fn outline(corners: &[[f64; 2]], reach: f64) -> Vec<[f64; 2]> {
    let k = corners.len();
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(2 * k);
    let mut push = |p: [f64; 2]| {
        if out.last() != Some(&p) {
            out.push(p);
        }
    };
    for i in 0..k {
        let (p, c, q) = (corners[(i + k - 1) % k], corners[i], corners[(i + 1) % k]);
        let run_in = (c[0] - p[0]).abs() + (c[1] - p[1]).abs();
        let run_out = (q[0] - c[0]).abs() + (q[1] - c[1]).abs();
        if run_in >= 2.0 && run_out >= 2.0 {
            push(c);
        } else {
            // Half a run is exact (a multiple of ½), so two cuts meeting at a run's
            // midpoint give equal points.
            let f = reach.min(0.5 * run_in) / run_in;
            push([c[0] - f * (c[0] - p[0]), c[1] - f * (c[1] - p[1])]);
            let f = reach.min(0.5 * run_out) / run_out;
            push([c[0] + f * (q[0] - c[0]), c[1] + f * (q[1] - c[1])]);
        }
    }
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    out
}

/// Douglas–Peucker on a closed ring: the points kept, in ring order from its first point
/// in raster order (least v, then least u). Every point of `ring` is within `tolerance` of the kept
/// ring's edge that spans it.
fn douglas_peucker(ring: &[[f64; 2]], tolerance: f64) -> Vec<[f64; 2]> {
    if ring.len() < 3 {
        return ring.to_vec();
    }
    let first = first_in_raster_order(ring);
    let mut far = first;
    let mut far_distance = 0.0;
    for (i, p) in ring.iter().enumerate() {
        let d = (p[0] - ring[first][0]).hypot(p[1] - ring[first][1]);
        if d > far_distance {
            (far, far_distance) = (i, d);
        }
    }
    if far == first {
        return vec![ring[first]];
    }
    split_chains(ring, first, far, |a, b, i| {
        let d = distance_to_segment(ring[i], ring[a], ring[b]);
        (d > tolerance).then_some((false, d))
    })
}

/// Douglas–Peucker on a closed ring that only moves outward: a chord replaces the points
/// between its ends only when none of them lies on its right (outside the region, which
/// is on the left of every edge) and none is farther than `tolerance` from it; otherwise
/// the chain is split at the point farthest to the right, or, with none on the right, at
/// the farthest one. Every point of `ring` is then on the left of, or on, the kept
/// ring's edge that spans it, and within `tolerance` of it.
fn outward_douglas_peucker(ring: &[[f64; 2]], tolerance: f64) -> Vec<[f64; 2]> {
    let n = ring.len();
    if n < 4 {
        return ring.to_vec();
    }
    // The first point in raster order is a corner of the region's hull, so a split
    // there and at the point halfway round loses nothing.
    let first = first_in_raster_order(ring);
    split_chains(ring, first, (first + n / 2) % n, |a, b, i| {
        let right = orient(ring[a], ring[b], ring[i]) < 0;
        let d = distance_to_segment(ring[i], ring[a], ring[b]);
        (right || d > tolerance).then_some((right, d))
    })
}

/// The points of closed `ring` kept when the chains between `first` and `second` (both
/// kept) are split again and again: a chain `a → b` is split at its point `i` of the
/// greatest `badness(a, b, i)` (`None` where `i` may go), until no point of any chain
/// must go. In ring order from `first`.
fn split_chains(
    ring: &[[f64; 2]],
    first: usize,
    second: usize,
    badness: impl Fn(usize, usize, usize) -> Option<(bool, f64)>,
) -> Vec<[f64; 2]> {
    let n = ring.len();
    let mut keep = vec![false; n];
    keep[first] = true;
    keep[second] = true;
    let mut chains = vec![(first, second), (second, first)];
    while let Some((a, b)) = chains.pop() {
        let mut split: Option<(usize, (bool, f64))> = None;
        let mut i = (a + 1) % n;
        while i != b {
            if let Some(bad) = badness(a, b, i)
                && split.is_none_or(|(_, worst)| bad > worst)
            {
                split = Some((i, bad));
            }
            i = (i + 1) % n;
        }
        if let Some((m, _)) = split {
            keep[m] = true;
            chains.push((a, m));
            chains.push((m, b));
        }
    }
    (0..n)
        .map(|k| (first + k) % n)
        .filter(|&i| keep[i])
        .map(|i| ring[i])
        .collect()
}

/// The Euclidean distance from `p` to the segment `a b`.
fn distance_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let length2 = dx * dx + dy * dy;
    let t = if length2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// One edge of a ring, for the sweep.
struct Edge {
    ring: usize,
    index: usize,
    a: [f64; 2],
    b: [f64; 2],
    simplified: bool,
}

impl Edge {
    fn span(&self, axis: usize) -> (f64, f64) {
        (
            self.a[axis].min(self.b[axis]),
            self.a[axis].max(self.b[axis]),
        )
    }
}

/// The simplified rings (`simple[r]` is `Some`) that touch or cross themselves or another
/// ring of the region (`exact[r]` standing for ring r where it is not simplified).
fn conflicting_rings(exact: &[Vec<[f64; 2]>], simple: &[Option<Vec<[f64; 2]>>]) -> Vec<usize> {
    let mut edges = Vec::new();
    let mut lengths = Vec::with_capacity(exact.len());
    for (r, (e, s)) in exact.iter().zip(simple).enumerate() {
        let ring = s.as_deref().unwrap_or(e);
        lengths.push(ring.len());
        edges.extend((0..ring.len()).map(|k| Edge {
            ring: r,
            index: k,
            a: ring[k],
            b: ring[(k + 1) % ring.len()],
            simplified: s.is_some(),
        }));
    }
    edges.sort_by(|s, t| s.span(0).0.total_cmp(&t.span(0).0));
    let mut bad = vec![false; exact.len()];
    for (i, s) in edges.iter().enumerate() {
        let (_, s_hi) = s.span(0);
        let (s_lo_v, s_hi_v) = s.span(1);
        for t in &edges[i + 1..] {
            if t.span(0).0 > s_hi {
                break;
            }
            // Only a conflict that would revert a ring not yet reverted matters.
            let open = |e: &Edge| e.simplified && !bad[e.ring];
            if !(open(s) || open(t)) {
                continue;
            }
            let (t_lo_v, t_hi_v) = t.span(1);
            if t_lo_v > s_hi_v || s_lo_v > t_hi_v {
                continue;
            }
            if edges_conflict(s, t, &lengths) {
                for e in [s, t] {
                    if e.simplified {
                        bad[e.ring] = true;
                    }
                }
            }
        }
    }
    (0..bad.len()).filter(|&r| bad[r]).collect()
}

/// Whether two edges meet anywhere but at the one vertex that joins consecutive edges of
/// a ring.
fn edges_conflict(s: &Edge, t: &Edge, lengths: &[usize]) -> bool {
    if s.ring == t.ring {
        let n = lengths[s.ring];
        if (s.index + 1) % n == t.index {
            return folds_back(s.a, s.b, t.b);
        }
        if (t.index + 1) % n == s.index {
            return folds_back(t.a, t.b, s.b);
        }
    }
    segments_meet(s.a, s.b, t.a, t.b)
}

/// Whether the path `p q r` turns back on itself (`r` on the line `p q`, behind `q`).
fn folds_back(p: [f64; 2], q: [f64; 2], r: [f64; 2]) -> bool {
    orient(p, q, r) == 0 && (q[0] - p[0]) * (r[0] - q[0]) + (q[1] - p[1]) * (r[1] - q[1]) < 0.0
}

/// Whether the closed segments `a b` and `c d` have a point in common.
fn segments_meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    if o1 * o2 > 0 {
        return false;
    }
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    if o3 * o4 > 0 {
        return false;
    }
    if o1 == 0 && o2 == 0 {
        // Collinear: they meet where their extents overlap on both axes.
        return (0..2)
            .all(|k| a[k].min(b[k]) <= c[k].max(d[k]) && c[k].min(d[k]) <= a[k].max(b[k]));
    }
    true
}

/// The sign of the turn `a b c`, exactly: 1 toward +v from +u (left), −1 right, 0
/// collinear.
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i8 {
    let coord = |p: [f64; 2]| Coord { x: p[0], y: p[1] };
    let o = orient2d(coord(a), coord(b), coord(c));
    if o > 0.0 {
        1
    } else if o < 0.0 {
        -1
    } else {
        0
    }
}

/// `½ Σ (u_i v_{i+1} − u_{i+1} v_i)`, positive for a ring turning from +u toward +v.
fn signed_area(ring: &[[f64; 2]]) -> f64 {
    let Some(&o) = ring.first() else {
        return 0.0;
    };
    let twice: f64 = ring
        .iter()
        .zip(ring.iter().cycle().skip(1))
        .map(|(p, q)| (p[0] - o[0]) * (q[1] - o[1]) - (q[0] - o[0]) * (p[1] - o[1]))
        .sum();
    0.5 * twice
}

/// `[u0, v0, u1, v1]` of a ring's points.
fn bounding_box(ring: &[[f64; 2]]) -> [f64; 4] {
    ring.iter().fold(
        [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ],
        |b, p| {
            [
                b[0].min(p[0]),
                b[1].min(p[1]),
                b[2].max(p[0]),
                b[3].max(p[1]),
            ]
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::testing::Rng;

    fn exact() -> ContourOptions {
        ContourOptions {
            tolerance_px: 0.0,
            min_area_px: 0.0,
            outward: false,
        }
    }

    fn with_tolerance(tolerance_px: f64) -> ContourOptions {
        ContourOptions {
            tolerance_px,
            min_area_px: 0.0,
            outward: false,
        }
    }

    fn random_mask(rng: &mut Rng, w: u32, h: u32, density: f64) -> Mask {
        Mask::from_fn(w, h, |_, _| rng.range(0.0, 1.0) < density)
    }

    /// Random discs, some of them punched out again: blobs with holes and islands.
    fn blob_mask(rng: &mut Rng, w: u32, h: u32, discs: usize, largest: f64) -> Mask {
        let mut mask = Mask::new(w, h);
        for k in 0..discs {
            let (cu, cv) = (rng.range(0.0, w as f64), rng.range(0.0, h as f64));
            let r = rng.range(1.0, largest);
            let inside = k % 3 != 2;
            let (x0, x1) = ((cu - r).max(0.0) as u32, ((cu + r).ceil() as u32).min(w));
            let (y0, y1) = ((cv - r).max(0.0) as u32, ((cv + r).ceil() as u32).min(h));
            for y in y0..y1 {
                for x in x0..x1 {
                    let (du, dv) = (x as f64 + 0.5 - cu, y as f64 + 0.5 - cv);
                    if du * du + dv * dv <= r * r {
                        mask.set(x, y, inside);
                    }
                }
            }
        }
        mask
    }

    /// (pixels, holes) of each region, in raster order of its first pixel, found without
    /// any tracing: regions and outside components by label propagation to a fixed point
    /// (each pixel takes the least index among its neighbours of the same kind), and each
    /// outside component that does not reach the border (in a frame one pixel wider all
    /// round) credited as a hole to the region of the pixel above its first pixel.
    fn brute_force(mask: &Mask) -> Vec<(usize, usize)> {
        let (w, h) = (mask.width() as i64, mask.height() as i64);
        let propagate = |w: i64, h: i64, member: &dyn Fn(i64, i64) -> bool, diagonal: bool| {
            let mut label: Vec<usize> = (0..(w * h) as usize).collect();
            let mut changed = true;
            while changed {
                changed = false;
                for y in 0..h {
                    for x in 0..w {
                        if !member(x, y) {
                            continue;
                        }
                        let i = (y * w + x) as usize;
                        for dy in -1..=1i64 {
                            for dx in -1..=1i64 {
                                let (nx, ny) = (x + dx, y + dy);
                                let side = dx == 0 || dy == 0;
                                if (side || diagonal)
                                    && (0..w).contains(&nx)
                                    && (0..h).contains(&ny)
                                    && member(nx, ny)
                                {
                                    let j = (ny * w + nx) as usize;
                                    if label[j] < label[i] {
                                        label[i] = label[j];
                                        changed = true;
                                    }
                                }
                            }
                        }
                    }
                }
            }
            label
        };
        let inside = |x: i64, y: i64| mask.get(x as u32, y as u32);
        let regions = propagate(w, h, &inside, false);
        let mut firsts: Vec<usize> = (0..(w * h) as usize)
            .filter(|&i| mask.bits()[i] && regions[i] == i)
            .collect();
        firsts.sort_unstable();
        let mut result: Vec<(usize, usize)> = firsts
            .iter()
            .map(|&f| {
                let pixels = (0..(w * h) as usize)
                    .filter(|&i| mask.bits()[i] && regions[i] == f)
                    .count();
                (pixels, 0)
            })
            .collect();
        let (pw, ph) = (w + 2, h + 2);
        let outside = |x: i64, y: i64| {
            !(1..=w).contains(&x) || !(1..=h).contains(&y) || {
                !mask.get((x - 1) as u32, (y - 1) as u32)
            }
        };
        let background = propagate(pw, ph, &outside, true);
        for i in 0..(pw * ph) as usize {
            let (x, y) = (i as i64 % pw, i as i64 / pw);
            if outside(x, y) && background[i] == i && background[i] != background[0] {
                let above = ((y - 2) * w + (x - 1)) as usize;
                let k = firsts.binary_search(&regions[above]).expect("a region");
                result[k].1 += 1;
            }
        }
        result
    }

    fn distance_to_ring(p: [f64; 2], ring: &[[f64; 2]]) -> f64 {
        (0..ring.len())
            .map(|k| distance_to_segment(p, ring[k], ring[(k + 1) % ring.len()]))
            .fold(f64::INFINITY, f64::min)
    }

    /// Whether `p` is inside the region by the even-odd rule over all its rings.
    fn covers(region: &Region, p: [f64; 2]) -> bool {
        let mut inside = false;
        for ring in std::iter::once(&region.outer).chain(&region.holes) {
            for k in 0..ring.len() {
                let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
                if (a[1] > p[1]) != (b[1] > p[1]) {
                    let u = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                    if u > p[0] {
                        inside = !inside;
                    }
                }
            }
        }
        inside
    }

    /// Whether two edges of the rings, one of them on a simplified ring (`true`), meet
    /// other than consecutive edges at their common vertex, by trying every pair (plain
    /// arithmetic: the points tested are on the half-pixel grid).
    fn rings_meet(rings: &[(&Vec<[f64; 2]>, bool)]) -> bool {
        let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
            let c = (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
            c.partial_cmp(&0.0).map_or(0, |o| o as i8)
        };
        // (ring, index, ring length, start, end)
        let edges: Vec<_> = rings
            .iter()
            .enumerate()
            .flat_map(|(r, &(ring, _))| {
                (0..ring.len())
                    .map(move |k| (r, k, ring.len(), ring[k], ring[(k + 1) % ring.len()]))
            })
            .collect();
        for (i, &(r, k, n, a, b)) in edges.iter().enumerate() {
            for &(r2, k2, _, c, d) in &edges[i + 1..] {
                if !(rings[r].1 || rings[r2].1) {
                    continue;
                }
                if r == r2 && ((k + 1) % n == k2 || (k2 + 1) % n == k) {
                    let (p, q, s) = if (k + 1) % n == k2 {
                        (a, b, d)
                    } else {
                        (c, d, b)
                    };
                    let back = (q[0] - p[0]) * (s[0] - q[0]) + (q[1] - p[1]) * (s[1] - q[1]);
                    if cross(p, q, s) == 0 && back < 0.0 {
                        return true;
                    }
                    continue;
                }
                let (o1, o2, o3, o4) = (
                    cross(a, b, c),
                    cross(a, b, d),
                    cross(c, d, a),
                    cross(c, d, b),
                );
                let apart = o1 * o2 > 0
                    || o3 * o4 > 0
                    || (o1 == 0
                        && o2 == 0
                        && (0..2).any(|j| {
                            a[j].max(b[j]) < c[j].min(d[j]) || c[j].max(d[j]) < a[j].min(b[j])
                        }));
                if !apart {
                    return true;
                }
            }
        }
        false
    }

    #[test]
    fn regions_holes_and_pixel_counts_match_a_brute_force_fill_on_random_masks() {
        let mut rng = Rng(11);
        let mut holes_seen = 0;
        for trial in 0..80 {
            let w = 1 + (rng.next_u64() % 40) as u32;
            let h = 1 + (rng.next_u64() % 30) as u32;
            let density = [0.1, 0.4, 0.55, 0.6, 0.7, 0.9][trial % 6];
            let mask = random_mask(&mut rng, w, h, density);
            let regions = trace_regions(&mask, &exact());
            let want = brute_force(&mask);
            let got: Vec<(usize, usize)> =
                regions.iter().map(|r| (r.pixels, r.holes.len())).collect();
            assert_eq!(got, want, "{w}×{h}, density {density}");
            holes_seen += want.iter().map(|r| r.1).sum::<usize>();
            assert_eq!(
                regions.iter().map(|r| r.pixels).sum::<usize>(),
                mask.count()
            );
        }
        assert!(holes_seen > 50, "the masks had {holes_seen} holes");
    }

    #[test]
    fn unsimplified_area_is_the_pixel_count_and_rings_are_oriented_on_random_masks() {
        let mut rng = Rng(12);
        for trial in 0..80 {
            let w = 1 + (rng.next_u64() % 60) as u32;
            let h = 1 + (rng.next_u64() % 50) as u32;
            let mask = if trial % 2 == 0 {
                random_mask(&mut rng, w, h, [0.3, 0.5, 0.6, 0.8][trial / 2 % 4])
            } else {
                blob_mask(&mut rng, w, h, 12, 15.0)
            };
            let regions = trace_regions(&mask, &exact());
            for region in &regions {
                assert_eq!(region.area, region.pixels as f64, "{w}×{h}, trial {trial}");
                assert!(signed_area(&region.outer) > 0.0);
                for hole in &region.holes {
                    assert!(signed_area(hole) < 0.0);
                    assert!(hole.len() >= 4);
                }
                // The crack boundary runs along pixel sides and keeps corners only.
                for ring in std::iter::once(&region.outer).chain(&region.holes) {
                    for k in 0..ring.len() {
                        let (p, q, r) = (
                            ring[k],
                            ring[(k + 1) % ring.len()],
                            ring[(k + 2) % ring.len()],
                        );
                        assert!(p[0] == q[0] || p[1] == q[1], "an axis-aligned side");
                        assert!(p[0].fract() == 0.0 && p[1].fract() == 0.0);
                        assert_ne!((p[0] == q[0]), (q[0] == r[0]), "a corner at {q:?}");
                    }
                }
            }
            // Each bounding box is that of its region's pixels, and each outer ring starts
            // at the top-left corner of its region's first pixel.
            let (labels, _) = label_regions(&mask);
            let mut boxes = vec![[f64::INFINITY, f64::INFINITY, 0.0, 0.0]; regions.len()];
            let mut firsts = vec![None; regions.len()];
            for (i, &label) in labels.iter().enumerate() {
                if label != NO_REGION {
                    let (x, y) = ((i % w as usize) as f64, (i / w as usize) as f64);
                    let b = &mut boxes[label as usize];
                    *b = [
                        b[0].min(x),
                        b[1].min(y),
                        b[2].max(x + 1.0),
                        b[3].max(y + 1.0),
                    ];
                    firsts[label as usize].get_or_insert([x, y]);
                }
            }
            for ((region, b), first) in regions.iter().zip(boxes).zip(firsts) {
                assert_eq!(region.bbox, b);
                assert_eq!(Some(region.outer[0]), first);
            }
        }
    }

    #[test]
    fn unsimplified_rings_cover_exactly_their_regions_pixels() {
        let mut rng = Rng(13);
        for trial in 0..30 {
            let (w, h) = (
                1 + (rng.next_u64() % 30) as u32,
                1 + (rng.next_u64() % 30) as u32,
            );
            let mask = random_mask(&mut rng, w, h, [0.4, 0.6, 0.75][trial % 3]);
            let regions = trace_regions(&mask, &exact());
            for y in 0..h {
                for x in 0..w {
                    let centre = [x as f64 + 0.5, y as f64 + 0.5];
                    let covering = regions.iter().filter(|r| covers(r, centre)).count();
                    assert_eq!(covering, mask.get(x, y) as usize, "pixel ({x}, {y})");
                }
            }
        }
    }

    #[test]
    fn simplified_rings_stay_on_and_near_the_cracks_and_stay_valid() {
        let mut rng = Rng(14);
        let mut simplified = 0;
        for trial in 0..48 {
            let (w, h) = (
                4 + (rng.next_u64() % 60) as u32,
                4 + (rng.next_u64() % 60) as u32,
            );
            let mask = if trial % 3 == 0 {
                random_mask(&mut rng, w, h, 0.6)
            } else {
                blob_mask(&mut rng, w, h, 10, 25.0)
            };
            let cracks = trace_regions(&mask, &exact());
            for tolerance in [0.2, 0.5, 1.0, 2.5] {
                let regions = trace_regions(&mask, &with_tolerance(tolerance));
                assert_eq!(regions.len(), cracks.len());
                let bound = tolerance + tolerance.min(0.5) + 1e-9;
                for (region, crack) in regions.iter().zip(&cracks) {
                    assert_eq!(region.pixels, crack.pixels);
                    assert_eq!(region.holes.len(), crack.holes.len());
                    let pairs = std::iter::once((&region.outer, &crack.outer))
                        .chain(region.holes.iter().zip(&crack.holes));
                    for (k, (ring, exact_ring)) in pairs.enumerate() {
                        assert!(ring.len() >= 3);
                        let area = signed_area(ring);
                        assert!(if k == 0 { area > 0.0 } else { area < 0.0 }, "orientation");
                        for &p in ring.iter() {
                            assert!(
                                distance_to_ring(p, exact_ring) < 1e-9,
                                "{p:?} off the cracks"
                            );
                        }
                        for &p in exact_ring.iter() {
                            let d = distance_to_ring(p, ring);
                            assert!(
                                d <= bound,
                                "corner {p:?} {d} px away, tolerance {tolerance}"
                            );
                        }
                        if ring != exact_ring {
                            simplified += 1;
                        }
                    }
                    let rings: Vec<(&Vec<[f64; 2]>, bool)> = std::iter::once(&region.outer)
                        .chain(&region.holes)
                        .zip(std::iter::once(&crack.outer).chain(&crack.holes))
                        .map(|(ring, exact_ring)| (ring, ring != exact_ring))
                        .collect();
                    if tolerance >= 0.5 {
                        // On the half-pixel grid the plain test is exact.
                        assert!(!rings_meet(&rings), "rings meet at tolerance {tolerance}");
                    }
                }
            }
        }
        assert!(simplified > 500, "{simplified} rings were simplified");
    }

    #[test]
    fn a_disc_of_radius_100_gives_tens_of_vertices_and_its_area() {
        let r = 100.0;
        let mask = Mask::from_fn(240, 240, |x, y| {
            let (du, dv) = (x as f64 + 0.5 - 120.0, y as f64 + 0.5 - 120.0);
            du * du + dv * dv <= r * r
        });
        let exact_disc = trace_regions(&mask, &exact());
        let regions = trace_regions(&mask, &ContourOptions::default());
        assert_eq!(regions.len(), 1);
        let disc = &regions[0];
        println!(
            "disc r = 100: {} crack corners, {} vertices at 0.5 px, area {:.1} (πr² = {:.1}, {} pixels)",
            exact_disc[0].outer.len(),
            disc.outer.len(),
            disc.area,
            std::f64::consts::PI * r * r,
            disc.pixels
        );
        assert!(
            (10..=80).contains(&disc.outer.len()),
            "{} vertices",
            disc.outer.len()
        );
        assert!(disc.holes.is_empty());
        let circle = std::f64::consts::PI * r * r;
        assert!(
            (disc.area - circle).abs() < 0.01 * circle,
            "area {}",
            disc.area
        );
        for p in &disc.outer {
            let d = (p[0] - 120.0).hypot(p[1] - 120.0);
            assert!((d - r).abs() < 1.0, "{p:?} is {d} px from the centre");
        }
        let mut wrong = 0;
        for y in 0..240 {
            for x in 0..240 {
                if covers(disc, [x as f64 + 0.5, y as f64 + 0.5]) != mask.get(x, y) {
                    wrong += 1;
                }
            }
        }
        assert!(
            wrong as f64 <= 0.02 * disc.pixels as f64,
            "{wrong} of {} pixels differ",
            disc.pixels
        );
    }

    #[test]
    fn a_square_with_a_square_hole_keeps_four_and_four_corners() {
        let mask = Mask::from_fn(30, 30, |x, y| {
            let square = (5..25).contains(&x) && (5..25).contains(&y);
            let hole = (10..18).contains(&x) && (11..20).contains(&y);
            square && !hole
        });
        for tolerance in [0.0, 0.3, 0.5, 2.0] {
            let regions = trace_regions(&mask, &with_tolerance(tolerance));
            assert_eq!(regions.len(), 1);
            let region = &regions[0];
            assert_eq!(
                region.outer,
                vec![[5.0, 5.0], [25.0, 5.0], [25.0, 25.0], [5.0, 25.0]],
                "tolerance {tolerance}"
            );
            assert_eq!(region.holes.len(), 1);
            let mut hole = region.holes[0].clone();
            assert_eq!(hole.len(), 4);
            assert!(signed_area(&hole) < 0.0);
            hole.sort_by(|a, b| a.partial_cmp(b).unwrap());
            assert_eq!(
                hole,
                vec![[10.0, 11.0], [10.0, 20.0], [18.0, 11.0], [18.0, 20.0]]
            );
            assert_eq!(region.area, 400.0 - 72.0);
            assert_eq!(region.pixels, 328);
            assert_eq!(region.bbox, [5.0, 5.0, 25.0, 25.0]);
        }
    }

    #[test]
    fn a_45_degree_staircase_becomes_one_straight_edge() {
        // Pixels on or below the diagonal: a staircase of 50 steps.
        let mask = Mask::from_fn(50, 50, |x, y| x <= y);
        let exact_triangle = trace_regions(&mask, &exact());
        assert_eq!(exact_triangle[0].outer.len(), 50 + 49 + 3);
        let regions = trace_regions(&mask, &ContourOptions::default());
        let outer = &regions[0].outer;
        assert!(outer.len() <= 5, "{outer:?}");
        // The long edge runs through the crack midpoints, v = u − ½.
        let longest = (0..outer.len())
            .map(|k| (outer[k], outer[(k + 1) % outer.len()]))
            .max_by(|(a, b), (c, d)| {
                let l = |p: [f64; 2], q: [f64; 2]| (q[0] - p[0]).hypot(q[1] - p[1]);
                l(*a, *b).total_cmp(&l(*c, *d))
            })
            .unwrap();
        for p in [longest.0, longest.1] {
            assert_eq!(p[1], p[0] - 0.5, "{longest:?}");
        }
    }

    #[test]
    fn small_and_touching_regions() {
        // One pixel, and pixels touching only at corners: a region each.
        let mut mask = Mask::new(5, 4);
        mask.set(0, 0, true);
        mask.set(2, 1, true);
        mask.set(3, 2, true);
        mask.set(2, 3, true);
        for options in [exact(), ContourOptions::default()] {
            let regions = trace_regions(&mask, &options);
            assert_eq!(regions.len(), 4);
            let unit =
                |x: f64, y: f64| vec![[x, y], [x + 1.0, y], [x + 1.0, y + 1.0], [x, y + 1.0]];
            for (region, (x, y)) in
                regions
                    .iter()
                    .zip([(0.0, 0.0), (2.0, 1.0), (3.0, 2.0), (2.0, 3.0)])
            {
                assert_eq!(region.outer, unit(x, y));
                assert_eq!((region.area, region.pixels), (1.0, 1));
                assert_eq!(region.bbox, [x, y, x + 1.0, y + 1.0]);
                assert!(region.holes.is_empty());
            }
        }
        // A checkerboard: every pixel its own region.
        let board = Mask::from_fn(64, 64, |x, y| (x + y) % 2 == 0);
        let regions = trace_regions(&board, &ContourOptions::default());
        assert_eq!(regions.len(), 64 * 32);
        assert!(
            regions
                .iter()
                .all(|r| r.outer.len() == 4 && r.holes.is_empty() && r.area == 1.0)
        );
    }

    #[test]
    fn a_pinched_ring_touches_itself_and_encloses_no_hole() {
        // The outside reaches the middle pixel through the corner (3, 3), where two
        // pixels of the region meet diagonally: no hole, and the outer ring passes that
        // corner twice.
        #[rustfmt::skip]
        let rows = [
            ".....",
            ".###.",
            ".#.#.",
            ".##..",
            ".....",
        ];
        let mask = Mask::from_fn(5, 5, |x, y| rows[y as usize].as_bytes()[x as usize] == b'#');
        let regions = trace_regions(&mask, &exact());
        assert_eq!(regions.len(), 1);
        assert!(regions[0].holes.is_empty());
        assert_eq!((regions[0].pixels, regions[0].area), (7, 7.0));
        let visits = regions[0]
            .outer
            .iter()
            .filter(|&&p| p == [3.0, 3.0])
            .count();
        assert_eq!(visits, 2);
        let regions = trace_regions(&mask, &ContourOptions::default());
        assert_eq!(regions.len(), 1);
        assert!(regions[0].holes.is_empty());
        assert!(regions[0].outer.len() >= 3 && regions[0].area > 0.0);
    }

    #[test]
    fn several_holes_and_an_island_inside_a_hole() {
        #[rustfmt::skip]
        let rows = [
            "###########",
            "#...#.....#",
            "#...#.###.#",
            "#####.#.#.#",
            "#.#...###.#",
            "###.......#",
            "###########",
        ];
        let mask = Mask::from_fn(11, 7, |x, y| {
            rows[y as usize].as_bytes()[x as usize] == b'#'
        });
        for options in [exact(), ContourOptions::default()] {
            let regions = trace_regions(&mask, &options);
            assert_eq!(regions.len(), 2);
            let (frame, island) = (&regions[0], &regions[1]);
            assert_eq!((frame.pixels, island.pixels), (41, 8));
            assert_eq!(frame.bbox, [0.0, 0.0, 11.0, 7.0]);
            assert_eq!(island.bbox, [6.0, 2.0, 9.0, 5.0]);
            assert_eq!(island.holes.len(), 1);
            assert_eq!(island.holes[0][0], [7.0, 3.0]);
            // Holes in raster order of their first pixel, each ring starting at its
            // top-left corner.
            let starts: Vec<[f64; 2]> = frame.holes.iter().map(|h| h[0]).collect();
            assert_eq!(starts, vec![[1.0, 1.0], [5.0, 1.0], [1.0, 4.0]]);
            if options.tolerance_px == 0.0 {
                let hole_pixels: Vec<f64> = frame.holes.iter().map(|h| -signed_area(h)).collect();
                // The middle hole's ring encloses the island and its hole too.
                assert_eq!(hole_pixels, vec![6.0, 29.0, 1.0]);
                assert_eq!(frame.area, 41.0);
            }
        }
    }

    #[test]
    fn empty_full_and_degenerate_masks() {
        assert!(trace_regions(&Mask::new(0, 0), &exact()).is_empty());
        assert!(trace_regions(&Mask::new(7, 0), &exact()).is_empty());
        assert!(trace_regions(&Mask::new(7, 5), &exact()).is_empty());
        let full = Mask::from_fn(7, 5, |_, _| true);
        for options in [exact(), ContourOptions::default()] {
            let regions = trace_regions(&full, &options);
            assert_eq!(regions.len(), 1);
            assert_eq!(
                regions[0].outer,
                vec![[0.0, 0.0], [7.0, 0.0], [7.0, 5.0], [0.0, 5.0]]
            );
            assert_eq!((regions[0].area, regions[0].pixels), (35.0, 35));
            assert_eq!(regions[0].bbox, [0.0, 0.0, 7.0, 5.0]);
        }
        // A one-pixel-wide line keeps its rectangle rather than collapsing.
        let line = Mask::from_fn(50, 1, |_, _| true);
        let regions = trace_regions(&line, &ContourOptions::default());
        assert_eq!(regions[0].outer.len(), 4);
        assert_eq!(regions[0].area, 50.0);
    }

    #[test]
    fn small_regions_are_left_out_and_any_options_are_taken() {
        let mut mask = Mask::new(20, 10);
        mask.set(1, 1, true);
        for y in 3..8 {
            for x in 5..15 {
                mask.set(x, y, true);
            }
        }
        let options = ContourOptions {
            min_area_px: 2.0,
            ..ContourOptions::default()
        };
        let regions = trace_regions(&mask, &options);
        assert_eq!(regions.len(), 1);
        assert_eq!(regions[0].pixels, 50);
        let exact_regions = trace_regions(&mask, &exact());
        assert_eq!(exact_regions.len(), 2);
        for odd in [-0.1, f64::NAN] {
            let options = ContourOptions {
                tolerance_px: odd,
                min_area_px: odd,
                outward: false,
            };
            assert_eq!(trace_regions(&mask, &options), exact_regions, "{odd}");
        }
        // No tolerance is too large: a ring it would reduce to two points stays exact.
        let huge = trace_regions(&mask, &with_tolerance(f64::INFINITY));
        assert_eq!(huge, exact_regions);
        let none = ContourOptions {
            min_area_px: f64::INFINITY,
            ..ContourOptions::default()
        };
        assert!(trace_regions(&mask, &none).is_empty());
    }

    #[test]
    fn mask_construction_and_access() {
        let mask = Mask::from_bits(3, 2, vec![true, false, false, false, true, true]).unwrap();
        assert_eq!((mask.width(), mask.height(), mask.count()), (3, 2, 3));
        assert!(mask.get(0, 0) && mask.get(2, 1) && !mask.get(1, 0));
        assert!(
            !mask.get(3, 0) && !mask.get(0, 2),
            "beyond the mask is outside"
        );
        assert_eq!(
            mask,
            Mask::from_fn(3, 2, |x, y| (x == 0 && y == 0) || (y == 1 && x > 0))
        );
        assert_eq!(
            Mask::from_bits(3, 2, vec![false; 5]),
            Err(ImageError::Samples {
                expected: 6,
                got: 5
            })
        );
        assert!(matches!(
            Mask::from_bits(u32::MAX, 2, Vec::new()),
            Err(ImageError::BadParameter { .. })
        ));
    }

    #[test]
    fn a_2000_square_serpentine_is_traced_without_recursion() {
        // Full rows joined alternately at the right and left ends: one region, one ring
        // of about 4 million pixel sides.
        let n = 2000;
        let mask = Mask::from_fn(n, n, |x, y| {
            y % 2 == 0 || (y % 4 == 1 && x == n - 1) || (y % 4 == 3 && x == 0)
        });
        let regions = trace_regions(&mask, &exact());
        assert_eq!(regions.len(), 1);
        assert!(regions[0].holes.is_empty());
        assert_eq!(regions[0].pixels, mask.count());
        assert_eq!(regions[0].area, mask.count() as f64);
        let simplified = trace_regions(&mask, &ContourOptions::default());
        assert_eq!(simplified.len(), 1);
        assert!(simplified[0].outer.len() >= 3);
        assert!(signed_area(&simplified[0].outer) > 0.0);
    }

    #[test]
    fn a_640_by_480_blob_mask_is_traced_quickly() {
        let mut rng = Rng(15);
        let mask = blob_mask(&mut rng, 640, 480, 400, 30.0);
        let start = std::time::Instant::now();
        let regions = trace_regions(&mask, &ContourOptions::default());
        let simplified_time = start.elapsed();
        let start = std::time::Instant::now();
        let cracks = trace_regions(&mask, &exact());
        let exact_time = start.elapsed();
        let vertices: usize = regions
            .iter()
            .map(|r| r.outer.len() + r.holes.iter().map(Vec::len).sum::<usize>())
            .sum();
        let corners: usize = cracks
            .iter()
            .map(|r| r.outer.len() + r.holes.iter().map(Vec::len).sum::<usize>())
            .sum();
        println!(
            "640×480 blobs ({} inside pixels): {} regions, {} holes; \
             tolerance 0.5 px: {vertices} vertices in {simplified_time:?}; \
             tolerance 0: {corners} corners in {exact_time:?}",
            mask.count(),
            regions.len(),
            regions.iter().map(|r| r.holes.len()).sum::<usize>(),
        );
        assert_eq!(regions.len(), cracks.len());
        assert_eq!(
            cracks.iter().map(|r| r.area).sum::<f64>(),
            mask.count() as f64
        );
        assert!(
            vertices < corners / 2,
            "{vertices} vertices from {corners} corners"
        );
    }
}
