//! Writing GLB: one buffer (the BIN chunk), a mesh per body, a material per colour.

use std::borrow::Cow;
use std::collections::HashMap;

use ::gltf::binary::{Glb, Header};
use ::gltf::json;
use json::accessor::{ComponentType, GenericComponentType, Type};
use json::validation::{Checked, USize64};

use super::srgb8_to_linear;
use crate::mesh::write::{ExportError, Solid};
use crate::model::{Camera, Color, Pose};

/// The near clipping distance written for cameras (m): winged's cameras have none.
pub(super) const ZNEAR: f32 = 0.05;

/// The roughness of written materials (metallic is 0).
const ROUGHNESS: f32 = 0.8;

fn encode(detail: impl Into<String>) -> ExportError {
    ExportError::Encode {
        format: "glb",
        detail: detail.into(),
    }
}

/// A glTF document being built, with the bytes of its one buffer.
pub(super) struct Builder {
    root: json::Root,
    bin: Vec<u8>,
    materials: HashMap<Color, json::Index<json::Material>>,
}

impl Builder {
    /// An empty document (asset version 2.0, generator "winged").
    pub(super) fn new() -> Builder {
        Builder {
            root: json::Root {
                asset: json::Asset {
                    generator: Some("winged".into()),
                    ..json::Asset::default()
                },
                ..json::Root::default()
            },
            bin: Vec::new(),
            materials: HashMap::new(),
        }
    }

    /// A mesh named `name` of `solid`'s triangles ([`Solid::triangles`]): one TRIANGLES primitive,
    /// its vertices shared (f32), indices u32, the material of `solid.color`. `None`
    /// when the solid has no triangle (glTF has no empty mesh).
    ///
    /// Refused with [`ExportError::Encode`] for a locus that is not finite as f32.
    pub(super) fn mesh(
        &mut self,
        solid: &Solid,
        name: Option<String>,
    ) -> Result<Option<json::Index<json::Mesh>>, ExportError> {
        let triangles = solid.triangles();
        if triangles.is_empty() {
            return Ok(None);
        }
        let n = solid.positions.len();
        if let Some(bad) = triangles.iter().flatten().find(|&&i| i as usize >= n) {
            return Err(encode(format!(
                "body {}: a triangle names vertex {bad} of {n}",
                solid.id
            )));
        }
        let mut min = [f32::INFINITY; 3];
        let mut max = [f32::NEG_INFINITY; 3];
        let start = self.bin.len();
        self.bin.reserve(12 * n + 12 * triangles.len());
        for p in &solid.positions {
            let p = [p.x as f32, p.y as f32, p.z as f32];
            if p.iter().any(|c| !c.is_finite()) {
                return Err(encode(format!(
                    "body {}: a vertex locus is not finite as f32",
                    solid.id
                )));
            }
            for k in 0..3 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
                self.bin.extend_from_slice(&p[k].to_le_bytes());
            }
        }
        let positions = self.view(start, json::buffer::Target::ArrayBuffer);
        let start = self.bin.len();
        for i in triangles.iter().flatten() {
            self.bin.extend_from_slice(&i.to_le_bytes());
        }
        let indices = self.view(start, json::buffer::Target::ElementArrayBuffer);
        let bound = |v: [f32; 3]| Some(json::Value::from(v.map(f64::from).to_vec()));
        let positions = self.root.push(json::Accessor {
            buffer_view: Some(positions),
            byte_offset: None,
            count: USize64::from(n),
            component_type: Checked::Valid(GenericComponentType(ComponentType::F32)),
            extensions: None,
            extras: Default::default(),
            type_: Checked::Valid(Type::Vec3),
            min: bound(min),
            max: bound(max),
            name: None,
            normalized: false,
            sparse: None,
        });
        let indices = self.root.push(json::Accessor {
            buffer_view: Some(indices),
            byte_offset: None,
            count: USize64::from(3 * triangles.len()),
            component_type: Checked::Valid(GenericComponentType(ComponentType::U32)),
            extensions: None,
            extras: Default::default(),
            type_: Checked::Valid(Type::Scalar),
            min: None,
            max: None,
            name: None,
            normalized: false,
            sparse: None,
        });
        let material = self.material(solid.color);
        let primitive = json::mesh::Primitive {
            attributes: [(Checked::Valid(json::mesh::Semantic::Positions), positions)].into(),
            extensions: None,
            extras: Default::default(),
            indices: Some(indices),
            material: Some(material),
            mode: Checked::Valid(json::mesh::Mode::Triangles),
            targets: None,
        };
        Ok(Some(self.root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name,
            primitives: vec![primitive],
            weights: None,
        })))
    }

    /// A buffer view of the bytes from `start` to the end of the buffer, then pads the
    /// buffer to a multiple of 4 bytes. Precondition: `start` is a multiple of 4.
    fn view(
        &mut self,
        start: usize,
        target: json::buffer::Target,
    ) -> json::Index<json::buffer::View> {
        let length = self.bin.len() - start;
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64::from(length),
            byte_offset: Some(USize64::from(start)),
            byte_stride: None,
            name: None,
            target: Some(Checked::Valid(target)),
            extensions: None,
            extras: Default::default(),
        })
    }

    /// The material of `color` (one per colour): its base colour in linear RGB, metallic
    /// 0, one-sided.
    fn material(&mut self, color: Color) -> json::Index<json::Material> {
        if let Some(&m) = self.materials.get(&color) {
            return m;
        }
        let [r, g, b] = color.0.map(srgb8_to_linear);
        let m = self.root.push(json::Material {
            name: Some(color.to_hex()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor([r, g, b, 1.0]),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(ROUGHNESS),
                ..Default::default()
            },
            double_sided: false,
            ..Default::default()
        });
        self.materials.insert(color, m);
        m
    }

    /// A perspective camera of `camera`'s intrinsics: yfov = 2·atan(height / 2 / fy),
    /// aspect ratio width / height, near [`ZNEAR`], no far plane.
    pub(super) fn camera(&mut self, name: &str, camera: &Camera) -> json::Index<json::Camera> {
        let k = &camera.intrinsics;
        let height = f64::from(k.height);
        let yfov = 2.0 * (height / 2.0 / k.fy).atan();
        self.root.push(json::Camera {
            name: Some(name.to_owned()),
            orthographic: None,
            perspective: Some(json::camera::Perspective {
                aspect_ratio: Some((f64::from(k.width) / height) as f32),
                yfov: yfov as f32,
                zfar: None,
                znear: ZNEAR,
                extensions: None,
                extras: Default::default(),
            }),
            type_: Checked::Valid(json::camera::Type::Perspective),
            extensions: None,
            extras: Default::default(),
        })
    }

    /// Adds a node.
    pub(super) fn node(&mut self, node: json::Node) -> json::Index<json::Node> {
        self.root.push(node)
    }

    /// The GLB file: one scene of `nodes` (the default scene; none when `nodes` is
    /// empty), the buffer (if any bytes) as the BIN chunk.
    ///
    /// Refused with [`ExportError::Encode`] when the file would pass 4 GiB (GLB's
    /// lengths are 32-bit) or the JSON cannot be written.
    pub(super) fn finish(
        mut self,
        nodes: Vec<json::Index<json::Node>>,
    ) -> Result<Vec<u8>, ExportError> {
        if !self.bin.is_empty() {
            self.root.push(json::Buffer {
                byte_length: USize64::from(self.bin.len()),
                name: None,
                uri: None,
                extensions: None,
                extras: Default::default(),
            });
        }
        // A scene without nodes is valid glTF, but the `gltf` crate (1.4) refuses one:
        // with nothing to show, there is no scene at all.
        if !nodes.is_empty() {
            let scene = self.root.push(json::Scene {
                extensions: None,
                extras: Default::default(),
                name: None,
                nodes,
            });
            self.root.scene = Some(scene);
        }
        let json = json::serialize::to_vec(&self.root).map_err(|e| encode(e.to_string()))?;
        let padded = |n: usize| n.div_ceil(4) * 4;
        let mut length = 12 + 8 + padded(json.len());
        if !self.bin.is_empty() {
            length += 8 + padded(self.bin.len());
        }
        let Ok(length) = u32::try_from(length) else {
            return Err(encode(format!(
                "the file would have {length} bytes, past GLB's limit of 4 GiB"
            )));
        };
        let glb = Glb {
            header: Header {
                magic: *b"glTF",
                version: 2,
                length,
            },
            json: Cow::Owned(json),
            bin: (!self.bin.is_empty()).then_some(Cow::Owned(self.bin)),
        };
        let out = glb.to_vec().map_err(|e| encode(e.to_string()))?;
        debug_assert_eq!(out.len(), length as usize);
        Ok(out)
    }
}

/// A node's (and mesh's) name: the body's, else `body-<id>`.
pub(super) fn node_name(id: u64, name: Option<&str>) -> String {
    name.map_or_else(|| format!("body-{id}"), str::to_owned)
}

/// A node's translation and rotation for `pose` (f64 to f32), each `None` when it is the
/// identity's.
pub(super) fn trs(pose: &Pose) -> (Option<[f32; 3]>, Option<json::scene::UnitQuaternion>) {
    let p = pose.position;
    let q = pose.rotation;
    let translation = (p != glam::DVec3::ZERO).then_some([p.x as f32, p.y as f32, p.z as f32]);
    let rotation = (q != glam::DQuat::IDENTITY).then_some(json::scene::UnitQuaternion([
        q.x as f32, q.y as f32, q.z as f32, q.w as f32,
    ]));
    (translation, rotation)
}
