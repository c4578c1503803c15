//! PNG images from clients: valid ones decode to the right pixels, broken ones are clean
//! errors, and decompression bombs are refused from their header, before the decoded image
//! is allocated.
//!
//! A global allocator records the largest single allocation made on the current thread, so
//! the bomb tests can check that no buffer of the decoded size was ever requested.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::io::Write;

use png::{BitDepth, ColorType, Compression, Encoder, Filter};
use winged::server::limits::{DecodedImage, ImageError, ImageLimits, Measure, decode_png};

struct Tracking;

thread_local! {
    /// The largest allocation (bytes) requested by this thread since the last reset.
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

fn note(size: usize) {
    let _ = LARGEST.try_with(|c| {
        if size > c.get() {
            c.set(size);
        }
    });
}

// SAFETY: every call is forwarded unchanged to the system allocator; the bookkeeping touches
// only a const-initialised thread-local Cell, which never allocates.
unsafe impl GlobalAlloc for Tracking {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Tracking = Tracking;

/// Runs `f` and returns its result with the largest allocation it made on this thread.
fn largest_allocation<T>(f: impl FnOnce() -> T) -> (T, usize) {
    LARGEST.with(|c| c.set(0));
    let out = f();
    (out, LARGEST.with(Cell::get))
}

/// Options of a test image beyond size, colour type and depth.
#[derive(Default)]
struct Extra<'a> {
    palette: Option<&'a [u8]>,
    trns: Option<&'a [u8]>,
}

fn encode(
    width: u32,
    height: u32,
    color: ColorType,
    depth: BitDepth,
    data: &[u8],
    extra: Extra<'_>,
) -> Vec<u8> {
    let mut out = Vec::new();
    let mut e = Encoder::new(&mut out, width, height);
    e.set_color(color);
    e.set_depth(depth);
    if let Some(p) = extra.palette {
        e.set_palette(p.to_vec());
    }
    if let Some(t) = extra.trns {
        e.set_trns(t.to_vec());
    }
    let mut w = e.write_header().unwrap();
    w.write_image_data(data).unwrap();
    w.finish().unwrap();
    out
}

fn rgb8(width: u32, height: u32, data: &[u8]) -> Vec<u8> {
    encode(
        width,
        height,
        ColorType::Rgb,
        BitDepth::Eight,
        data,
        Extra::default(),
    )
}

/// `(type, offset of the length field, data length)` of every chunk.
fn chunks(png: &[u8]) -> Vec<([u8; 4], usize, usize)> {
    let mut out = Vec::new();
    let mut at = 8;
    while at + 8 <= png.len() {
        let len = u32::from_be_bytes(png[at..at + 4].try_into().unwrap()) as usize;
        let kind: [u8; 4] = png[at + 4..at + 8].try_into().unwrap();
        out.push((kind, at, len));
        at += 12 + len;
    }
    out
}

fn chunk(png: &[u8], kind: &[u8; 4]) -> (usize, usize) {
    chunks(png)
        .into_iter()
        .find(|(k, _, _)| k == kind)
        .map(|(_, at, len)| (at, len))
        .expect("the chunk is present")
}

/// Rewrites the IHDR dimensions of `png` and fixes its CRC.
fn claim_size(png: &mut [u8], width: u32, height: u32) {
    let (at, len) = chunk(png, b"IHDR");
    png[at + 8..at + 12].copy_from_slice(&width.to_be_bytes());
    png[at + 12..at + 16].copy_from_slice(&height.to_be_bytes());
    let crc = crc32fast::hash(&png[at + 4..at + 8 + len]);
    png[at + 8 + len..at + 12 + len].copy_from_slice(&crc.to_be_bytes());
}

/// Deterministic pseudo-random bytes (xorshift64*).
fn noise(n: usize, mut seed: u64) -> Vec<u8> {
    (0..n)
        .map(|_| {
            seed ^= seed >> 12;
            seed ^= seed << 25;
            seed ^= seed >> 27;
            (seed.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 56) as u8
        })
        .collect()
}

fn wide_limits() -> ImageLimits {
    ImageLimits {
        max_width: 200_000,
        max_height: 200_000,
        ..ImageLimits::default()
    }
}

#[test]
fn a_small_rgba_png_decodes_to_its_pixels() {
    let data: Vec<u8> = (0..3 * 2 * 4).map(|i| (i * 11) as u8).collect();
    let png = encode(
        3,
        2,
        ColorType::Rgba,
        BitDepth::Eight,
        &data,
        Extra::default(),
    );
    let img = decode_png(&png, &ImageLimits::default()).unwrap();
    assert_eq!(
        img,
        DecodedImage {
            width: 3,
            height: 2,
            channels: 4,
            pixels: data
        }
    );
}

#[test]
fn other_formats_are_normalised_to_eight_bits() {
    let limits = ImageLimits::default();

    // 16-bit gray keeps the high byte.
    let gray16 = [0x12, 0x34, 0xab, 0xcd, 0xff, 0x00, 0x00, 0xff];
    let png = encode(
        2,
        2,
        ColorType::Grayscale,
        BitDepth::Sixteen,
        &gray16,
        Extra::default(),
    );
    let img = decode_png(&png, &limits).unwrap();
    assert_eq!(
        (img.channels, img.pixels),
        (1, vec![0x12, 0xab, 0xff, 0x00])
    );

    // A 2-bit palette image becomes RGB.
    let palette = [10, 20, 30, 40, 50, 60, 70, 80, 90, 100, 110, 120];
    // Indices 0,1,2,3 packed into one byte, then 3,2 (padded) in the next row.
    let png = encode(
        4,
        2,
        ColorType::Indexed,
        BitDepth::Two,
        &[0b0001_1011, 0b1110_0000],
        Extra {
            palette: Some(&palette),
            ..Extra::default()
        },
    );
    let img = decode_png(&png, &limits).unwrap();
    assert_eq!((img.width, img.height, img.channels), (4, 2, 3));
    let expect: Vec<u8> = [0usize, 1, 2, 3, 3, 2, 0, 0]
        .iter()
        .flat_map(|&i| palette[3 * i..3 * i + 3].to_vec())
        .collect();
    assert_eq!(img.pixels, expect);

    // Gray with a tRNS colour gains an alpha channel.
    let png = encode(
        2,
        1,
        ColorType::Grayscale,
        BitDepth::Eight,
        &[7, 9],
        Extra {
            trns: Some(&[0, 9]),
            ..Extra::default()
        },
    );
    let img = decode_png(&png, &limits).unwrap();
    assert_eq!((img.channels, img.pixels), (2, vec![7, 255, 9, 0]));
}

#[test]
fn the_decoded_limit_is_exact() {
    let png = rgb8(10, 10, &[1; 300]);
    let at = |max_decoded_bytes| ImageLimits {
        max_decoded_bytes,
        ..ImageLimits::default()
    };
    assert_eq!(decode_png(&png, &at(300)).unwrap().pixels.len(), 300);
    assert_eq!(
        decode_png(&png, &at(299)),
        Err(ImageError::TooLarge {
            what: Measure::Decoded,
            bytes: 300,
            limit: 299
        })
    );

    // 100 bytes by the header alone, 200 once tRNS adds alpha: refused after the metadata.
    let png = encode(
        10,
        10,
        ColorType::Grayscale,
        BitDepth::Eight,
        &[3; 100],
        Extra {
            trns: Some(&[0, 3]),
            ..Extra::default()
        },
    );
    assert_eq!(decode_png(&png, &at(200)).unwrap().channels, 2);
    assert_eq!(
        decode_png(&png, &at(150)),
        Err(ImageError::TooLarge {
            what: Measure::Decoded,
            bytes: 200,
            limit: 150
        })
    );
}

#[test]
fn width_height_and_encoded_size_are_limited() {
    let png = rgb8(10, 4, &[0; 120]);
    let limits = ImageLimits {
        max_width: 9,
        ..ImageLimits::default()
    };
    assert_eq!(
        decode_png(&png, &limits),
        Err(ImageError::TooWide {
            width: 10,
            height: 4,
            max_width: 9,
            max_height: 16_384
        })
    );
    let limits = ImageLimits {
        max_height: 3,
        ..ImageLimits::default()
    };
    assert!(matches!(
        decode_png(&png, &limits),
        Err(ImageError::TooWide { .. })
    ));
    let limits = ImageLimits {
        max_encoded_bytes: png.len() - 1,
        ..ImageLimits::default()
    };
    assert!(matches!(
        decode_png(&png, &limits),
        Err(ImageError::TooLarge {
            what: Measure::Encoded,
            ..
        })
    ));
}

#[test]
fn broken_pngs_are_clean_errors() {
    let limits = ImageLimits::default();
    let data = noise(16 * 16 * 3, 7);
    let png = rgb8(16, 16, &data);
    assert_eq!(decode_png(&png, &limits).unwrap().pixels, data);

    // Random bytes, and random bytes after a valid signature.
    assert_eq!(
        decode_png(&noise(4096, 1), &limits),
        Err(ImageError::NotPng)
    );
    assert_eq!(decode_png(&[], &limits), Err(ImageError::NotPng));
    let mut fake = png[..8].to_vec();
    fake.extend(noise(4096, 2));
    assert!(matches!(
        decode_png(&fake, &limits),
        Err(ImageError::Corrupt(_))
    ));

    // Every truncation that cuts into the header or the image data.
    let (idat, idat_len) = chunk(&png, b"IDAT");
    for cut in 8..idat + 8 + idat_len {
        match decode_png(&png[..cut], &limits) {
            Err(ImageError::Corrupt(_)) => {}
            other => panic!("truncated at {cut} of {}: {other:?}", png.len()),
        }
    }

    // A bad CRC on IHDR, a bad CRC on IDAT, a flipped byte inside the compressed data.
    let (ihdr, ihdr_len) = chunk(&png, b"IHDR");
    for at in [
        ihdr + 8 + ihdr_len,
        idat + 8 + idat_len,
        idat + 8 + idat_len / 2,
    ] {
        let mut bad = png.clone();
        bad[at] ^= 0x40;
        match decode_png(&bad, &limits) {
            Err(ImageError::Corrupt(msg)) => assert!(!msg.is_empty()),
            other => panic!("byte {at} flipped: {other:?}"),
        }
    }
}

#[test]
fn a_decompression_bomb_is_refused_before_its_pixels_are_allocated() {
    // 30000 × 30000 8-bit gray zeros: 900 MB of pixels. The rows are streamed through the
    // encoder, so this test never holds the raw image either.
    const SIDE: u32 = 30_000;
    let mut png = Vec::new();
    {
        let mut e = Encoder::new(&mut png, SIDE, SIDE);
        e.set_color(ColorType::Grayscale);
        e.set_depth(BitDepth::Eight);
        e.set_compression(Compression::High);
        e.set_filter(Filter::NoFilter);
        let mut w = e.write_header().unwrap();
        let mut s = w.stream_writer().unwrap();
        let row = vec![0u8; SIDE as usize];
        for _ in 0..SIDE {
            s.write_all(&row).unwrap();
        }
        s.finish().unwrap();
        w.finish().unwrap();
    }
    assert!(png.len() < 4 << 20, "the bomb is {} bytes", png.len());

    let (result, largest) = largest_allocation(|| decode_png(&png, &wide_limits()));
    assert_eq!(
        result,
        Err(ImageError::TooLarge {
            what: Measure::Decoded,
            bytes: u64::from(SIDE) * u64::from(SIDE),
            limit: 256 << 20
        })
    );
    assert!(largest < 1 << 20, "an allocation of {largest} bytes");

    // Under the default limits, the width alone refuses it.
    assert!(matches!(
        decode_png(&png, &ImageLimits::default()),
        Err(ImageError::TooWide { width: SIDE, .. })
    ));
}

#[test]
fn a_header_claiming_a_huge_image_over_a_tiny_idat_is_refused() {
    let mut png = encode(
        1,
        1,
        ColorType::Rgba,
        BitDepth::Eight,
        &[1, 2, 3, 4],
        Extra::default(),
    );
    claim_size(&mut png, 100_000, 100_000);
    assert!(png.len() < 100);

    let (result, largest) = largest_allocation(|| decode_png(&png, &ImageLimits::default()));
    assert_eq!(
        result,
        Err(ImageError::TooWide {
            width: 100_000,
            height: 100_000,
            max_width: 16_384,
            max_height: 16_384
        })
    );
    assert!(largest < 1 << 20, "an allocation of {largest} bytes");

    let (result, largest) = largest_allocation(|| decode_png(&png, &wide_limits()));
    assert_eq!(
        result,
        Err(ImageError::TooLarge {
            what: Measure::Decoded,
            bytes: 100_000 * 100_000 * 4,
            limit: 256 << 20
        })
    );
    assert!(largest < 1 << 20, "an allocation of {largest} bytes");

    // Within every limit, the claimed rows are missing: a clean error, not a panic.
    let mut png = encode(
        1,
        1,
        ColorType::Grayscale,
        BitDepth::Eight,
        &[1],
        Extra::default(),
    );
    claim_size(&mut png, 64, 64);
    assert!(matches!(
        decode_png(&png, &ImageLimits::default()),
        Err(ImageError::Corrupt(_))
    ));
}
