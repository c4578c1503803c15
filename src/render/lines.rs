//! Anti-aliased line drawing (Xiaolin Wu's algorithm) for the `wire` and `hidden` modes.
//!
//! Lines are given in continuous pixel coordinates (the camera's convention: (0, 0) is
//! the top-left corner of the top-left pixel, whose centre is (0.5, 0.5)). Along the
//! line's major axis each pixel column (or row) is visited once; the line's intercept
//! with that column's centre splits a coverage of one pixel between the two nearest
//! pixels, and the end columns are weighted by how much of them the line spans.

use glam::DVec2;

use super::image::RgbImage;

/// Draws the segment `a`–`b` in `color`, anti-aliased, about one pixel wide. Parts
/// outside the image are skipped; a segment of zero length draws nothing. Non-finite
/// ends draw nothing.
pub fn draw_line(img: &mut RgbImage, a: DVec2, b: DVec2, color: [u8; 3]) {
    if !(a.is_finite() && b.is_finite()) {
        return;
    }
    let d = b - a;
    let steep = d.y.abs() > d.x.abs();
    // Work in (major, minor) coordinates; swap back when plotting.
    let (mut p, mut q) = if steep {
        (DVec2::new(a.y, a.x), DVec2::new(b.y, b.x))
    } else {
        (a, b)
    };
    if p.x > q.x {
        std::mem::swap(&mut p, &mut q);
    }
    let run = q.x - p.x;
    if run <= 0.0 {
        return;
    }
    let slope = (q.y - p.y) / run;
    let (w, h) = (img.width as f64, img.height as f64);
    let major_limit = if steep { h } else { w };
    // Columns whose centres lie within [p.x, q.x], widened by half a pixel at the ends
    // so that short segments still leave a mark.
    let first = floor(p.x - 0.5).max(0.0);
    let last = (-floor(0.5 - q.x)).min(major_limit - 1.0);
    if first > last {
        return;
    }
    let mut plot = |major: f64, minor: f64, alpha: f64| {
        if alpha <= 0.0 {
            return;
        }
        let (x, y) = if steep {
            (minor, major)
        } else {
            (major, minor)
        };
        img.blend(x as i64, y as i64, color, alpha);
    };
    let mut col = first;
    while col <= last {
        let centre = col + 0.5;
        // How much of this column the segment covers along the major axis.
        let cover = (q.x.min(col + 1.0) - p.x.max(col)).clamp(0.0, 1.0);
        if cover > 0.0 {
            let t = centre.clamp(p.x, q.x);
            let y = p.y + slope * (t - p.x) - 0.5;
            let row = floor(y);
            let frac = y - row;
            plot(col, row, (1.0 - frac) * cover);
            plot(col, row + 1.0, frac * cover);
        }
        col += 1.0;
    }
}

/// ⌊x⌋, as `f64::floor` gives it, without a libm call for |x| < 2⁵² (the baseline x86-64
/// target has no rounding instruction).
#[inline]
fn floor(x: f64) -> f64 {
    if x.abs() < 4_503_599_627_370_496.0 {
        let t = x as i64 as f64;
        if t > x { t - 1.0 } else { t }
    } else {
        x.floor()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ink(img: &RgbImage) -> f64 {
        img.data.iter().step_by(3).map(|&r| r as f64 / 255.0).sum()
    }

    #[test]
    fn a_horizontal_line_on_pixel_centres_fills_one_row() {
        let mut img = RgbImage::filled(10, 5, [0, 0, 0]);
        draw_line(
            &mut img,
            DVec2::new(1.0, 2.5),
            DVec2::new(9.0, 2.5),
            [255, 255, 255],
        );
        for x in 1..9 {
            assert_eq!(img.get(x, 2), [255, 255, 255], "column {x}");
            assert_eq!(img.get(x, 1), [0, 0, 0]);
            assert_eq!(img.get(x, 3), [0, 0, 0]);
        }
        assert_eq!(img.get(0, 2), [0, 0, 0]);
        assert_eq!(img.get(9, 2), [0, 0, 0]);
    }

    #[test]
    fn ink_is_proportional_to_length_at_any_angle() {
        for angle in [0.1f64, 0.5, 0.9, 1.3, 2.0, 2.8] {
            let mut img = RgbImage::filled(64, 64, [0, 0, 0]);
            let c = DVec2::new(32.0, 32.0);
            let r = DVec2::new(angle.cos(), angle.sin()) * 20.0;
            draw_line(&mut img, c - r, c + r, [255, 255, 255]);
            let major = (2.0 * r.x).abs().max((2.0 * r.y).abs());
            assert!(
                (ink(&img) - major).abs() < 2.5,
                "angle {angle}: {}",
                ink(&img)
            );
        }
    }

    #[test]
    fn lines_outside_or_degenerate_draw_nothing() {
        let mut img = RgbImage::filled(8, 8, [0, 0, 0]);
        draw_line(
            &mut img,
            DVec2::new(-5.0, -5.0),
            DVec2::new(-1.0, -3.0),
            [255; 3],
        );
        draw_line(
            &mut img,
            DVec2::new(3.0, 3.0),
            DVec2::new(3.0, 3.0),
            [255; 3],
        );
        draw_line(
            &mut img,
            DVec2::new(f64::NAN, 3.0),
            DVec2::new(3.0, 3.0),
            [255; 3],
        );
        assert_eq!(ink(&img), 0.0);
    }

    #[test]
    fn the_local_floor_is_f64_floor() {
        for x in [
            -3.5,
            -3.0,
            -2.999,
            -0.5,
            -0.0,
            0.0,
            0.49,
            1.0,
            7.25,
            1e15 + 0.5,
            -1e15 - 0.5,
            1e300,
            -1e300,
        ] {
            assert_eq!(floor(x), x.floor(), "{x}");
        }
    }
}
