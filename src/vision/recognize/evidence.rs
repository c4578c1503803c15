//! What a picture's edges say about the model's predicted edges: which of a body's
//! visible edge points lie on an image edge running the same way, and which image edges
//! some predicted edge accounts for.

use glam::DVec2;

use crate::render::hidden::Segment;
use crate::vision::image::EdgeMap;

/// How predicted edges are matched with image edges.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Matching {
    /// The farthest an image edge may be from a predicted edge point and support it,
    /// pixels.
    pub tolerance_px: f64,
    /// The cosine of the largest angle between the predicted edge and the image edge.
    pub min_cos: f64,
    /// Distance between points sampled along a predicted edge, pixels.
    pub spacing_px: f64,
}

/// A point on a predicted edge, in pixels, with the edge's unit direction in the image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgePoint {
    /// Where, pixels.
    pub pixel: DVec2,
    /// The edge's unit direction in the image.
    pub direction: DVec2,
}

/// Points every `spacing_px` along the visible `pieces`, at the middles of equal steps
/// (a piece shorter than one spacing gives one point at its middle; a piece of no length
/// none).
pub fn edge_points<'a>(
    pieces: impl IntoIterator<Item = &'a Segment>,
    spacing_px: f64,
) -> Vec<EdgePoint> {
    let mut points = Vec::new();
    for piece in pieces {
        let d = piece.b - piece.a;
        let length = d.length();
        if !(length.is_finite() && length > 0.0) {
            continue;
        }
        let direction = d / length;
        let n = (length / spacing_px).ceil().max(1.0) as usize;
        points.extend((0..n).map(|i| EdgePoint {
            pixel: piece.a + d * ((i as f64 + 0.5) / n as f64),
            direction,
        }));
    }
    points
}

impl Matching {
    /// Whether an image edge of `edges` within the tolerance of `point` runs along its
    /// direction.
    pub fn supported(&self, edges: &EdgeMap, point: &EdgePoint) -> bool {
        self.supported_at(edges, point, DVec2::ZERO)
    }

    /// [`Matching::supported`] for the point shifted by `shift` pixels.
    pub fn supported_at(&self, edges: &EdgeMap, point: &EdgePoint, shift: DVec2) -> bool {
        let p = point.pixel + shift;
        let Some(edgel) = edges.nearest(p.x, p.y) else {
            return false;
        };
        let e = edgel.position.as_dvec2();
        p.distance_squared(e) <= self.tolerance_px * self.tolerance_px
            && self.runs_along(edgel.normal.as_dvec2(), point.direction)
    }

    /// Whether an image edge of unit normal `normal` runs within the largest angle of
    /// the unit direction `direction`.
    fn runs_along(&self, normal: DVec2, direction: DVec2) -> bool {
        normal.perp_dot(direction).abs() >= self.min_cos
    }

    /// The fraction of `points` that the image's edges support; `None` for no points.
    pub fn support(&self, edges: &EdgeMap, points: &[EdgePoint]) -> Option<f64> {
        (!points.is_empty()).then(|| {
            let hits = points.iter().filter(|p| self.supported(edges, p)).count();
            hits as f64 / points.len() as f64
        })
    }

    /// Marks in `explained` (one flag per pixel, row-major) every edge pixel of `edges`
    /// that lies within the tolerance of one of `points` and runs along it.
    ///
    /// Precondition: `explained.len()` is the edge map's pixel count.
    pub fn explain(&self, edges: &EdgeMap, points: &[EdgePoint], explained: &mut [bool]) {
        let (w, h) = (edges.width() as i64, edges.height() as i64);
        let reach = self.tolerance_px.ceil() as i64 + 1;
        let tolerance2 = self.tolerance_px * self.tolerance_px;
        for point in points {
            let (cx, cy) = (point.pixel.x.floor() as i64, point.pixel.y.floor() as i64);
            for y in (cy - reach).max(0)..=(cy + reach).min(h - 1) {
                for x in (cx - reach).max(0)..=(cx + reach).min(w - 1) {
                    let Some(edgel) = edges.edgel_at(x as u32, y as u32) else {
                        continue;
                    };
                    let e = edgel.position.as_dvec2();
                    if e.distance_squared(point.pixel) <= tolerance2
                        && self.runs_along(edgel.normal.as_dvec2(), point.direction)
                    {
                        explained[(y * w + x) as usize] = true;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{BodyId, Serial};
    use crate::vision::image::{EdgeOptions, Luma};

    /// A 64 × 48 picture dark left of the column u = 30.5 and bright right of it.
    fn step() -> EdgeMap {
        let (w, h) = (64u32, 48u32);
        let pixels: Vec<u8> = (0..w * h)
            .map(|i| if (i % w) as f64 + 0.5 < 30.5 { 40 } else { 200 })
            .collect();
        let luma = Luma::from_samples(w, h, 1, &pixels).expect("a picture");
        EdgeMap::detect(&luma, &EdgeOptions::default()).expect("edges")
    }

    fn segment(a: [f64; 2], b: [f64; 2]) -> Segment {
        Segment {
            body: BodyId(Serial(1)),
            edge: 1,
            a: DVec2::from_array(a),
            b: DVec2::from_array(b),
            depth: [1.0, 1.0],
        }
    }

    const MATCHING: Matching = Matching {
        tolerance_px: 2.0,
        min_cos: 0.866,
        spacing_px: 1.0,
    };

    #[test]
    fn an_edge_on_the_step_is_supported_and_one_beside_or_across_it_is_not() {
        let edges = step();
        let on = edge_points(&[segment([30.5, 8.0], [30.5, 40.0])], 1.0);
        assert_eq!(on.len(), 32);
        assert_eq!(MATCHING.support(&edges, &on), Some(1.0));
        let beside = edge_points(&[segment([36.0, 8.0], [36.0, 40.0])], 1.0);
        assert_eq!(MATCHING.support(&edges, &beside), Some(0.0));
        let across = edge_points(&[segment([26.0, 20.0], [35.0, 20.0])], 1.0);
        assert_eq!(MATCHING.support(&edges, &across), Some(0.0));
        assert_eq!(MATCHING.support(&edges, &[]), None);
    }

    #[test]
    fn only_the_edge_pixels_along_a_predicted_edge_are_explained() {
        let edges = step();
        let mut explained = vec![false; 64 * 48];
        let points = edge_points(&[segment([30.5, 10.0], [30.5, 20.0])], 1.0);
        MATCHING.explain(&edges, &points, &mut explained);
        let marked: Vec<(u32, u32)> = (0..48u32)
            .flat_map(|y| (0..64u32).map(move |x| (x, y)))
            .filter(|&(x, y)| explained[(y * 64 + x) as usize])
            .collect();
        assert!(!marked.is_empty());
        for &(x, y) in &marked {
            assert!(
                edges.edgel_at(x, y).is_some(),
                "({x}, {y}) is no edge pixel"
            );
            assert!(
                (8..=22).contains(&y),
                "({x}, {y}) is beyond the predicted edge"
            );
        }
        let across = edge_points(&[segment([26.0, 30.0], [35.0, 30.0])], 1.0);
        let mut none = vec![false; 64 * 48];
        MATCHING.explain(&edges, &across, &mut none);
        assert!(none.iter().all(|&e| !e));
    }
}
