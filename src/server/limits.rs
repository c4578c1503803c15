//! Images sent by clients, decoded within bounds.
//!
//! A PNG of a few hundred kilobytes can claim tens of thousands of pixels per side and inflate
//! to gigabytes (a decompression bomb). [`decode_png`] therefore reads the header first and
//! refuses an image whose dimensions or decoded size exceed [`ImageLimits`] before a single
//! row of pixel data is inflated or the output buffer allocated; the decoder's own working
//! memory is bounded too.

use std::fmt;
use std::io::Cursor;

use axum::http::StatusCode;
use png::{BitDepth, ColorType, DecodeOptions, DecodingError, Transformations};

use super::problem::Problem;

/// The eight bytes every PNG file starts with.
const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];

/// Bounds on an image accepted from a client.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImageLimits {
    /// Most bytes of the encoded (PNG) image.
    pub max_encoded_bytes: usize,
    /// Most pixels per row.
    pub max_width: u32,
    /// Most rows.
    pub max_height: u32,
    /// Most bytes of the decoded pixels (8 bits per channel); also the bound on the
    /// decoder's working memory.
    pub max_decoded_bytes: usize,
}

impl Default for ImageLimits {
    /// 32 MiB encoded, 16384 pixels per side, 256 MiB decoded.
    fn default() -> Self {
        ImageLimits {
            max_encoded_bytes: 32 << 20,
            max_width: 16_384,
            max_height: 16_384,
            max_decoded_bytes: 256 << 20,
        }
    }
}

/// A decoded image, 8 bits per channel, rows top to bottom without padding.
///
/// Invariant: `pixels.len() == width * height * channels`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DecodedImage {
    /// Pixels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Channels per pixel: 1 gray, 2 gray+alpha, 3 RGB, 4 RGBA. Palette images become RGB
    /// (RGBA with transparency); a `tRNS` chunk adds an alpha channel.
    pub channels: u8,
    /// The samples, `channels` bytes per pixel.
    pub pixels: Vec<u8>,
}

/// Which size of an image a [`ImageError::TooLarge`] is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Measure {
    /// The PNG bytes as sent.
    Encoded,
    /// The pixels after decoding.
    Decoded,
}

impl fmt::Display for Measure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Measure::Encoded => "encoded",
            Measure::Decoded => "decoded",
        })
    }
}

/// Why an image was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ImageError {
    /// The bytes do not start with the PNG signature.
    #[error("not a PNG image (the PNG signature is missing)")]
    NotPng,
    /// The PNG is malformed or truncated; the decoder's message.
    #[error("corrupt PNG image: {0}")]
    Corrupt(String),
    /// The encoded or decoded image is larger than its limit.
    #[error("the {what} image is {bytes} bytes; at most {limit} bytes are accepted")]
    TooLarge {
        /// Which size.
        what: Measure,
        /// The size (saturated at `u64::MAX`).
        bytes: u64,
        /// The limit.
        limit: u64,
    },
    /// The image has more pixels per row or more rows than accepted.
    #[error("the image is {width}×{height} pixels; at most {max_width}×{max_height} are accepted")]
    TooWide {
        /// Pixels per row claimed by the header.
        width: u32,
        /// Rows claimed by the header.
        height: u32,
        /// The width limit.
        max_width: u32,
        /// The height limit.
        max_height: u32,
    },
    /// Decoding needed more working memory than allowed (e.g. huge metadata chunks).
    #[error("decoding the image needs more than {limit} bytes of working memory")]
    WorkingMemory {
        /// The limit.
        limit: usize,
    },
}

impl From<ImageError> for Problem {
    /// 400 `invalid-image` for images that are not PNG or are broken, 413 `too-large` for
    /// images beyond a limit.
    fn from(e: ImageError) -> Problem {
        let detail = e.to_string();
        match e {
            ImageError::NotPng | ImageError::Corrupt(_) => Problem::new(
                StatusCode::BAD_REQUEST,
                "invalid-image",
                "Invalid image",
                detail,
            ),
            ImageError::TooLarge { .. }
            | ImageError::TooWide { .. }
            | ImageError::WorkingMemory { .. } => Problem::new(
                StatusCode::PAYLOAD_TOO_LARGE,
                "too-large",
                "Image too large",
                detail,
            ),
        }
    }
}

fn decoding_error(e: DecodingError, limits: &ImageLimits) -> ImageError {
    match e {
        DecodingError::LimitsExceeded => ImageError::WorkingMemory {
            limit: limits.max_decoded_bytes,
        },
        other => ImageError::Corrupt(other.to_string()),
    }
}

/// The fewest 8-bit channels an image of `color` decodes to (without a `tRNS` chunk).
fn min_channels(color: ColorType) -> u64 {
    match color {
        ColorType::Grayscale => 1,
        ColorType::GrayscaleAlpha => 2,
        ColorType::Rgb | ColorType::Indexed => 3,
        ColorType::Rgba => 4,
    }
}

fn too_large_decoded(bytes: u64, limits: &ImageLimits) -> ImageError {
    ImageError::TooLarge {
        what: Measure::Decoded,
        bytes,
        limit: limits.max_decoded_bytes as u64,
    }
}

/// The bytes from a PNG file's start to the end of its header chunk (IHDR): the
/// signature, the chunk's length and type, its 13 bytes of data and its checksum.
pub const PNG_HEADER_BYTES: usize = 8 + 4 + 4 + 13 + 4;

/// The width and height a PNG file's header claims, read from its first
/// [`PNG_HEADER_BYTES`] bytes (more may be given; they are not looked at). Nothing is
/// decoded or allocated.
///
/// Postcondition: on success both are between 1 and 2³¹ − 1, as the PNG specification
/// requires, and the header's checksum is right: the decoder would read the same size.
///
/// # Errors
/// [`ImageError::NotPng`] without the PNG signature; [`ImageError::Corrupt`] when the
/// bytes are too few, the first chunk is not a 13-byte IHDR, its checksum is wrong or a
/// side is out of range.
pub fn png_size(bytes: &[u8]) -> Result<(u32, u32), ImageError> {
    if !bytes.starts_with(&PNG_SIGNATURE) {
        return Err(ImageError::NotPng);
    }
    let corrupt = |why: &str| ImageError::Corrupt(format!("the PNG header {why}"));
    let Some(head) = bytes.get(..PNG_HEADER_BYTES) else {
        return Err(corrupt("is cut short"));
    };
    let word = |at: usize| u32::from_be_bytes([head[at], head[at + 1], head[at + 2], head[at + 3]]);
    if word(8) != 13 || &head[12..16] != b"IHDR" {
        return Err(corrupt("does not start with a 13-byte IHDR chunk"));
    }
    if crc32fast::hash(&head[12..29]) != word(29) {
        return Err(corrupt("fails its checksum"));
    }
    let (width, height) = (word(16), word(20));
    let side = 1..=(i32::MAX as u32);
    if !side.contains(&width) || !side.contains(&height) {
        return Err(corrupt(&format!("claims {width}×{height} pixels")));
    }
    Ok((width, height))
}

/// Decodes a PNG image to 8 bits per channel, within `limits`.
///
/// Order of checks, each before any further work:
/// 1. the encoded size against `max_encoded_bytes`, and the PNG signature;
/// 2. the header (IHDR): width and height against `max_width`/`max_height`, and the least
///    decoded size the colour type allows against `max_decoded_bytes`;
/// 3. the metadata up to the first image data chunk (e.g. `tRNS`, which adds an alpha
///    channel): the exact decoded size against `max_decoded_bytes`;
/// 4. only then is the output buffer allocated and pixel data inflated. The decoder's own
///    buffers are bounded by `max_decoded_bytes` through [`png::Limits`].
///
/// 16-bit samples keep their high byte; palette and sub-byte images are expanded. Only the
/// default image of an animated PNG is decoded; text and ICC profile chunks are skipped, and
/// chunks after the image data are not read.
///
/// Postcondition: on success `pixels.len() == width * height * channels <= max_decoded_bytes`.
///
/// # Errors
/// [`ImageError::NotPng`], [`ImageError::Corrupt`] (malformed, truncated, bad checksum),
/// [`ImageError::TooLarge`], [`ImageError::TooWide`], [`ImageError::WorkingMemory`].
pub fn decode_png(bytes: &[u8], limits: &ImageLimits) -> Result<DecodedImage, ImageError> {
    let mut reader = open_png(bytes, limits, Transformations::normalize_to_color8())?;
    let (color, depth) = reader.output_color_type();
    let channels: u8 = match color {
        ColorType::Grayscale => 1,
        ColorType::GrayscaleAlpha => 2,
        ColorType::Rgb => 3,
        ColorType::Rgba => 4,
        ColorType::Indexed => {
            return Err(ImageError::Corrupt("the palette was not expanded".into()));
        }
    };
    if depth != BitDepth::Eight {
        return Err(ImageError::Corrupt(format!(
            "samples decode to {} bits, not 8",
            depth as u8
        )));
    }
    let (width, height, pixels) = read_frame(&mut reader, channels, limits)?;
    Ok(DecodedImage {
        width,
        height,
        channels,
        pixels,
    })
}

/// A depth picture: 16-bit grey samples, row-major.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DecodedDepth {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// `width × height` samples.
    pub units: Vec<u16>,
}

/// Decodes a depth picture: a 16-bit greyscale PNG, within `limits` as [`decode_png`]
/// holds colour pictures to them.
///
/// # Errors
/// As [`decode_png`]'s, and [`ImageError::Corrupt`] for a PNG that is not 16-bit grey.
pub fn decode_depth_png(bytes: &[u8], limits: &ImageLimits) -> Result<DecodedDepth, ImageError> {
    let mut reader = open_png(bytes, limits, Transformations::IDENTITY)?;
    let (color, depth) = reader.output_color_type();
    if (color, depth) != (ColorType::Grayscale, BitDepth::Sixteen) {
        return Err(ImageError::Corrupt(format!(
            "a depth picture must be 16-bit grey, not {} bits of {color:?}",
            depth as u8
        )));
    }
    let (width, height, bytes) = read_frame(&mut reader, 2, limits)?;
    let units = bytes
        .chunks_exact(2)
        .map(|b| u16::from_be_bytes([b[0], b[1]]))
        .collect();
    Ok(DecodedDepth {
        width,
        height,
        units,
    })
}

/// Checks a PNG's encoded size, signature and header against `limits` and reads the
/// chunks before its pixels, decoding with `transformations`.
fn open_png<'a>(
    bytes: &'a [u8],
    limits: &ImageLimits,
    transformations: Transformations,
) -> Result<png::Reader<Cursor<&'a [u8]>>, ImageError> {
    if bytes.len() > limits.max_encoded_bytes {
        return Err(ImageError::TooLarge {
            what: Measure::Encoded,
            bytes: bytes.len() as u64,
            limit: limits.max_encoded_bytes as u64,
        });
    }
    if !bytes.starts_with(&PNG_SIGNATURE) {
        return Err(ImageError::NotPng);
    }

    let mut options = DecodeOptions::default();
    options.set_ignore_text_chunk(true);
    options.set_ignore_iccp_chunk(true);
    let mut decoder = png::Decoder::new_with_options(Cursor::new(bytes), options);
    decoder.set_limits(png::Limits {
        bytes: limits.max_decoded_bytes,
    });
    decoder.set_transformations(transformations);

    let header = decoder
        .read_header_info()
        .map_err(|e| decoding_error(e, limits))?;
    let (width, height) = (header.width, header.height);
    if width > limits.max_width || height > limits.max_height {
        return Err(ImageError::TooWide {
            width,
            height,
            max_width: limits.max_width,
            max_height: limits.max_height,
        });
    }
    let least = u64::from(width)
        .saturating_mul(u64::from(height))
        .saturating_mul(min_channels(header.color_type));
    if least > limits.max_decoded_bytes as u64 {
        return Err(too_large_decoded(least, limits));
    }
    // Reads the chunks before the first IDAT; no pixel data yet.
    decoder.read_info().map_err(|e| decoding_error(e, limits))
}

/// Reads the image of `reader`, whose samples take `bytes_per_pixel` bytes, within
/// `limits`: its width, height and bytes.
fn read_frame(
    reader: &mut png::Reader<Cursor<&[u8]>>,
    bytes_per_pixel: u8,
    limits: &ImageLimits,
) -> Result<(u32, u32, Vec<u8>), ImageError> {
    let info = reader.info();
    let exact = u64::from(info.width)
        .saturating_mul(u64::from(info.height))
        .saturating_mul(u64::from(bytes_per_pixel));
    let size = match reader.output_buffer_size() {
        Some(size) if size as u64 <= limits.max_decoded_bytes as u64 => size,
        _ => return Err(too_large_decoded(exact, limits)),
    };
    let mut pixels = vec![0u8; size];
    let frame = reader
        .next_frame(&mut pixels)
        .map_err(|e| decoding_error(e, limits))?;
    pixels.truncate(frame.buffer_size());
    Ok((frame.width, frame.height, pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn problems_have_the_right_status() {
        let p: Problem = ImageError::NotPng.into();
        assert_eq!(p.status, StatusCode::BAD_REQUEST);
        let p: Problem = ImageError::Corrupt("bad".into()).into();
        assert_eq!(
            (p.status, p.kind),
            (StatusCode::BAD_REQUEST, "invalid-image")
        );
        let p: Problem = ImageError::TooLarge {
            what: Measure::Decoded,
            bytes: 10,
            limit: 5,
        }
        .into();
        assert_eq!(p.status, StatusCode::PAYLOAD_TOO_LARGE);
        assert_eq!(
            p.detail,
            "the decoded image is 10 bytes; at most 5 bytes are accepted"
        );
        let p: Problem = ImageError::TooWide {
            width: 9,
            height: 1,
            max_width: 8,
            max_height: 8,
        }
        .into();
        assert_eq!(
            (p.status, p.kind),
            (StatusCode::PAYLOAD_TOO_LARGE, "too-large")
        );
    }

    /// A real PNG of `width` × `height` grey pixels.
    fn grey_png(width: u32, height: u32) -> Vec<u8> {
        let mut out = Vec::new();
        let mut encoder = png::Encoder::new(&mut out, width, height);
        encoder.set_color(ColorType::Grayscale);
        encoder.set_depth(BitDepth::Eight);
        encoder
            .write_header()
            .expect("a header")
            .write_image_data(&vec![0; (width * height) as usize])
            .expect("pixels");
        out
    }

    #[test]
    fn the_size_is_read_from_the_header_alone() {
        let png = grey_png(7, 3);
        assert_eq!(png_size(&png), Ok((7, 3)));
        assert_eq!(png_size(&png[..PNG_HEADER_BYTES]), Ok((7, 3)));
        assert!(matches!(
            png_size(&png[..PNG_HEADER_BYTES - 1]),
            Err(ImageError::Corrupt(_))
        ));
        assert_eq!(png_size(b"GIF89a"), Err(ImageError::NotPng));
        let mut bent = png.clone();
        bent[19] ^= 1;
        assert!(matches!(png_size(&bent), Err(ImageError::Corrupt(_))));
    }

    #[test]
    fn encoded_size_and_signature_are_checked_first() {
        let limits = ImageLimits {
            max_encoded_bytes: 4,
            ..ImageLimits::default()
        };
        assert_eq!(
            decode_png(&PNG_SIGNATURE, &limits),
            Err(ImageError::TooLarge {
                what: Measure::Encoded,
                bytes: 8,
                limit: 4
            })
        );
        assert_eq!(
            decode_png(b"GIF89a", &ImageLimits::default()),
            Err(ImageError::NotPng)
        );
        assert!(matches!(
            decode_png(&PNG_SIGNATURE, &ImageLimits::default()),
            Err(ImageError::Corrupt(_))
        ));
    }
}
