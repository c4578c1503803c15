//! Edges of a grey-level picture: Sobel gradients, non-maximum suppression, a threshold
//! set from the picture's own noise, sub-pixel positions, and the distance transform of
//! the result.
//!
//! # Method
//!
//! 1. **Gradient.** The Sobel operator divided by 8, so that the gradient is in grey
//!    levels per pixel: a step of height `s` between two pixels gives a peak of `s/2`.
//!    Pixels on the picture's border get no gradient (no edge is found there).
//! 2. **Threshold from the noise.** On a picture made mostly of smooth areas the gradient
//!    of most pixels is noise. For independent Gaussian pixel noise of deviation σ each
//!    gradient component has deviation `σ_g = σ·√12/8 ≈ 0.433·σ`, and the gradient
//!    magnitude follows a Rayleigh law whose median is `σ_g·√(2 ln 2) ≈ 1.177·σ_g`. The
//!    noise is estimated from the median magnitude (over every other pixel of every
//!    other row) as
//!    `σ_g ≈ median/1.177`, and a pixel can be an edge only if its magnitude is at least
//!    `max(noise_factor·σ_g, min_gradient)` ([`EdgeOptions`]). With the default factor
//!    of 4, noise alone passes the threshold at a fraction `exp(−8) ≈ 3·10⁻⁴` of the pixels
//!    (before suppression). The median overestimates the noise of a picture that is
//!    mostly texture, which only raises the threshold; `min_gradient` keeps a noiseless
//!    picture (median 0) from taking rounding ripples for edges.
//! 3. **Non-maximum suppression.** A pixel stays an edge only if its magnitude is a
//!    maximum along the gradient direction, quantised to the nearest of 0°, 45°, 90° and
//!    135°: strictly above the neighbour behind, at least the neighbour ahead (so of two
//!    equal pixels on either side of a step exactly one remains). A neighbour whose
//!    gradient points the opposite way counts as zero: it belongs to the other side of a
//!    stripe a few pixels wide (a face seen nearly edge-on), which is another edge and
//!    must not suppress this one.
//! 4. **Sub-pixel position.** A parabola through the three magnitudes along that
//!    direction puts the edge at offset `δ = (m₋ − m₊) / (2·(m₋ − 2m + m₊))`, `|δ| ≤ ½`,
//!    from the pixel centre, in units of the neighbour step. For a step edge between
//!    two pixels this is exactly the pixel boundary.
//! 5. **Distance transform** of the edge pixels ([`DistanceField`]), so the nearest edge
//!    to any point is one look-up.

use glam::Vec2;
use rayon::prelude::*;

use super::ImageError;
use super::distance::{DistanceField, NO_SITE};
use super::luma::Luma;

/// How edges are told from noise (see the [image module's documentation](crate::vision::image)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeOptions {
    /// The threshold in multiples of the estimated noise of one gradient component;
    /// finite and positive.
    pub noise_factor: f64,
    /// The lowest threshold, grey levels per pixel (a step of twice this height between
    /// two pixels reaches it); finite and positive.
    pub min_gradient: f64,
}

impl Default for EdgeOptions {
    /// A factor of 4 and at least 2 grey levels per pixel.
    fn default() -> Self {
        EdgeOptions {
            noise_factor: 4.0,
            min_gradient: 2.0,
        }
    }
}

impl EdgeOptions {
    pub(crate) fn validate(&self) -> Result<(), ImageError> {
        for (value, what) in [
            (self.noise_factor, "the edge noise factor"),
            (self.min_gradient, "the minimum edge gradient"),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(ImageError::BadParameter { what, value });
            }
        }
        Ok(())
    }
}

/// One edge pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edgel {
    /// Where the edge crosses this pixel, in pixel coordinates (corner origin: the pixel
    /// `(x, y)` spans `[x, x+1) × [y, y+1)`); within one pixel step of its centre.
    pub position: Vec2,
    /// The unit gradient direction (towards brighter), the edge's normal in the image.
    pub normal: Vec2,
    /// The gradient magnitude, grey levels per pixel.
    pub strength: f32,
}

/// The edges of a picture and their distance transform. See the
/// [image module's documentation](crate::vision::image).
///
/// Invariants: `at.len() == width × height`; `at[i]` is an index into `edgels` or
/// [`NO_SITE`]; the field's sites are exactly the pixels with an edgel.
#[derive(Clone, Debug)]
pub struct EdgeMap {
    width: u32,
    height: u32,
    threshold: f64,
    edgels: Vec<Edgel>,
    at: Vec<u32>,
    field: DistanceField,
}

impl EdgeMap {
    /// The edges of `image`.
    ///
    /// Refused with [`ImageError::BadParameter`] when `options` are out of range.
    /// Postcondition: every edgel passed the threshold ([`EdgeMap::threshold`]) and
    /// non-maximum suppression; a blank picture has none.
    pub fn detect(image: &Luma, options: &EdgeOptions) -> Result<EdgeMap, ImageError> {
        options.validate()?;
        let (w, h) = (image.width() as usize, image.height() as usize);
        let gradient = Gradient::of(image);
        let threshold =
            (options.noise_factor * gradient.noise_deviation()).max(options.min_gradient);
        let rows: Vec<Vec<(u32, Edgel)>> = (0..h)
            .into_par_iter()
            .with_min_len(16)
            .map(|y| gradient.suppress_row(y, threshold as f32))
            .collect();
        let mut edgels = Vec::with_capacity(rows.iter().map(Vec::len).sum());
        let mut at = vec![NO_SITE; w * h];
        for (i, edgel) in rows.into_iter().flatten() {
            at[i as usize] = edgels.len() as u32;
            edgels.push(edgel);
        }
        let sites: Vec<bool> = at.iter().map(|&e| e != NO_SITE).collect();
        let field = DistanceField::from_sites(image.width(), image.height(), &sites)?;
        Ok(EdgeMap {
            width: image.width(),
            height: image.height(),
            threshold,
            edgels,
            at,
            field,
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

    /// The gradient threshold used, grey levels per pixel.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// Every edge pixel, in row-major order of the pixels.
    pub fn edgels(&self) -> &[Edgel] {
        &self.edgels
    }

    /// The edge pixel at column `x`, row `y`, if that pixel is one.
    pub fn edgel_at(&self, x: u32, y: u32) -> Option<&Edgel> {
        if x >= self.width || y >= self.height {
            return None;
        }
        self.edgels
            .get(self.at[y as usize * self.width as usize + x as usize] as usize)
    }

    /// The edge pixel nearest (between pixel centres) to the pixel containing the point
    /// `(u, v)`; `None` when that point is outside the picture (or not finite) or the
    /// picture has no edges.
    #[inline]
    pub fn nearest(&self, u: f64, v: f64) -> Option<&Edgel> {
        if !(u >= 0.0 && v >= 0.0 && u < self.width as f64 && v < self.height as f64) {
            return None;
        }
        let site = self.field.nearest_index(u as u32, v as u32);
        if site == NO_SITE {
            return None;
        }
        self.edgels.get(self.at[site as usize] as usize)
    }

    /// The distance transform of the edge pixels.
    pub fn field(&self) -> &DistanceField {
        &self.field
    }
}

/// Sobel gradients (×8, so integers) and magnitudes (grey levels per pixel).
struct Gradient {
    width: usize,
    height: usize,
    gx: Vec<i16>,
    gy: Vec<i16>,
    magnitude: Vec<f32>,
}

/// Bins of the magnitude histogram per grey level per pixel, and how many grey levels per
/// pixel it covers (larger magnitudes go to the last bin).
const BINS_PER_LEVEL: f64 = 16.0;
const HISTOGRAM_LEVELS: usize = 64;

/// The median of a Rayleigh law in units of its σ: `√(2 ln 2)`.
const RAYLEIGH_MEDIAN: f64 = 1.177_410_022_515_474_7;

impl Gradient {
    fn of(image: &Luma) -> Gradient {
        let (w, h) = (image.width() as usize, image.height() as usize);
        let p = image.pixels();
        let mut gx = vec![0i16; w * h];
        let mut gy = vec![0i16; w * h];
        let mut magnitude = vec![0f32; w * h];
        if w >= 3 && h >= 3 {
            let n = w - 2;
            gx.par_chunks_mut(w)
                .zip(gy.par_chunks_mut(w))
                .zip(magnitude.par_chunks_mut(w))
                .enumerate()
                .with_min_len(16)
                .for_each_init(
                    || (vec![0i16; w], vec![0i16; w]),
                    |(smooth, across), (y, ((gx, gy), m))| {
                        if y == 0 || y == h - 1 {
                            return;
                        }
                        let up = &p[(y - 1) * w..][..w];
                        let mid = &p[y * w..][..w];
                        let down = &p[(y + 1) * w..][..w];
                        // The separable Sobel: columns smoothed (1, 2, 1) and differenced
                        // (−1, 0, 1) down the three rows, then the other way along the row.
                        for ((((s, a), &u), &c), &d) in smooth
                            .iter_mut()
                            .zip(across.iter_mut())
                            .zip(up)
                            .zip(mid)
                            .zip(down)
                        {
                            *s = u as i16 + 2 * c as i16 + d as i16;
                            *a = d as i16 - u as i16;
                        }
                        let (s0, s2) = (&smooth[..n], &smooth[2..]);
                        let (a0, a1, a2) = (&across[..n], &across[1..=n], &across[2..]);
                        let (gx, gy, m) = (&mut gx[1..=n], &mut gy[1..=n], &mut m[1..=n]);
                        for i in 0..n {
                            let sx = s2[i] - s0[i];
                            let sy = a0[i] + 2 * a1[i] + a2[i];
                            gx[i] = sx;
                            gy[i] = sy;
                            let (fx, fy) = (sx as f32, sy as f32);
                            m[i] = (fx * fx + fy * fy).sqrt() * 0.125;
                        }
                    },
                );
        }
        Gradient {
            width: w,
            height: h,
            gx,
            gy,
            magnitude,
        }
    }

    /// The deviation of one gradient component's noise, estimated from the median
    /// magnitude over a quarter of the interior pixels (see the module documentation).
    fn noise_deviation(&self) -> f64 {
        let (w, h) = (self.width, self.height);
        if w < 3 || h < 3 {
            return 0.0;
        }
        let bins = HISTOGRAM_LEVELS * BINS_PER_LEVEL as usize;
        let mut histogram = vec![0u32; bins];
        // Every other row and column: a quarter of the pixels gives the same median.
        let mut counted = 0u64;
        for y in (1..h - 1).step_by(2) {
            for &m in self.magnitude[y * w + 1..][..w - 2].iter().step_by(2) {
                let bin = ((m * BINS_PER_LEVEL as f32) as usize).min(bins - 1);
                histogram[bin] += 1;
                counted += 1;
            }
        }
        let half = counted.div_ceil(2);
        let mut seen = 0u64;
        for (bin, &count) in histogram.iter().enumerate() {
            seen += count as u64;
            if seen >= half {
                // The bin's centre.
                let median = (bin as f64 + 0.5) / BINS_PER_LEVEL;
                return if bin == 0 {
                    0.0
                } else {
                    median / RAYLEIGH_MEDIAN
                };
            }
        }
        0.0
    }

    /// The edge pixels of row `y` after suppression: `(pixel index, edgel)`.
    fn suppress_row(&self, y: usize, threshold: f32) -> Vec<(u32, Edgel)> {
        let (w, h) = (self.width, self.height);
        let mut out = Vec::new();
        if y == 0 || y + 1 >= h || w < 3 {
            return out;
        }
        // tan(22.5°) in the comparisons below.
        const TAN_22_5: f32 = 0.414_213_56;
        let m = &self.magnitude;
        for x in 1..w - 1 {
            let i = y * w + x;
            let here = m[i];
            if here < threshold {
                continue;
            }
            let (gx, gy) = (self.gx[i] as f32, self.gy[i] as f32);
            let (ax, ay) = (gx.abs(), gy.abs());
            // The neighbour step (dx, dy) along the quantised gradient.
            let (dx, dy): (isize, isize) = if ay <= TAN_22_5 * ax {
                (1, 0)
            } else if ax <= TAN_22_5 * ay {
                (0, 1)
            } else if (gx > 0.0) == (gy > 0.0) {
                (1, 1)
            } else {
                (1, -1)
            };
            let step = dy * w as isize + dx;
            // A neighbour whose gradient points the other way is the far side of a thin
            // stripe, another edge: it does not suppress this one.
            let along = |j: usize| {
                let same = self.gx[j] as i32 * self.gx[i] as i32
                    + self.gy[j] as i32 * self.gy[i] as i32
                    > 0;
                if same { m[j] } else { 0.0 }
            };
            let ahead = along((i as isize + step) as usize);
            let behind = along((i as isize - step) as usize);
            if !(here > behind && here >= ahead) {
                continue;
            }
            let curvature = behind - 2.0 * here + ahead;
            let delta = if curvature < 0.0 {
                ((behind - ahead) / (2.0 * curvature)).clamp(-0.5, 0.5)
            } else {
                0.0
            };
            let position = Vec2::new(
                x as f32 + 0.5 + delta * dx as f32,
                y as f32 + 0.5 + delta * dy as f32,
            );
            let normal = Vec2::new(gx, gy) / (8.0 * here);
            out.push((
                i as u32,
                Edgel {
                    position,
                    normal,
                    strength: here,
                },
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w × h` picture of grey `outside` with the rectangle `[x0, x1) × [y0, y1)` (pixel
    /// boundaries) in grey `inside`.
    fn rectangle(w: u32, h: u32, (x0, y0, x1, y1): (u32, u32, u32, u32), inside: u8) -> Luma {
        let outside = 40;
        let samples: Vec<u8> = (0..h)
            .flat_map(|y| {
                (0..w).map(move |x| {
                    if (x0..x1).contains(&x) && (y0..y1).contains(&y) {
                        inside
                    } else {
                        outside
                    }
                })
            })
            .collect();
        Luma::from_samples(w, h, 1, &samples).unwrap()
    }

    #[test]
    fn a_step_edge_is_found_on_the_pixel_boundary_with_its_normal() {
        let image = rectangle(40, 30, (10, 8, 30, 22), 200);
        let map = EdgeMap::detect(&image, &EdgeOptions::default()).unwrap();
        // The left side, away from the corners: the edge is the line u = 10, normal +x.
        for y in 11..19 {
            let edgels: Vec<_> = (0..40).filter_map(|x| map.edgel_at(x, y)).collect();
            let left: Vec<_> = edgels.iter().filter(|e| e.position.x < 20.0).collect();
            assert_eq!(left.len(), 1, "one edge pixel per row on the left side");
            let e = left[0];
            assert!((e.position.x - 10.0).abs() < 1e-5, "{e:?}");
            assert!((e.normal - Vec2::X).length() < 1e-6, "{e:?}");
            assert!(
                (e.strength - 80.0).abs() < 1e-3,
                "a step of 160 peaks at 80"
            );
        }
        // The bottom side: v = 22, normal −y (brighter above).
        let e = map.edgel_at(20, 21).or(map.edgel_at(20, 22)).unwrap();
        assert!((e.position.y - 22.0).abs() < 1e-5, "{e:?}");
        assert!((e.normal + Vec2::Y).length() < 1e-6);
        // Nothing far from the rectangle's outline.
        assert!(map.edgels().iter().all(|e| {
            let p = e.position;
            let near_x = (p.x - 10.0).abs() < 1.5 || (p.x - 30.0).abs() < 1.5;
            let near_y = (p.y - 8.0).abs() < 1.5 || (p.y - 22.0).abs() < 1.5;
            near_x || near_y
        }));
        // The nearest edge from the middle of the rectangle is on its nearest side.
        let e = map.nearest(12.2, 15.0).unwrap();
        assert!((e.position.x - 10.0).abs() < 1e-5);
        assert_eq!(map.nearest(-1.0, 15.0), None);
    }

    #[test]
    fn a_blank_picture_has_no_edges_and_faint_steps_are_ignored() {
        let blank = rectangle(32, 32, (0, 0, 0, 0), 0);
        let map = EdgeMap::detect(&blank, &EdgeOptions::default()).unwrap();
        assert!(map.edgels().is_empty());
        assert_eq!(map.nearest(5.0, 5.0), None);
        // A step of 3 grey levels peaks at 1.5 < 2 grey levels per pixel.
        let faint = rectangle(32, 32, (8, 8, 24, 24), 43);
        assert!(
            EdgeMap::detect(&faint, &EdgeOptions::default())
                .unwrap()
                .edgels()
                .is_empty()
        );
    }

    #[test]
    fn the_threshold_follows_the_noise() {
        use crate::vision::testing::Rng;
        let mut rng = Rng(11);
        let sigma = 6.0;
        let samples: Vec<u8> = (0..200 * 150)
            .map(|_| (128.0 + sigma * rng.normal()).round().clamp(0.0, 255.0) as u8)
            .collect();
        let noise = Luma::from_samples(200, 150, 1, &samples).unwrap();
        let map = EdgeMap::detect(&noise, &EdgeOptions::default()).unwrap();
        // σ_g = 0.433·σ ≈ 2.6, so the threshold is about 10.4 grey levels per pixel.
        let want = 4.0 * sigma * 12f64.sqrt() / 8.0;
        assert!(
            (map.threshold() - want).abs() < 0.1 * want,
            "threshold {} for noise alone, expected about {want}",
            map.threshold()
        );
        assert!(
            map.edgels().len() < 200 * 150 / 1000,
            "noise alone leaves few edges ({})",
            map.edgels().len()
        );
    }

    /// A box rendered shaded (default light, grey-blue background): every visible edge of
    /// the exact hidden-line drawing has an edge pixel on it, and every edge pixel lies
    /// on a drawn edge.
    #[test]
    fn the_edges_of_a_rendered_box_are_found() {
        use crate::camera::{Camera, DEFAULT_NEAR, Intrinsics, View};
        use crate::model::solids::box_solid;
        use crate::model::{Pose, World};
        use crate::render::hidden::hidden_lines;
        use crate::render::{Mode, Options, Picture, SHADED_BACKGROUND, Scene, render};
        use glam::{DQuat, DVec2, DVec3};

        let mut world = World::new();
        let root = world.root();
        let pose = Pose::new(DVec3::ZERO, DQuat::from_rotation_z(0.4)).unwrap();
        world
            .insert_with(Some("box"), root, pose, |s| {
                box_solid(s, DVec3::new(0.4, 0.3, 0.2))
            })
            .unwrap();
        let scene = Scene::build(&world);
        let k = Intrinsics::centered(320, 240, 400.0).unwrap();
        let camera = Camera::look_at(DVec3::new(0.9, -1.1, 0.8), DVec3::ZERO, DVec3::Z, k).unwrap();
        let options = Options {
            background: SHADED_BACKGROUND,
            ..Options::default()
        };
        let Picture::Rgb(rgb) = render(&scene, &camera, Mode::Shaded, &options).unwrap() else {
            panic!("a shaded picture is RGB");
        };
        let image = Luma::from_samples(rgb.width, rgb.height, 3, &rgb.data).unwrap();
        let map = EdgeMap::detect(&image, &EdgeOptions::default()).unwrap();
        let segments = hidden_lines(&scene, &View::new(&camera, DEFAULT_NEAR));
        assert_eq!(segments.len(), 9, "three faces of a box show nine edges");

        let distance_to_drawing = |p: DVec2| {
            segments
                .iter()
                .map(|s| {
                    let d = s.b - s.a;
                    let t = ((p - s.a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
                    p.distance(s.a + d * t)
                })
                .fold(f64::INFINITY, f64::min)
        };
        for e in map.edgels() {
            let d = distance_to_drawing(e.position.as_dvec2());
            assert!(d < 1.0, "edge pixel {e:?} is {d} px from every drawn edge");
        }
        // Along every drawn edge, away from its ends, an edge pixel within a pixel whose
        // normal is across the edge (within 30°, the angle the alignment allows): at all
        // but a few points. The picture is not anti-aliased, so the staircase of a shallow
        // edge tilts some normals, and where two edges meet at a sharp angle their Sobel
        // windows overlap.
        let (mut points, mut found) = (0, 0);
        let mut tilts = Vec::new();
        for s in &segments {
            let length = s.a.distance(s.b);
            let along = (s.b - s.a) / length;
            let mut x = 3.0;
            while x < length - 3.0 {
                let p = s.a + along * x;
                let e = map.nearest(p.x, p.y).unwrap();
                let sin_tilt = e.normal.as_dvec2().dot(along).abs();
                points += 1;
                if p.distance(e.position.as_dvec2()) < 1.0 && sin_tilt < 0.5 {
                    found += 1;
                    tilts.push(sin_tilt);
                }
                x += 1.0;
            }
        }
        assert!(points > 300, "{points} points");
        assert!(
            found as f64 >= 0.97 * points as f64,
            "edge pixels found at {found} of {points} points along the drawn edges"
        );
        tilts.sort_by(f64::total_cmp);
        let median = tilts[tilts.len() / 2];
        assert!(median < 10f64.to_radians().sin(), "median tilt {median}");
    }

    #[test]
    fn out_of_range_options_are_refused() {
        let image = rectangle(8, 8, (2, 2, 6, 6), 200);
        let bad = EdgeOptions {
            noise_factor: f64::NAN,
            ..EdgeOptions::default()
        };
        assert!(matches!(
            EdgeMap::detect(&image, &bad),
            Err(ImageError::BadParameter { .. })
        ));
    }
}
