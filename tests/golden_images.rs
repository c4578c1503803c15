//! Golden images: the `--demo` scene from its camera "eye" in every mode, compared with
//! the PNGs in `tests/golden/`, so that a change which alters what the renderer draws is
//! seen. The comparison allows small differences: any sample may be off by rounding (2
//! levels of 255, or the same fraction of 65535), and at most 0.5% of the samples (an
//! edge's anti-aliasing, a pixel whose centre sits on an outline) by more.
//!
//! After an intended change, look at the new images and bless them:
//! `WINGED_BLESS=1 cargo test --test golden_images`.

use std::path::PathBuf;

use winged::render::{Mode, Options, Picture, SHADED_BACKGROUND, Scene, hidden, render};
use winged::server::demo::demo_world;

/// Decoded samples (16-bit as u16) and the size.
fn decode(bytes: &[u8]) -> (u32, u32, usize, Vec<u16>) {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes.to_vec()));
    let mut reader = decoder.read_info().expect("a PNG header");
    let mut buf = vec![0; reader.output_buffer_size().expect("a size")];
    let info = reader.next_frame(&mut buf).expect("PNG data");
    let buf = &buf[..info.buffer_size()];
    let samples = if info.bit_depth == png::BitDepth::Sixteen {
        buf.chunks_exact(2)
            .map(|c| u16::from_be_bytes([c[0], c[1]]))
            .collect()
    } else {
        buf.iter().map(|&b| b as u16 * 257).collect()
    };
    (info.width, info.height, info.color_type.samples(), samples)
}

fn png_of(picture: Picture, options: &Options) -> Vec<u8> {
    match picture {
        Picture::Rgb(img) => img.to_png(),
        Picture::Depth { image, .. } | Picture::Ids { image, .. } => image.to_png(),
        Picture::Lines {
            segments,
            width,
            height,
        } => hidden::draw(&segments, width, height, options.background, options.ink).to_png(),
    }
}

#[test]
fn the_demo_scene_looks_as_it_did() {
    let world = demo_world().expect("the demo world builds");
    let camera = *world.camera("eye").expect("the demo camera");
    let scene = Scene::build(&world);
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    let bless = std::env::var_os("WINGED_BLESS").is_some();
    let mut failures = Vec::new();
    for mode in [
        Mode::Shaded,
        Mode::Wire,
        Mode::Hidden,
        Mode::Depth,
        Mode::Ids,
    ] {
        let mut options = Options::default();
        if mode == Mode::Shaded {
            options.background = SHADED_BACKGROUND;
        }
        let picture = render(&scene, &camera, mode, &options).expect("the demo renders");
        let png = png_of(picture, &options);
        let path = dir.join(format!("demo_{}.png", mode.name()));
        if bless {
            std::fs::create_dir_all(&dir).unwrap();
            std::fs::write(&path, &png).unwrap();
            continue;
        }
        let golden = std::fs::read(&path).unwrap_or_else(|e| {
            panic!(
                "{}: {e}; bless with WINGED_BLESS=1 cargo test --test golden_images",
                path.display()
            )
        });
        let (w, h, c, new) = decode(&png);
        let (gw, gh, gc, old) = decode(&golden);
        assert_eq!((w, h, c), (gw, gh, gc), "{}: size or channels", mode.name());
        let far = new
            .iter()
            .zip(&old)
            .filter(|(a, b)| a.abs_diff(**b) > 2 * 257)
            .count();
        let far = far as f64 / new.len() as f64;
        if far > 0.005 {
            failures.push(format!(
                "{}: {:.3}% of samples differ by more than 2 levels",
                mode.name(),
                far * 100.0
            ));
            let fresh = dir.join(format!("demo_{}.new.png", mode.name()));
            std::fs::write(&fresh, &png).ok();
        }
    }
    assert!(
        failures.is_empty(),
        "the drawings changed (new ones written beside the golden ones as *.new.png):\n{}",
        failures.join("\n")
    );
}
