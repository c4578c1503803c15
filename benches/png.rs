//! PNG encoding of rendered pictures: the 1280 × 960 shaded picture of the 3,000-block
//! world ([`sample::blocks`], seed 1) seen from the first camera of
//! [`sample::ring_cameras`], and its 16-bit depth image in millimetres. The pictures are
//! rendered once, outside the timing; each iteration encodes one.
//!
//! Each picture is encoded twice: by the renderer's own DEFLATE encoder (`to_png`), and
//! by zlib-rs, the Rust port of zlib-ng, on the same input (`to_png_with`): the same
//! Up-filtered bands, compressed in parallel, each one raw DEFLATE stream at level 1 with
//! run-length matches only (`Strategy::Rle`, zlib's `Z_RLE`) ending in a sync flush, in the
//! same zlib framing. The sizes of both are printed once, and the zlib-rs stream is checked
//! to inflate to the same bytes as the renderer's.
//!
//! ```text
//! cargo bench --bench png
//! ```

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use winged::camera::{DEFAULT_NEAR, View};
use winged::render::raster::{Shading, depth_image, rasterize, shaded};
use winged::render::{Scene, sample};
use zlib_rs::{Deflate, DeflateConfig, DeflateFlush, Strategy};

/// One band as zlib-rs compresses it: raw DEFLATE (negative window bits: no zlib header or
/// checksum), level 1, `Strategy::Rle`, ending in a sync flush so that the bands join.
fn zlib_rs_rle(band: &[u8]) -> Vec<u8> {
    let mut z = Deflate::new_with_config(DeflateConfig {
        level: 1,
        window_bits: -15,
        strategy: Strategy::Rle,
        ..DeflateConfig::default()
    });
    // Room for the whole band at once; a flush is complete when output room is left over.
    let mut out = vec![0; zlib_rs::compress_bound(band.len()) + 16];
    z.compress(band, &mut out, DeflateFlush::SyncFlush)
        .expect("zlib-rs compresses a band");
    let n = z.total_out() as usize;
    assert!(z.total_in() == band.len() as u64 && n < out.len());
    out.truncate(n);
    out
}

/// The zlib stream in a PNG file's IDAT chunks, joined.
fn idat(png: &[u8]) -> Vec<u8> {
    let mut z = Vec::new();
    let mut at = 8;
    while at < png.len() {
        let len = u32::from_be_bytes(png[at..at + 4].try_into().expect("4 bytes")) as usize;
        if &png[at + 4..at + 8] == b"IDAT" {
            z.extend_from_slice(&png[at + 8..at + 8 + len]);
        }
        at += 12 + len;
    }
    z
}

/// Checks that the zlib-rs PNG holds the same filtered bytes as the renderer's (the
/// inflater also verifies each stream's Adler-32), and prints both sizes.
fn compare(name: &str, own: &[u8], peer: &[u8]) {
    let inflate = |png: &[u8]| {
        miniz_oxide::inflate::decompress_to_vec_zlib(&idat(png))
            .unwrap_or_else(|e| panic!("{name}: the zlib stream inflates: {e:?}"))
    };
    assert!(
        inflate(own) == inflate(peer),
        "{name}: zlib-rs's stream inflates to other bytes"
    );
    eprintln!(
        "PNG sizes, {name}: winged {} bytes, zlib-rs (RLE, level 1) {} bytes ({:+.1}%)",
        own.len(),
        peer.len(),
        (peer.len() as f64 / own.len() as f64 - 1.0) * 100.0
    );
}

fn png(c: &mut Criterion) {
    let world = sample::blocks(3000, 1).expect("a block world");
    let scene = Scene::build(&world);
    let camera = &sample::ring_cameras(3000, 20, 1280, 960)[0];
    let view = View::new(camera, DEFAULT_NEAR);
    let picture = shaded(&scene, &view, &Shading::default());
    let depth = depth_image(&rasterize(&scene, &view), 0.001);
    compare(
        "shaded",
        &picture.to_png(),
        &picture.to_png_with(zlib_rs_rle),
    );
    compare("depth", &depth.to_png(), &depth.to_png_with(zlib_rs_rle));

    let mut g = c.benchmark_group("png_1280x960");
    g.sample_size(50)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    g.bench_function("shaded_rgb", |b| b.iter(|| black_box(picture.to_png())));
    g.bench_function("shaded_rgb_zlib_rs_rle", |b| {
        b.iter(|| black_box(picture.to_png_with(zlib_rs_rle)))
    });
    g.bench_function("depth_gray16", |b| b.iter(|| black_box(depth.to_png())));
    g.bench_function("depth_gray16_zlib_rs_rle", |b| {
        b.iter(|| black_box(depth.to_png_with(zlib_rs_rle)))
    });
    g.finish();
}

criterion_group!(benches, png);
criterion_main!(benches);
