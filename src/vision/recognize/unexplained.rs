//! The parts of a picture that nothing modeled explains, as a mask: closed outlines of
//! edges that no predicted edge accounts for, filled, and (with depth) surfaces nearer
//! than the model predicts.

/// A pixel grid of flags, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct Flags {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// `width × height` flags, row-major.
    pub bits: Vec<bool>,
}

impl Flags {
    /// All false.
    pub fn new(width: usize, height: usize) -> Flags {
        Flags {
            width,
            height,
            bits: vec![false; width * height],
        }
    }

    /// Every flag set within the square of half-side `r` around a set flag (dilation).
    pub fn grown(&self, r: usize) -> Flags {
        self.morphed(r, true)
    }

    /// Only flags whose whole square of half-side `r` is set (erosion; the picture's
    /// border counts as set, so that regions cut by it are not eaten from there).
    pub fn shrunk(&self, r: usize) -> Flags {
        self.morphed(r, false)
    }

    /// Dilation (`any`) or erosion, separably: rows, then columns.
    fn morphed(&self, r: usize, any: bool) -> Flags {
        let (w, h) = (self.width, self.height);
        let pass = |get: &dyn Fn(usize, usize) -> bool, out: &mut Vec<bool>, along_rows: bool| {
            for y in 0..h {
                for x in 0..w {
                    let (lo, hi) = if along_rows {
                        (x.saturating_sub(r), (x + r).min(w - 1))
                    } else {
                        (y.saturating_sub(r), (y + r).min(h - 1))
                    };
                    let mut hit = !any;
                    for t in lo..=hi {
                        let v = if along_rows { get(t, y) } else { get(x, t) };
                        if any && v {
                            hit = true;
                            break;
                        }
                        if !any && !v {
                            hit = false;
                            break;
                        }
                    }
                    out[y * w + x] = hit;
                }
            }
        };
        let mut rows = vec![false; w * h];
        pass(&|x, y| self.bits[y * w + x], &mut rows, true);
        let mut both = vec![false; w * h];
        pass(&|x, y| rows[y * w + x], &mut both, false);
        Flags {
            width: w,
            height: h,
            bits: both,
        }
    }

    /// The flags with every hole filled: unset pixels that no path of unset pixels
    /// (4-connected) joins to the picture's border become set.
    pub fn filled(&self) -> Flags {
        let (w, h) = (self.width, self.height);
        let mut outside = vec![false; w * h];
        let mut stack: Vec<usize> = Vec::new();
        let push = |i: usize, outside: &mut Vec<bool>, stack: &mut Vec<usize>| {
            if !self.bits[i] && !outside[i] {
                outside[i] = true;
                stack.push(i);
            }
        };
        for x in 0..w {
            push(x, &mut outside, &mut stack);
            push((h - 1) * w + x, &mut outside, &mut stack);
        }
        for y in 0..h {
            push(y * w, &mut outside, &mut stack);
            push(y * w + w - 1, &mut outside, &mut stack);
        }
        while let Some(i) = stack.pop() {
            let (x, y) = (i % w, i / w);
            if x > 0 {
                push(i - 1, &mut outside, &mut stack);
            }
            if x + 1 < w {
                push(i + 1, &mut outside, &mut stack);
            }
            if y > 0 {
                push(i - w, &mut outside, &mut stack);
            }
            if y + 1 < h {
                push(i + w, &mut outside, &mut stack);
            }
        }
        Flags {
            width: w,
            height: h,
            bits: outside.iter().map(|&o| !o).collect(),
        }
    }

    /// Each flag set in `self` or `other` (same size).
    pub fn union(&self, other: &Flags) -> Flags {
        Flags {
            width: self.width,
            height: self.height,
            bits: self
                .bits
                .iter()
                .zip(&other.bits)
                .map(|(&a, &b)| a || b)
                .collect(),
        }
    }

    /// The flags without the 4-connected components of set flags that have fewer than
    /// `min_pixels` pixels.
    pub fn without_specks(&self, min_pixels: usize) -> Flags {
        let (w, h) = (self.width, self.height);
        let mut kept = self.bits.clone();
        let mut seen = vec![false; w * h];
        let mut component = Vec::new();
        let mut stack = Vec::new();
        for start in 0..w * h {
            if !self.bits[start] || seen[start] {
                continue;
            }
            component.clear();
            seen[start] = true;
            stack.push(start);
            while let Some(i) = stack.pop() {
                component.push(i);
                let (x, y) = (i % w, i / w);
                let neighbours = [
                    (x > 0).then(|| i - 1),
                    (x + 1 < w).then(|| i + 1),
                    (y > 0).then(|| i - w),
                    (y + 1 < h).then(|| i + w),
                ];
                for j in neighbours.into_iter().flatten() {
                    if self.bits[j] && !seen[j] {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
            if component.len() < min_pixels {
                for &i in &component {
                    kept[i] = false;
                }
            }
        }
        Flags {
            width: w,
            height: h,
            bits: kept,
        }
    }

    /// The number of set flags.
    pub fn count(&self) -> usize {
        self.bits.iter().filter(|&&b| b).count()
    }
}

/// A class of pixels that no class holds (they are not judged).
pub const NO_CLASS: u32 = u32::MAX;

/// Pixels whose grey level departs from the rest of their class: each pixel `i` of class
/// `classes[i]` (pixels that the model predicts show one surface, lit one way, are one
/// class) is compared with its class's median, and set when it lies farther from it than
/// `spread` times the class's robust deviation (1.4826 × the median absolute deviation)
/// and at least `least` grey levels. A planar face under distant light shows one grey
/// level up to noise, whatever renderer or camera drew it, so what departs from it is
/// something else in front of it.
///
/// Precondition: `grey.len() == classes.len() == width × height`.
pub fn deviant(
    grey: &[u8],
    classes: &[u32],
    width: usize,
    height: usize,
    spread: f64,
    least: f64,
) -> Flags {
    let count = classes
        .iter()
        .filter(|&&c| c != NO_CLASS)
        .max()
        .map_or(0, |&c| c as usize + 1);
    let mut histograms = vec![[0u32; 256]; count];
    for (&g, &c) in grey.iter().zip(classes) {
        if c != NO_CLASS {
            histograms[c as usize][g as usize] += 1;
        }
    }
    let limits: Vec<(f64, f64)> = histograms
        .iter()
        .map(|h| {
            let median = quantile(h, 0.5);
            let mut spread_histogram = [0u32; 256];
            for (g, &n) in h.iter().enumerate() {
                spread_histogram[(g as f64 - median).abs().min(255.0) as usize] += n;
            }
            let deviation = 1.4826 * quantile(&spread_histogram, 0.5);
            (median, (spread * deviation).max(least))
        })
        .collect();
    let mut flags = Flags::new(width, height);
    for (i, (&g, &c)) in grey.iter().zip(classes).enumerate() {
        if c != NO_CLASS {
            let (median, limit) = limits[c as usize];
            flags.bits[i] = (g as f64 - median).abs() > limit;
        }
    }
    flags
}

/// The `q`-quantile of the grey levels counted in `histogram` (0 for none).
fn quantile(histogram: &[u32; 256], q: f64) -> f64 {
    let total: u64 = histogram.iter().map(|&n| n as u64).sum();
    let target = (q * total as f64).ceil().max(1.0) as u64;
    let mut seen = 0u64;
    for (g, &n) in histogram.iter().enumerate() {
        seen += n as u64;
        if seen >= target {
            return g as f64;
        }
    }
    0.0
}

/// Regions enclosed by unexplained edge pixels: the edge pixels grown by `close_px`
/// (bridging gaps that small), holes filled, then shrunk back by `close_px`.
pub fn enclosed(edges: &Flags, close_px: usize) -> Flags {
    edges.grown(close_px).filled().shrunk(close_px)
}

/// Opening: what survives shrinking by `r` then growing by `r` (specks and lines
/// thinner than `2r + 1` go).
pub fn opened(flags: &Flags, r: usize) -> Flags {
    flags.shrunk(r).grown(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square_outline(w: usize, h: usize, x0: usize, y0: usize, side: usize) -> Flags {
        let mut f = Flags::new(w, h);
        for t in 0..side {
            for (x, y) in [
                (x0 + t, y0),
                (x0 + t, y0 + side - 1),
                (x0, y0 + t),
                (x0 + side - 1, y0 + t),
            ] {
                f.bits[y * w + x] = true;
            }
        }
        f
    }

    #[test]
    fn a_closed_outline_encloses_its_inside_and_an_open_one_nothing_more() {
        let outline = square_outline(40, 30, 10, 5, 12);
        let region = enclosed(&outline, 1);
        assert_eq!(region.count(), 144);
        // The same outline with a gap of three pixels on one side: bridged by 2.
        let mut open = outline.clone();
        for x in 14..17 {
            open.bits[5 * 40 + x] = false;
        }
        assert_eq!(enclosed(&open, 2).count(), 144);
        // Not by 1: only the outline's own pixels stay.
        assert!(enclosed(&open, 1).count() < 60);
    }

    #[test]
    fn pixels_unlike_their_class_are_deviant() {
        // Two classes, grey 100 ± 3 and 180 ± 3; a block of 60 in the first.
        let (w, h) = (20usize, 10usize);
        let mut grey = Vec::new();
        let mut classes = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let jitter = ((x * 7 + y * 3) % 7) as u8;
                let first = x < 10;
                let block = first && (2..5).contains(&x) && (3..6).contains(&y);
                grey.push(if block {
                    60
                } else if first {
                    97 + jitter
                } else {
                    177 + jitter
                });
                classes.push(if x == 19 { NO_CLASS } else { u32::from(!first) });
            }
        }
        let flags = deviant(&grey, &classes, w, h, 4.0, 12.0);
        assert_eq!(flags.count(), 9);
        for y in 3..6 {
            for x in 2..5 {
                assert!(flags.bits[y * w + x]);
            }
        }
    }

    #[test]
    fn opening_removes_specks_and_keeps_blocks() {
        let mut f = Flags::new(20, 20);
        f.bits[3 * 20 + 3] = true;
        for y in 8..16 {
            for x in 8..16 {
                f.bits[y * 20 + x] = true;
            }
        }
        let o = opened(&f, 1);
        assert_eq!(o.count(), 64);
        assert!(!o.bits[3 * 20 + 3]);
    }
}
