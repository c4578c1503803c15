//! Raster images the renderer fills and their PNG encoding.
//!
//! Two kinds: [`RgbImage`] (8-bit sRGB, for `shaded`, `wire` and `hidden`) and
//! [`Gray16`] (16-bit, for `depth` and `ids`). Rows run top to bottom, pixels left to
//! right, as in the camera's pixel convention. PNG encoding uses the `png` crate's fast
//! setting (its tuned DEFLATE, one fixed filter), which trades some size for speed.

use png::{BitDepth, ColorType, Compression, Encoder};

/// An 8-bit RGB image, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RgbImage {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// `width × height × 3` bytes, R, G, B.
    pub data: Vec<u8>,
}

impl RgbImage {
    /// An image filled with `color`.
    pub fn filled(width: u32, height: u32, color: [u8; 3]) -> RgbImage {
        let n = width as usize * height as usize;
        let mut data = Vec::with_capacity(n * 3);
        for _ in 0..n {
            data.extend_from_slice(&color);
        }
        RgbImage {
            width,
            height,
            data,
        }
    }

    /// The pixel at column `x`, row `y`. Precondition: inside the image.
    pub fn get(&self, x: u32, y: u32) -> [u8; 3] {
        let i = (y as usize * self.width as usize + x as usize) * 3;
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    /// Sets the pixel at column `x`, row `y`. Precondition: inside the image.
    pub fn set(&mut self, x: u32, y: u32, c: [u8; 3]) {
        let i = (y as usize * self.width as usize + x as usize) * 3;
        self.data[i..i + 3].copy_from_slice(&c);
    }

    /// Mixes `c` into the pixel at (`x`, `y`) with coverage `alpha` in [0, 1]; pixels
    /// outside the image are ignored.
    pub fn blend(&mut self, x: i64, y: i64, c: [u8; 3], alpha: f64) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return;
        }
        let a = alpha.clamp(0.0, 1.0);
        let i = (y as usize * self.width as usize + x as usize) * 3;
        for (d, &c) in self.data[i..i + 3].iter_mut().zip(&c) {
            let old = *d as f64;
            *d = round_byte(old + (c as f64 - old) * a);
        }
    }

    /// The PNG file of this image (8-bit RGB).
    /// Gives the pixel buffer back for later pictures (see the renderer's buffer pool):
    /// a caller done with an image may call this instead of dropping it.
    pub fn recycle(self) {
        super::buffers::give(self.data);
    }

    pub fn to_png(&self) -> Vec<u8> {
        encode(
            self.width,
            self.height,
            ColorType::Rgb,
            BitDepth::Eight,
            &self.data,
        )
    }
}

/// `v` (between 0 and 255) rounded half away from zero, as `f64::round` does, but without
/// a libm call (the baseline x86-64 target has no rounding instruction); NaN gives 0.
#[inline]
fn round_byte(v: f64) -> u8 {
    let t = v as u8;
    if v - t as f64 >= 0.5 { t + 1 } else { t }
}

/// A 16-bit single-channel image, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Gray16 {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// `width × height` values.
    pub data: Vec<u16>,
}

impl Gray16 {
    /// An image of zeros.
    pub fn zeros(width: u32, height: u32) -> Gray16 {
        Gray16 {
            width,
            height,
            data: vec![0; width as usize * height as usize],
        }
    }

    /// The value at column `x`, row `y`. Precondition: inside the image.
    pub fn get(&self, x: u32, y: u32) -> u16 {
        self.data[y as usize * self.width as usize + x as usize]
    }

    /// The PNG file of this image (16-bit grayscale, big-endian samples as PNG requires).
    pub fn to_png(&self) -> Vec<u8> {
        let bytes: Vec<u8> = self.data.iter().flat_map(|v| v.to_be_bytes()).collect();
        encode(
            self.width,
            self.height,
            ColorType::Grayscale,
            BitDepth::Sixteen,
            &bytes,
        )
    }
}

/// Encodes raw samples as a PNG file with the fast compression setting.
fn encode(width: u32, height: u32, color: ColorType, depth: BitDepth, data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len() / 8 + 1024);
    let mut encoder = Encoder::new(&mut out, width, height);
    encoder.set_color(color);
    encoder.set_depth(depth);
    encoder.set_compression(Compression::Fast);
    // Writing to memory a header and data whose sizes match cannot fail.
    let mut writer = encoder
        .write_header()
        .expect("a PNG header for a valid size");
    writer
        .write_image_data(data)
        .expect("image data of the declared size");
    writer.finish().expect("finishing a PNG in memory");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pngs_decode_back_to_the_same_pixels() {
        let mut img = RgbImage::filled(5, 3, [10, 20, 30]);
        img.set(4, 2, [255, 0, 7]);
        let png = img.to_png();
        let decoded = crate::server::limits::decode_png(&png, &Default::default()).unwrap();
        assert_eq!((decoded.width, decoded.height), (5, 3));

        let mut g = Gray16::zeros(4, 2);
        g.data[7] = 65535;
        g.data[1] = 258;
        let png = g.to_png();
        let mut reader = png::Decoder::new(std::io::Cursor::new(png))
            .read_info()
            .unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        reader.next_frame(&mut buf).unwrap();
        assert_eq!(&buf[2..4], &[1, 2]);
        assert_eq!(&buf[14..16], &[255, 255]);
    }

    #[test]
    fn bytes_round_as_f64_round_does() {
        for i in 0..=2550 {
            let v = i as f64 / 10.0;
            assert_eq!(round_byte(v), v.round() as u8, "{v}");
        }
        assert_eq!(round_byte(0.499_999_999_999_999_94), 0);
        assert_eq!(round_byte(f64::NAN), 0);
    }
}
