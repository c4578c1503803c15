//! The exact Euclidean distance transform of a set of pixels, with the nearest of them.
//!
//! # Method
//!
//! Felzenszwalb and Huttenlocher, "Distance Transforms of Sampled Functions" (Theory of
//! Computing 8, 2012): the squared Euclidean distance is separable,
//! `d²(x, y) = min_q [(x − q)² + min_r (y − r)²]` over sites `(q, r)`, so it is computed
//! in two passes, each linear in the number of pixels:
//!
//! 1. **Columns.** For every pixel, the nearest site in its own column (two sweeps, down
//!    and up, row by row so that memory is read in order).
//! 2. **Rows.** In each row, the lower envelope of the parabolas
//!    `x ↦ (x − q)² + g(q)²` (with `g(q)` the vertical distance found by pass 1 in column
//!    q) is built left to right and read off at every x. Rows are independent and run in
//!    parallel.
//!
//! Besides the distance, the transform keeps the site that achieves it (its "feature
//! transform"), which is what finding an edge from a point needs. Where two sites are
//! equally near, either may be kept. All distances are between pixel centres, so they
//! are square roots of integers; the envelope's breakpoints are computed in `f64`, whose
//! 53-bit mantissa holds the integer numerators exactly for any image this crate accepts.

use rayon::prelude::*;

use super::ImageError;

/// The value of [`DistanceField::nearest_index`] where there is no site at all.
pub const NO_SITE: u32 = u32::MAX;

/// For every pixel of a `width × height` grid, the nearest *site* pixel (Euclidean
/// distance between pixel centres) and so the distance to it. See the
/// [image module's documentation](crate::vision::image).
///
/// Invariant: `nearest.len() == width × height`, and every entry is [`NO_SITE`] (only
/// when there are no sites) or the row-major index of a site nearest to that pixel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DistanceField {
    width: u32,
    height: u32,
    nearest: Vec<u32>,
}

impl DistanceField {
    /// The distance transform of the pixels `i` (row-major) with `is_site[i]`.
    ///
    /// Refused with [`ImageError::Samples`] unless
    /// `is_site.len() == width × height`, and with [`ImageError::BadParameter`] when the
    /// grid has more pixels than a `u32` index can number.
    pub fn from_sites(
        width: u32,
        height: u32,
        is_site: &[bool],
    ) -> Result<DistanceField, ImageError> {
        let (w, h) = (width as usize, height as usize);
        let n = w.checked_mul(h);
        if n != Some(is_site.len()) {
            return Err(ImageError::Samples {
                expected: n.unwrap_or(usize::MAX),
                got: is_site.len(),
            });
        }
        if is_site.len() >= NO_SITE as usize {
            return Err(ImageError::BadParameter {
                what: "the number of pixels",
                value: is_site.len() as f64,
            });
        }
        let column_rows = nearest_in_columns(w, h, is_site);
        let mut nearest = vec![NO_SITE; w * h];
        if w > 0 {
            nearest
                .par_chunks_mut(w)
                .zip(column_rows.par_chunks(w))
                .enumerate()
                .with_min_len(8)
                .for_each_init(
                    || Envelope::with_capacity(w),
                    |envelope, (y, (out, rows))| envelope.row(y, rows, out),
                );
        }
        Ok(DistanceField {
            width,
            height,
            nearest,
        })
    }

    /// Width of the grid, pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height of the grid, pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The row-major index of a site nearest to pixel `(x, y)`; [`NO_SITE`] when there are
    /// no sites or `(x, y)` is outside the grid.
    #[inline]
    pub fn nearest_index(&self, x: u32, y: u32) -> u32 {
        if x < self.width && y < self.height {
            self.nearest[y as usize * self.width as usize + x as usize]
        } else {
            NO_SITE
        }
    }

    /// A site nearest to pixel `(x, y)` as `(column, row)`, or `None` when there are no
    /// sites or `(x, y)` is outside the grid.
    pub fn nearest(&self, x: u32, y: u32) -> Option<(u32, u32)> {
        let i = self.nearest_index(x, y);
        (i != NO_SITE).then(|| (i % self.width, i / self.width))
    }

    /// The squared distance from pixel `(x, y)` to its nearest site, or `None` as for
    /// [`DistanceField::nearest`].
    pub fn squared_distance(&self, x: u32, y: u32) -> Option<u64> {
        self.nearest(x, y).map(|(q, r)| {
            let (dx, dy) = (x.abs_diff(q) as u64, y.abs_diff(r) as u64);
            dx * dx + dy * dy
        })
    }
}

/// For every pixel, the row of the nearest site in its column (`NO_SITE` when the column
/// has none).
fn nearest_in_columns(w: usize, h: usize, is_site: &[bool]) -> Vec<u32> {
    // Downward sweep: the last site at or above each pixel.
    let mut rows = vec![NO_SITE; w * h];
    let mut last = vec![NO_SITE; w];
    for y in 0..h {
        let line = &is_site[y * w..][..w];
        let out = &mut rows[y * w..][..w];
        for x in 0..w {
            if line[x] {
                last[x] = y as u32;
            }
            out[x] = last[x];
        }
    }
    // Upward sweep: the first site at or below, kept where it is nearer.
    last.fill(NO_SITE);
    for y in (0..h).rev() {
        let line = &is_site[y * w..][..w];
        let out = &mut rows[y * w..][..w];
        let row = y as u32;
        for x in 0..w {
            if line[x] {
                last[x] = row;
            }
            let below = last[x];
            if below != NO_SITE && (out[x] == NO_SITE || below - row < row - out[x]) {
                out[x] = below;
            }
        }
    }
    rows
}

/// The lower envelope of one row's parabolas (pass 2), with its scratch space.
struct Envelope {
    /// Columns of the parabolas in the envelope, left to right.
    columns: Vec<u32>,
    /// `bounds[k]..bounds[k+1]` is where parabola k is lowest.
    bounds: Vec<f64>,
}

impl Envelope {
    fn with_capacity(w: usize) -> Envelope {
        Envelope {
            columns: Vec::with_capacity(w),
            bounds: Vec::with_capacity(w + 1),
        }
    }

    /// Fills `out` (one row) with the nearest site of every pixel of row `y`, given the
    /// nearest row in each column (`rows`).
    fn row(&mut self, y: usize, rows: &[u32], out: &mut [u32]) {
        let w = rows.len();
        self.columns.clear();
        self.bounds.clear();
        // f(q) + q², the parabola of column q written as q² − 2qx + (f(q) + q²) + x².
        let height = |q: usize| -> f64 {
            let g = rows[q].abs_diff(y as u32) as f64;
            g * g + (q * q) as f64
        };
        for (q, &row) in rows.iter().enumerate() {
            if row == NO_SITE {
                continue;
            }
            let hq = height(q);
            loop {
                let (Some(&v), Some(&bound)) = (self.columns.last(), self.bounds.last()) else {
                    self.columns.push(q as u32);
                    self.bounds.push(f64::NEG_INFINITY);
                    break;
                };
                let v = v as usize;
                // The parabolas of v and q cross at s = (hq − hv)/(2(q − v)); q > v, so
                // s ≤ bound compares without dividing.
                let (rise, run) = (hq - height(v), 2.0 * (q - v) as f64);
                if rise <= bound * run {
                    self.columns.pop();
                    self.bounds.pop();
                } else {
                    self.columns.push(q as u32);
                    self.bounds.push(rise / run);
                    break;
                }
            }
        }
        if self.columns.is_empty() {
            out.fill(NO_SITE);
            return;
        }
        let mut k = 0;
        for (x, o) in out.iter_mut().enumerate() {
            while k + 1 < self.columns.len() && self.bounds[k + 1] < x as f64 {
                k += 1;
            }
            let q = self.columns[k] as usize;
            *o = rows[q] * w as u32 + q as u32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::testing::Rng;

    /// The squared distance to the nearest site by trying every site.
    fn brute_force(w: u32, h: u32, sites: &[bool], x: u32, y: u32) -> Option<u64> {
        (0..h)
            .flat_map(|r| (0..w).map(move |q| (q, r)))
            .filter(|&(q, r)| sites[(r * w + q) as usize])
            .map(|(q, r)| {
                let (dx, dy) = (x.abs_diff(q) as u64, y.abs_diff(r) as u64);
                dx * dx + dy * dy
            })
            .min()
    }

    #[test]
    fn distances_are_exact_against_brute_force_on_random_maps() {
        let mut rng = Rng(7);
        for trial in 0..60 {
            let w = 1 + (rng.next_u64() % 40) as u32;
            let h = 1 + (rng.next_u64() % 30) as u32;
            // From empty to dense: the density spans three orders of magnitude.
            let density = [0.0, 0.002, 0.02, 0.1, 0.5, 0.95][trial % 6];
            let sites: Vec<bool> = (0..w * h).map(|_| rng.range(0.0, 1.0) < density).collect();
            let field = DistanceField::from_sites(w, h, &sites).unwrap();
            for y in 0..h {
                for x in 0..w {
                    let want = brute_force(w, h, &sites, x, y);
                    assert_eq!(
                        field.squared_distance(x, y),
                        want,
                        "{w}×{h} at ({x}, {y}), density {density}"
                    );
                    if let Some((q, r)) = field.nearest(x, y) {
                        assert!(sites[(r * w + q) as usize], "the nearest pixel is a site");
                    }
                }
            }
        }
    }

    #[test]
    fn one_site_gives_the_euclidean_distance_everywhere() {
        let (w, h) = (9u32, 7u32);
        let mut sites = vec![false; 63];
        sites[(5 * w + 2) as usize] = true;
        let field = DistanceField::from_sites(w, h, &sites).unwrap();
        assert_eq!(field.squared_distance(8, 0), Some(36 + 25));
        assert_eq!(field.nearest(0, 6), Some((2, 5)));
        assert_eq!(field.nearest(9, 0), None, "outside the grid");
        assert_eq!(field.nearest_index(9, 0), NO_SITE);
    }

    #[test]
    fn a_grid_without_sites_has_no_nearest_site_and_a_wrong_length_is_refused() {
        let field = DistanceField::from_sites(4, 3, &[false; 12]).unwrap();
        assert_eq!(field.squared_distance(1, 1), None);
        assert_eq!(
            DistanceField::from_sites(4, 3, &[false; 11]),
            Err(ImageError::Samples {
                expected: 12,
                got: 11
            })
        );
    }
}
