//! glTF 2.0 and GLB: reading nodes into objects, writing bodies and worlds as GLB.
//!
//! **Reading** ([`read`]): the document is parsed (JSON or GLB, told apart by the `glTF`
//! magic) and validated by the `gltf` crate; buffers come from the GLB's BIN chunk or
//! base64 `data:` URIs only (module `source`). The default scene's node hierarchy is
//! walked and every node whose mesh has triangles becomes one object (module `scene`):
//! its primitives' triangles concatenated, its pose the rigid part of its world matrix,
//! any scale, shear or mirror applied to its positions.
//!
//! **Writing** ([`write_solid`], [`write_world`]): GLB 2.0 with one buffer in the BIN
//! chunk, a mesh of shared f32 vertices and u32 indices per body, a material per colour,
//! the parts tree as the node hierarchy and cameras as perspective cameras (module
//! `write`).
//!
//! Colours: glTF's `baseColorFactor` is linear RGB, winged's
//! [`Color`](crate::model::Color) 8-bit sRGB; each direction converts.

mod scene;
mod source;
mod write;

#[cfg(test)]
mod tests;

use std::collections::HashSet;

use ::gltf::json;

use super::write::{ExportError, Solid};
use super::{ImportError, ImportOptions, RawScene};
use crate::model::{BodyId, Pose, World, default_color};

/// Reads a glTF (JSON, buffers as data URIs) or GLB file.
///
/// The scene read is the default one, else scene 0, else every node that is no node's
/// child. Each node with a mesh that has triangles becomes one [`RawObject`]
/// (in depth-first order, parents before their parts):
///
/// * `name`: the node's name, else its mesh's;
/// * `parent`: the nearest ancestor node that became an object; nodes without triangles
///   are folded, their transforms composed into their descendants';
/// * `pose`: relative to the parent object's world pose (the world's, at the top), the
///   rigid part (translation and rotation) of the node's world matrix; the rest (scale,
///   shear, mirror) is applied to `positions`, so that world positions are the file's
///   meaning exactly, and a mirror rewinds the faces so that they stay counter-clockwise
///   from outside. When every transform on the node's path is rigid (no scale other than
///   exactly 1, no matrix but the identity) the positions are the file's f32 values
///   converted exactly and the pose is composed of the file's own translations and
///   rotations;
/// * `faces`: the triangles of its primitives of mode TRIANGLES, TRIANGLE_STRIP and
///   TRIANGLE_FAN (strips and fans cut with their winding kept, their triangles naming a
///   vertex twice dropped), every primitive's after the previous one's; points and lines
///   are skipped; a primitive without indices uses its vertices in order;
/// * `positions`: the vertices the triangles use, in the file's order (primitives sharing
///   a POSITION accessor share them; a vertex no triangle uses is dropped);
///   `first_vertex` is `None` (renumbered) and `first_face` 0;
/// * `color`: the `baseColorFactor` (linear) of its first triangle primitive with a
///   material, as 8-bit sRGB.
///
/// Sparse accessors are read (their substitutions applied). Skins, morph targets,
/// normals and every other attribute are ignored.
///
/// Positions are in the file's unit (glTF's is the meter; the caller scales).
///
/// Refused, never panicking, with [`ImportError::Parse`] (format `"gltf"`) for a file
/// the `gltf` crate refuses, a bad accessor (wrong type, elements past its buffer view,
/// a count larger than the file, a bad sparse index), an index past its primitive's
/// vertices, a node hierarchy that is not a tree, a transform that is not finite or is
/// singular, or POSITION accessors that together decode to more than twice the file's
/// length (many accessors over the same bytes); [`ImportError::Unsupported`] for a
/// buffer in an external file (named by its URI) or a data URI that is not base64;
/// [`ImportError::TooLarge`] when the triangles (counted from the accessors, each
/// instance of a mesh counted) would pass `options.max_file_faces`, before any buffer is
/// decoded. Every size is checked before anything is allocated from it.
///
/// [`RawObject`]: super::RawObject
pub fn read(bytes: &[u8], options: &ImportOptions) -> Result<RawScene, ImportError> {
    let (root, blob) = source::parse(bytes)?;
    scene::objects(&root, blob.as_deref(), bytes.len(), options)
}

/// One solid as a GLB file: one scene, one node named as the solid, one mesh of one
/// TRIANGLES primitive ([`Solid::triangles`], vertices shared, f32 positions with their
/// bounds, u32 indices), one material of the solid's colour (metallic 0, roughness 0.8,
/// one-sided). A solid without triangles gives a node without a mesh (and no buffer).
///
/// Refused with [`ExportError::Encode`] for a locus that is not finite as f32 or a file
/// past GLB's 4 GiB.
pub fn write_solid(solid: &Solid) -> Result<Vec<u8>, ExportError> {
    let mut builder = write::Builder::new();
    let mesh = builder.mesh(solid, solid.name.clone())?;
    let node = builder.node(json::Node {
        name: solid.name.clone(),
        mesh,
        ..json::Node::default()
    });
    builder.finish(vec![node])
}

/// The whole world as a GLB file.
///
/// One node per body but the root (the root is the scene): the parts tree as the node
/// hierarchy (a body's children its parts, in attachment order; top-level bodies the
/// scene's nodes), each node's translation and rotation its body's pose relative to its
/// supart (f32), its mesh the body in its own frame (none for a body without
/// triangles), its name the body's or `body-<id>`; one material per colour (a body
/// without one has [`default_color`]). Each camera of the world becomes a root node
/// named as the camera, placed at its pose (glTF cameras look down their −z with +y up,
/// as winged's do), with a perspective camera: yfov = 2·atan(height / 2 / fy), aspect
/// ratio width / height, znear 0.05 m, no zfar. An empty world gives a valid GLB with
/// no node and no buffer, and no scene either (glTF allows an empty scene, but the
/// `gltf` crate refuses a scene without nodes).
///
/// Refused as [`write_solid`] is.
pub fn write_world(world: &World) -> Result<Vec<u8>, ExportError> {
    let root = world.root();
    // The bodies in depth-first order: each node's index is its place here.
    let mut order: Vec<BodyId> = Vec::new();
    let mut seen: HashSet<BodyId> = HashSet::new();
    let mut stack: Vec<BodyId> = parts(world, root);
    stack.reverse();
    while let Some(b) = stack.pop() {
        if b == root || !seen.insert(b) {
            continue;
        }
        order.push(b);
        let mut below = parts(world, b);
        below.reverse();
        stack.extend(below);
    }
    let index: std::collections::HashMap<BodyId, u32> = order
        .iter()
        .enumerate()
        .map(|(i, &b)| (b, i as u32))
        .collect();
    let node_of = |b: &BodyId| index.get(b).map(|&i| json::Index::new(i));
    let mut builder = write::Builder::new();
    for &b in &order {
        let Some(node) = world.node(b) else {
            return Err(ExportError::NotFound(b.get()));
        };
        let name = write::node_name(b.get(), node.name.as_deref());
        let color = node.color.unwrap_or_else(|| default_color(b));
        let solid = Solid::from_body(
            b.get(),
            node.name.clone(),
            color,
            &node.body,
            &Pose::IDENTITY,
        );
        let mesh = builder.mesh(&solid, Some(name.clone()))?;
        let children: Vec<_> = parts(world, b).iter().filter_map(node_of).collect();
        let (translation, rotation) = write::trs(&node.pose);
        builder.node(json::Node {
            name: Some(name),
            mesh,
            children: (!children.is_empty()).then_some(children),
            translation,
            rotation,
            ..json::Node::default()
        });
    }
    let mut scene: Vec<_> = parts(world, root).iter().filter_map(node_of).collect();
    for (name, camera) in world.cameras() {
        let c = builder.camera(name, camera);
        let (translation, rotation) = write::trs(&camera.pose);
        scene.push(builder.node(json::Node {
            name: Some(name.to_owned()),
            camera: Some(c),
            translation,
            rotation,
            ..json::Node::default()
        }));
    }
    builder.finish(scene)
}

/// Body `b`'s parts in attachment order (none for an unknown body).
fn parts(world: &World, b: BodyId) -> Vec<BodyId> {
    world
        .parts(b)
        .map(|p| p.iter().copied().collect())
        .unwrap_or_default()
}

/// A linear colour component (0 to 1, clamped; NaN as 0) as an 8-bit sRGB one.
pub(crate) fn linear_to_srgb8(c: f32) -> u8 {
    let c = f64::from(c);
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round().clamp(0.0, 255.0) as u8
}

/// An 8-bit sRGB colour component as a linear one (0 to 1).
pub(crate) fn srgb8_to_linear(c: u8) -> f32 {
    let s = f64::from(c) / 255.0;
    let l = if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    };
    l as f32
}
