//! What `write` leaves for `run` and for the peers: per scene and view count, one JSON
//! file of the cameras, the silhouette rings and the cones built from them (winged's
//! own `cone`, cut into triangles), and each view's mask as a PNG.
//!
//! Layout: `D/scenes.json` lists the cases; `D/SCENE/NN/sights.json` holds one case;
//! `D/SCENE/NN/mask_KK.png` are its masks (8-bit grey, 255 inside). Every number is
//! printed in shortest round-trip form, so readers get winged's loci bit for bit.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use glam::DVec2;
use serde_json::{Value, json};
use winged::model::camera::Camera;
use winged::vision::image::Mask;
use winged::vision::perceive::cone::cone;
use winged::vision::perceive::{Depths, Outline, Sight};

use super::triangles::triangles;

/// One case as read back: the sights winged carves with and the masks they came from.
pub struct Case {
    /// The sights, view `k` at index `k`.
    pub sights: Vec<Sight>,
    /// The masks, one per sight.
    pub masks: Vec<Mask>,
}

/// The folder of one case.
pub fn case_dir(dir: &Path, scene: &str, views: usize) -> PathBuf {
    dir.join(scene).join(format!("{views:02}"))
}

/// Writes one case: `sights` (with their cameras and rings) and their `masks`.
pub fn write_case(
    dir: &Path,
    scene: &str,
    true_volume: f64,
    radius: f64,
    sights: &[Sight],
    masks: &[Mask],
) -> Result<PathBuf, String> {
    let views = sights.len();
    let folder = case_dir(dir, scene, views);
    std::fs::create_dir_all(&folder).map_err(|e| format!("{}: {e}", folder.display()))?;
    let depths = Depths::default();
    let mut list = Vec::with_capacity(views);
    for (s, mask) in sights.iter().zip(masks) {
        let name = format!("mask_{:02}.png", s.view);
        write_png(&folder.join(&name), mask)?;
        list.push(sight_json(s, &name, depths));
    }
    let text = serde_json::to_string(&json!({
        "scene": scene,
        "views": views,
        "radius": radius,
        "true_volume": true_volume,
        "near": depths.near,
        "far": depths.far,
        "sights": list,
    }))
    .map_err(|e| e.to_string())?;
    let path = folder.join("sights.json");
    std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(path)
}

/// One sight as JSON: winged's camera (serde form) and the same camera spelled out
/// (i, j, k; OpenCV's R and t; intrinsics), the rings, the mask's file and the cones:
/// the outer ring's between the depths (to intersect), each hole's between half the
/// near and twice the far depth (to subtract), as winged's general boolean takes them.
fn sight_json(s: &Sight, mask: &str, depths: Depths) -> Value {
    let c = &s.camera;
    let k = &c.intrinsics;
    let (r, t) = c.to_opencv();
    let cones: Vec<Value> = s
        .outline
        .rings
        .iter()
        .enumerate()
        .map(|(ri, ring)| {
            let (op, near, far) = if ri == 0 {
                ("intersect", depths.near, depths.far)
            } else {
                ("subtract", depths.near * 0.5, depths.far * 2.0)
            };
            let mesh = cone(c, ring, near, far, s.view, ri as u32);
            let triangles = triangles(&mesh.positions, &mesh.faces);
            // A cone whose triangles do not close (a ring the ear clipper cannot cut
            // cleanly) is written anyway, marked, for `diagnose`; the peers skip it.
            let is_closed = closed(&triangles);
            if !is_closed {
                eprintln!(
                    "view {} ring {ri}: the cone's triangles do not close",
                    s.view
                );
            }
            json!({
                "ring": ri,
                "op": op,
                "near": near,
                "far": far,
                "positions": mesh.positions.iter().map(|p| p.to_array()).collect::<Vec<_>>(),
                "triangles": triangles,
                "closed": is_closed,
            })
        })
        .collect();
    json!({
        "view": s.view,
        "camera": c,
        "position": c.position().to_array(),
        "i": c.i().to_array(),
        "j": c.j().to_array(),
        "k": c.k().to_array(),
        "r_cv": [r.row(0).to_array(), r.row(1).to_array(), r.row(2).to_array()],
        "t_cv": t.to_array(),
        "width": k.width,
        "height": k.height,
        "fx": k.fx,
        "fy": k.fy,
        "cx": k.cx,
        "cy": k.cy,
        "rings": s.outline.rings.iter()
            .map(|ring| ring.iter().map(|q| q.to_array()).collect::<Vec<_>>())
            .collect::<Vec<_>>(),
        "mask": mask,
        "cones": cones,
    })
}

/// Whether every directed edge of `triangles` is used once, and its reverse once.
fn closed(triangles: &[[u32; 3]]) -> bool {
    let mut edges = std::collections::HashMap::new();
    for t in triangles {
        for k in 0..3 {
            *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    edges
        .iter()
        .all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1))
}

/// Writes the list of cases, `D/scenes.json`.
pub fn write_index(dir: &Path, cases: &[Value]) -> Result<(), String> {
    let path = dir.join("scenes.json");
    let text = serde_json::to_string_pretty(cases).map_err(|e| e.to_string())?;
    std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))
}

/// The cases listed in `D/scenes.json`, as (scene, views).
pub fn read_index(dir: &Path) -> Result<Vec<(String, usize)>, String> {
    let path = dir.join("scenes.json");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("{}: {e} (run `write` first)", path.display()))?;
    let list: Vec<Value> =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    list.iter()
        .map(|v| {
            let scene = v["scene"].as_str().ok_or("a case without a scene")?;
            let views = v["views"].as_u64().ok_or("a case without views")?;
            Ok((scene.to_string(), views as usize))
        })
        .collect()
}

/// One case read back from its JSON file and PNG masks.
pub fn read_case(dir: &Path, scene: &str, views: usize) -> Result<Case, String> {
    let folder = case_dir(dir, scene, views);
    let path = folder.join("sights.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let v: Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut sights = Vec::new();
    let mut masks = Vec::new();
    for s in v["sights"].as_array().ok_or("no sights")? {
        let camera: Camera = serde_json::from_value(s["camera"].clone())
            .map_err(|e| format!("{}: camera: {e}", path.display()))?;
        let rings: Vec<Vec<[f64; 2]>> = serde_json::from_value(s["rings"].clone())
            .map_err(|e| format!("{}: rings: {e}", path.display()))?;
        let rings = rings
            .into_iter()
            .map(|r| r.into_iter().map(DVec2::from).collect())
            .collect();
        let view = s["view"].as_u64().ok_or("a sight without a view")? as u32;
        sights.push(Sight {
            camera,
            outline: Outline { rings },
            view,
        });
        let mask = s["mask"].as_str().ok_or("a sight without a mask")?;
        masks.push(read_png(&folder.join(mask))?);
    }
    Ok(Case { sights, masks })
}

/// Writes `mask` as an 8-bit grey PNG, 255 inside, 0 outside.
pub fn write_png(path: &Path, mask: &Mask) -> Result<(), String> {
    let file = File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), mask.width(), mask.height());
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    let pixels: Vec<u8> = mask
        .bits()
        .iter()
        .map(|&b| if b { 255 } else { 0 })
        .collect();
    encoder
        .write_header()
        .and_then(|mut w| w.write_image_data(&pixels))
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// Reads a mask written by [`write_png`] (any grey PNG: nonzero is inside).
pub fn read_png(path: &Path) -> Result<Mask, String> {
    let file = File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| format!("{}: too large", path.display()))?;
    let mut buf = vec![0; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    if info.color_type != png::ColorType::Grayscale || info.bit_depth != png::BitDepth::Eight {
        return Err(format!("{}: not an 8-bit grey PNG", path.display()));
    }
    let bits = buf[..info.buffer_size()].iter().map(|&b| b != 0).collect();
    Mask::from_bits(info.width, info.height, bits).map_err(|e| format!("{}: {e}", path.display()))
}
