//! Raster images the renderer fills and their PNG encoding.
//!
//! Two kinds: [`RgbImage`] (8-bit sRGB, for `shaded`, `wire` and `hidden`) and
//! [`Gray16`] (16-bit, for `depth` and `ids`). Rows run top to bottom, pixels left to
//! right, as in the camera's pixel convention.
//!
//! # PNG encoding
//!
//! `to_png` writes a standard, non-interlaced PNG file (signature, IHDR, one IDAT, IEND)
//! that any decoder reads. Every row uses the Up filter (type 2: each byte minus the
//! byte above it; the first row's "above" is zeros, as PNG defines), and the IDAT data
//! is one zlib stream made by the renderer's own DEFLATE encoder, in parallel bands of
//! rows (see the `deflate` module's source): built for speed on rendered pictures, whose
//! large flat areas it turns into long runs of zero bytes.

use png::{BitDepth, ColorType, Encoder};

use super::deflate;

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

    /// Gives the pixel buffer back for later pictures (see the renderer's buffer pool):
    /// a caller done with an image may call this instead of dropping it.
    pub fn recycle(self) {
        super::buffers::give(self.data);
    }

    /// The PNG file of this image (8-bit RGB; Up filter, banded parallel DEFLATE: see the
    /// [module documentation](self)).
    ///
    /// Panics if the width or height is 0 (PNG has no empty images).
    pub fn to_png(&self) -> Vec<u8> {
        self.png(None)
    }

    /// The PNG file [`to_png`](Self::to_png) writes, except that `compress_band` makes the
    /// raw DEFLATE (ending in a sync flush) of each band of Up-filtered rows, the bands cut
    /// and framed as `to_png` does: for measuring other DEFLATE encoders on the same input.
    #[doc(hidden)]
    pub fn to_png_with(&self, compress_band: impl Fn(&[u8]) -> Vec<u8> + Sync) -> Vec<u8> {
        self.png(Some(&compress_band))
    }

    fn png(&self, compress_band: Option<&BandEncoder>) -> Vec<u8> {
        let row = self.width as usize * 3;
        let filter_up = |y: usize, out: &mut [u8]| {
            let cur = &self.data[y * row..(y + 1) * row];
            if y == 0 {
                out.copy_from_slice(cur);
                return;
            }
            let above = &self.data[(y - 1) * row..y * row];
            for ((o, &c), &a) in out.iter_mut().zip(cur).zip(above) {
                *o = c.wrapping_sub(a);
            }
        };
        encode_png(
            self.width,
            self.height,
            ColorType::Rgb,
            BitDepth::Eight,
            row,
            filter_up,
            compress_band,
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

    /// The PNG file of this image (16-bit grayscale, big-endian samples as PNG requires; Up
    /// filter, banded parallel DEFLATE: see the [module documentation](self)).
    ///
    /// Panics if the width or height is 0 (PNG has no empty images).
    pub fn to_png(&self) -> Vec<u8> {
        self.png(None)
    }

    /// The PNG file [`to_png`](Self::to_png) writes, except that `compress_band` makes the
    /// raw DEFLATE (ending in a sync flush) of each band of Up-filtered rows, the bands cut
    /// and framed as `to_png` does: for measuring other DEFLATE encoders on the same input.
    #[doc(hidden)]
    pub fn to_png_with(&self, compress_band: impl Fn(&[u8]) -> Vec<u8> + Sync) -> Vec<u8> {
        self.png(Some(&compress_band))
    }

    fn png(&self, compress_band: Option<&BandEncoder>) -> Vec<u8> {
        let w = self.width as usize;
        let filter_up = |y: usize, out: &mut [u8]| {
            let cur = &self.data[y * w..(y + 1) * w];
            if y == 0 {
                for (o, &c) in out.chunks_exact_mut(2).zip(cur) {
                    o.copy_from_slice(&c.to_be_bytes());
                }
                return;
            }
            // PNG filters work on bytes: high and low bytes are differenced apart.
            let above = &self.data[(y - 1) * w..y * w];
            for ((o, &c), &a) in out.chunks_exact_mut(2).zip(cur).zip(above) {
                let (c, a) = (c.to_be_bytes(), a.to_be_bytes());
                o[0] = c[0].wrapping_sub(a[0]);
                o[1] = c[1].wrapping_sub(a[1]);
            }
        };
        encode_png(
            self.width,
            self.height,
            ColorType::Grayscale,
            BitDepth::Sixteen,
            w * 2,
            filter_up,
            compress_band,
        )
    }
}

/// A DEFLATE encoder standing in for the renderer's own, band by band (see `to_png_with`).
type BandEncoder<'a> = dyn Fn(&[u8]) -> Vec<u8> + Sync + 'a;

/// The PNG file of an image whose `height` rows are `row_bytes` bytes each;
/// `filter_up(y, out)` writes row `y` Up-filtered (without the filter-type byte) into `out`.
/// The bands are compressed by the `deflate` module, or by `compress_band` if given.
fn encode_png(
    width: u32,
    height: u32,
    color: ColorType,
    depth: BitDepth,
    row_bytes: usize,
    filter_up: impl Fn(usize, &mut [u8]) + Sync,
    compress_band: Option<&BandEncoder>,
) -> Vec<u8> {
    let rows = height as usize;
    let band_rows = deflate::band_rows(rows, row_bytes + 1);
    let idat = match compress_band {
        None => deflate::zlib_stream(rows, row_bytes, band_rows, &filter_up),
        Some(compress) => {
            deflate::zlib_stream_with(rows, row_bytes, band_rows, &filter_up, &compress)
        }
    };
    let mut out = Vec::with_capacity(idat.len() + 64);
    let mut encoder = Encoder::new(&mut out, width, height);
    encoder.set_color(color);
    encoder.set_depth(depth);
    // Writing to memory a valid header and one chunk under 2 GiB cannot fail.
    let mut writer = encoder
        .write_header()
        .expect("a PNG header for a valid size");
    writer
        .write_chunk(png::chunk::IDAT, &idat)
        .expect("an IDAT chunk under 2 GiB");
    writer.finish().expect("finishing a PNG in memory");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::deflate::{ZLIB_HEADER, band_rows, zlib_stream};

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

    use crate::render::sample::SplitMix64;

    /// The pixels a PNG decodes to with the `png` crate, as it returns them (big-endian
    /// for 16 bits), and the image's size, colour type and bit depth.
    fn decode(png: &[u8]) -> (Vec<u8>, (u32, u32), png::ColorType, png::BitDepth) {
        let mut reader = png::Decoder::new(std::io::Cursor::new(png))
            .read_info()
            .expect("a PNG header");
        let mut buf = vec![0; reader.output_buffer_size().expect("a buffer size")];
        let info = reader.next_frame(&mut buf).expect("the pixels");
        buf.truncate(info.buffer_size());
        (
            buf,
            (info.width, info.height),
            info.color_type,
            info.bit_depth,
        )
    }

    /// The IDAT data of a PNG, concatenated.
    fn idat(png: &[u8]) -> Vec<u8> {
        let mut data = Vec::new();
        let mut at = 8;
        while at < png.len() {
            let len = u32::from_be_bytes(png[at..at + 4].try_into().unwrap()) as usize;
            if &png[at + 4..at + 8] == b"IDAT" {
                data.extend_from_slice(&png[at + 8..at + 8 + len]);
            }
            at += 12 + len;
        }
        data
    }

    /// Random bytes in which zero runs of every length (up to a few rows) and noise
    /// alternate once Up-filtered: each row copies the one above with random spans
    /// replaced by noise or by a flat value.
    fn mottled(len: usize, row: usize, seed: u64) -> Vec<u8> {
        let mut rng = SplitMix64::new(seed);
        let mut data = vec![0u8; len];
        let mut i = 0;
        while i < len {
            let span = (rng.next_u64() % 700) as usize + 1;
            let end = (i + span).min(len);
            match rng.next_u64() % 4 {
                // the same as the row above: zeros once filtered
                0 | 1 if i >= row => {
                    for k in i..end {
                        data[k] = data[k - row];
                    }
                }
                2 => data[i..end].fill(rng.next_u64() as u8),
                _ => data[i..end]
                    .iter_mut()
                    .for_each(|b| *b = rng.next_u64() as u8),
            }
            i = end;
        }
        data
    }

    /// The filtered bytes the IDAT stream must inflate to: each row the filter type 2
    /// (Up) and the row minus the one above.
    fn up_filtered(raw: &[u8], row: usize) -> Vec<u8> {
        let mut out = Vec::new();
        for y in 0..raw.len().checked_div(row).unwrap_or(0) {
            out.push(2);
            for x in 0..row {
                let above = if y == 0 { 0 } else { raw[(y - 1) * row + x] };
                out.push(raw[y * row + x].wrapping_sub(above));
            }
        }
        out
    }

    fn rgb(width: u32, height: u32, seed: u64) -> RgbImage {
        let data = mottled(
            width as usize * height as usize * 3,
            width as usize * 3,
            seed,
        );
        RgbImage {
            width,
            height,
            data,
        }
    }

    fn gray16(width: u32, height: u32, seed: u64) -> Gray16 {
        let bytes = mottled(
            width as usize * height as usize * 2,
            width as usize * 2,
            seed,
        );
        let data = bytes
            .chunks_exact(2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]))
            .collect();
        Gray16 {
            width,
            height,
            data,
        }
    }

    fn be_bytes(g: &Gray16) -> Vec<u8> {
        g.data.iter().flat_map(|v| v.to_be_bytes()).collect()
    }

    #[test]
    fn rgb_pngs_decode_to_the_same_pixels() {
        // 1 × 1; odd sizes; wide; one tall enough for many bands on any machine.
        for (k, &(w, h)) in [(1, 1), (333, 77), (2, 3), (1200, 9), (200, 5000)]
            .iter()
            .enumerate()
        {
            for seed in [k as u64, 100 + k as u64] {
                let img = rgb(w, h, seed);
                let png = img.to_png();
                let (pixels, size, color, depth) = decode(&png);
                assert_eq!(
                    (size, color, depth),
                    ((w, h), png::ColorType::Rgb, png::BitDepth::Eight)
                );
                assert!(pixels == img.data, "{w}×{h}, seed {seed}: pixels differ");
            }
        }
        let flat = RgbImage::filled(640, 480, [40, 44, 52]);
        assert_eq!(decode(&flat.to_png()).0, flat.data);
    }

    #[test]
    fn gray16_pngs_decode_to_the_same_samples() {
        for (k, &(w, h)) in [(1, 1), (333, 77), (3, 2), (1200, 9), (300, 4000)]
            .iter()
            .enumerate()
        {
            for seed in [k as u64, 200 + k as u64] {
                let img = gray16(w, h, seed);
                let png = img.to_png();
                let (pixels, size, color, depth) = decode(&png);
                assert_eq!(
                    (size, color, depth),
                    ((w, h), png::ColorType::Grayscale, png::BitDepth::Sixteen)
                );
                assert!(
                    pixels == be_bytes(&img),
                    "{w}×{h}, seed {seed}: samples differ"
                );
            }
        }
    }

    #[test]
    fn banded_zlib_streams_inflate_to_the_filtered_rows() {
        // Bands of 1, 2, 7 and 64 rows, and one band; the stream is checked by a second
        // decoder, which also verifies the Adler-32.
        let (w, h) = (333, 77);
        let img = rgb(w, h, 7);
        let row = w as usize * 3;
        let expected = up_filtered(&img.data, row);
        for band_rows in [1, 2, 7, 64, 77, 1000] {
            let z = zlib_stream(h as usize, row, band_rows, &|y, out: &mut [u8]| {
                for (x, o) in out.iter_mut().enumerate() {
                    let above = if y == 0 {
                        0
                    } else {
                        img.data[(y - 1) * row + x]
                    };
                    *o = img.data[y * row + x].wrapping_sub(above);
                }
            });
            assert_eq!(&z[..2], &ZLIB_HEADER);
            let adler = simd_adler32::adler32(&expected.as_slice());
            assert_eq!(
                z[z.len() - 4..],
                adler.to_be_bytes(),
                "{band_rows} rows a band"
            );
            let inflated = miniz_oxide::inflate::decompress_to_vec_zlib(&z)
                .unwrap_or_else(|e| panic!("{band_rows} rows a band: {e:?}"));
            assert!(
                inflated == expected,
                "{band_rows} rows a band: bytes differ"
            );
        }
        // The PNG's own stream, as to_png writes it, for both kinds.
        let inflated = miniz_oxide::inflate::decompress_to_vec_zlib(&idat(&img.to_png()));
        assert!(inflated.unwrap() == expected);
        let g = gray16(w, h, 8);
        let inflated = miniz_oxide::inflate::decompress_to_vec_zlib(&idat(&g.to_png()));
        assert!(inflated.unwrap() == up_filtered(&be_bytes(&g), w as usize * 2));
    }

    #[test]
    fn pngs_with_another_band_encoder_hold_the_same_rows() {
        // Stored blocks, then a sync flush: the simplest raw DEFLATE a band can be.
        let bands = std::sync::Mutex::new(Vec::new());
        let stored = |band: &[u8]| {
            bands.lock().unwrap().push(band.to_vec());
            let mut z = Vec::new();
            for chunk in band.chunks(65_535) {
                let len = chunk.len() as u16;
                z.push(0);
                z.extend_from_slice(&len.to_le_bytes());
                z.extend_from_slice(&(!len).to_le_bytes());
                z.extend_from_slice(chunk);
            }
            z.extend_from_slice(&[0, 0, 0, 0xff, 0xff]);
            z
        };
        let (w, h) = (700, 500);
        let img = rgb(w, h, 11);
        assert_eq!(decode(&img.to_png_with(stored)).0, img.data);
        let g = gray16(w, h, 12);
        assert!(decode(&g.to_png_with(stored)).0 == be_bytes(&g));
        // The bands (compressed in parallel, so in any order) are whole filtered lines, cut
        // as to_png cuts them.
        let bands = bands.into_inner().unwrap();
        let (rgb_line, gray_line) = (w as usize * 3 + 1, w as usize * 2 + 1);
        let mut sizes: Vec<usize> = bands.iter().map(Vec::len).collect();
        sizes.sort_unstable();
        let mut expected = Vec::new();
        for line in [rgb_line, gray_line] {
            let per_band = band_rows(h as usize, line);
            for first in (0..h as usize).step_by(per_band) {
                expected.push(per_band.min(h as usize - first) * line);
            }
        }
        expected.sort_unstable();
        assert_eq!(sizes, expected);
    }

    #[test]
    fn rendered_pictures_compress_well() {
        // Flat areas become zero runs: a picture of a few flat rectangles is tiny.
        let mut img = RgbImage::filled(1280, 960, [40, 44, 52]);
        for (x0, y0, c) in [(100, 100, [200, 30, 30]), (700, 400, [30, 200, 90])] {
            for y in y0..y0 + 300 {
                for x in x0..x0 + 400 {
                    img.set(x, y, c);
                }
            }
        }
        let png = img.to_png();
        assert!(png.len() < 20_000, "{} bytes", png.len());
        assert_eq!(decode(&png).0, img.data);
        // Noise cannot shrink, but grows by little.
        let mut rng = SplitMix64::new(3);
        let noise = RgbImage {
            width: 256,
            height: 256,
            data: (0..256 * 256 * 3).map(|_| rng.next_u64() as u8).collect(),
        };
        let png = noise.to_png();
        assert!(
            png.len() < noise.data.len() * 102 / 100,
            "{} bytes",
            png.len()
        );
        assert_eq!(decode(&png).0, noise.data);
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
