//! Grey-level pictures: from decoded samples, and halved for a pyramid.

use super::ImageError;

/// An 8-bit grey-level picture, row-major from the top-left pixel, in the camera's pixel
/// convention (pixel `(x, y)` covers `[x, x+1) × [y, y+1)`, its centre is
/// `(x + ½, y + ½)`; see [`crate::model::camera`]).
///
/// Invariant: `width ≥ 1`, `height ≥ 1`, `pixels.len() == width × height`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Luma {
    width: u32,
    height: u32,
    pixels: Vec<u8>,
}

impl Luma {
    /// The picture of `samples`, `channels` bytes per pixel, rows top to bottom without
    /// padding, as a PNG decoder gives them: 1 grey, 2 grey and alpha, 3 RGB, 4 RGBA.
    /// Colour becomes luma with Rec. 601 weights, `Y = 0.299·R + 0.587·G + 0.114·B`
    /// (rounded); alpha is ignored (the picture is what the camera saw).
    ///
    /// Refused with [`ImageError::BadParameter`] for a zero width or height,
    /// [`ImageError::Channels`] for another channel count, and
    /// [`ImageError::Samples`] unless `samples.len() == width × height × channels`.
    pub fn from_samples(
        width: u32,
        height: u32,
        channels: u8,
        samples: &[u8],
    ) -> Result<Luma, ImageError> {
        if width == 0 || height == 0 {
            return Err(ImageError::BadParameter {
                what: if width == 0 {
                    "the image width"
                } else {
                    "the image height"
                },
                value: 0.0,
            });
        }
        if !(1..=4).contains(&channels) {
            return Err(ImageError::Channels { channels });
        }
        let expected = (width as usize)
            .checked_mul(height as usize)
            .and_then(|n| n.checked_mul(channels as usize));
        if expected != Some(samples.len()) {
            return Err(ImageError::Samples {
                expected: expected.unwrap_or(usize::MAX),
                got: samples.len(),
            });
        }
        let c = channels as usize;
        let pixels = match channels {
            1 => samples.to_vec(),
            2 => samples.chunks_exact(c).map(|p| p[0]).collect(),
            _ => samples
                .chunks_exact(c)
                .map(|p| rec601(p[0], p[1], p[2]))
                .collect(),
        };
        Ok(Luma {
            width,
            height,
            pixels,
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

    /// The grey levels, row-major, `width × height` of them.
    pub fn pixels(&self) -> &[u8] {
        &self.pixels
    }

    /// The grey level at column `x`, row `y`, or `None` outside the picture.
    pub fn get(&self, x: u32, y: u32) -> Option<u8> {
        (x < self.width && y < self.height)
            .then(|| self.pixels[y as usize * self.width as usize + x as usize])
    }

    /// The picture at half the resolution: each pixel the rounded mean of a 2 × 2 block, a
    /// last odd column or row dropped. Pixel `(x, y)` of the result covers pixels
    /// `2x..2x+2 × 2y..2y+2` of this one, so a point at `(u, v)` here is at `(u/2, v/2)`
    /// there (the pixel convention puts coordinates on pixel corners). `None` when a side
    /// would become zero.
    pub fn half(&self) -> Option<Luma> {
        let (w, h) = (self.width / 2, self.height / 2);
        if w == 0 || h == 0 {
            return None;
        }
        let src = self.width as usize;
        let mut pixels = Vec::with_capacity(w as usize * h as usize);
        for y in 0..h as usize {
            let top = &self.pixels[2 * y * src..][..2 * w as usize];
            let bottom = &self.pixels[(2 * y + 1) * src..][..2 * w as usize];
            for (t, b) in top.chunks_exact(2).zip(bottom.chunks_exact(2)) {
                let sum = t[0] as u16 + t[1] as u16 + b[0] as u16 + b[1] as u16;
                pixels.push(((sum + 2) / 4) as u8);
            }
        }
        Some(Luma {
            width: w,
            height: h,
            pixels,
        })
    }
}

/// Rec. 601 luma of an sRGB-encoded colour, rounded (weights scaled by 2¹⁶).
fn rec601(r: u8, g: u8, b: u8) -> u8 {
    let y = 19_595 * r as u32 + 38_470 * g as u32 + 7_471 * b as u32;
    ((y + 32_768) >> 16) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_channel_layout_becomes_luma() {
        let grey = Luma::from_samples(2, 1, 1, &[10, 200]).unwrap();
        assert_eq!(grey.pixels(), &[10, 200]);
        let grey_alpha = Luma::from_samples(2, 1, 2, &[10, 0, 200, 255]).unwrap();
        assert_eq!(grey_alpha.pixels(), &[10, 200]);
        let rgb = Luma::from_samples(3, 1, 3, &[255, 0, 0, 0, 255, 0, 0, 0, 255]).unwrap();
        assert_eq!(rgb.pixels(), &[76, 150, 29]);
        let rgba = Luma::from_samples(1, 1, 4, &[255, 255, 255, 0]).unwrap();
        assert_eq!(rgba.pixels(), &[255]);
        assert_eq!(rgba.get(0, 0), Some(255));
        assert_eq!(rgba.get(1, 0), None);
    }

    #[test]
    fn malformed_samples_are_refused() {
        assert_eq!(
            Luma::from_samples(2, 2, 3, &[0; 11]),
            Err(ImageError::Samples {
                expected: 12,
                got: 11
            })
        );
        assert_eq!(
            Luma::from_samples(1, 1, 5, &[0; 5]),
            Err(ImageError::Channels { channels: 5 })
        );
        assert!(matches!(
            Luma::from_samples(0, 1, 1, &[]),
            Err(ImageError::BadParameter { .. })
        ));
    }

    #[test]
    fn halving_averages_blocks_and_drops_odd_sides() {
        #[rustfmt::skip]
        let p = Luma::from_samples(3, 3, 1, &[
            0, 4, 9,
            8, 4, 9,
            9, 9, 9,
        ]).unwrap();
        let h = p.half().unwrap();
        assert_eq!((h.width(), h.height()), (1, 1));
        assert_eq!(h.pixels(), &[4]);
        assert_eq!(h.half(), None);
    }
}
