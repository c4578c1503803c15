//! Reading a [`Shape`] from JSON as it streams.
//!
//! serde's derive for an internally tagged enum (`{"type": "box", ...}`) first reads the
//! whole object into a generic tree, since the tag may come last; for a polyhedron of
//! millions of faces that tree costs many times the request's own size, all spent before
//! any count can be checked. Here instead every field any shape has is read straight into
//! a typed slot (lists bounded while they are read, see [`super::bounded`]), whatever the
//! order of the fields, and the shape is made from the slots once the object has been
//! read. The names, defaults and refusals are those documented on [`Shape`]'s variants: a
//! field that only another shape takes is refused as unknown, a missing one as missing,
//! and no field may be `null`.

use serde::Deserialize;
use serde::de::{self, Deserializer};

use super::bounded::seq_at_most;
use super::{FaceList, MAX_BODY_FACES, MAX_BODY_VERTICES, Shape, d16, d32};

/// The `type` of a shape.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
enum ShapeType {
    Box,
    Tetrahedron,
    Prism,
    Pyramid,
    Cylinder,
    Cone,
    Sphere,
    Torus,
    Polyhedron,
    Seminal,
    Mesh,
}

impl ShapeType {
    /// The fields a shape of this type takes besides `type`.
    fn fields(self) -> &'static [&'static str] {
        match self {
            ShapeType::Box => &["size"],
            ShapeType::Tetrahedron => &["radius"],
            ShapeType::Prism | ShapeType::Pyramid => &["polygon", "height"],
            ShapeType::Cylinder | ShapeType::Cone => &["radius", "height", "segments"],
            ShapeType::Sphere => &["radius", "segments", "rings"],
            ShapeType::Torus => &["major_radius", "minor_radius", "segments", "rings"],
            ShapeType::Polyhedron => &["vertices", "faces"],
            ShapeType::Seminal => &["position"],
            ShapeType::Mesh => &[
                "format",
                "data",
                "unit",
                "merge_coplanar",
                "weld",
                "coplanar_tolerance",
                "check_intersections",
            ],
        }
    }
}

/// Every field of every shape, each `Some` when given.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Fields {
    #[serde(rename = "type", default, deserialize_with = "given")]
    kind: Option<ShapeType>,
    #[serde(default, deserialize_with = "given")]
    size: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "given")]
    radius: Option<f64>,
    #[serde(default, deserialize_with = "polygon")]
    polygon: Option<Vec<[f64; 2]>>,
    #[serde(default, deserialize_with = "given")]
    height: Option<f64>,
    #[serde(default, deserialize_with = "given")]
    segments: Option<u32>,
    #[serde(default, deserialize_with = "given")]
    rings: Option<u32>,
    #[serde(default, deserialize_with = "given")]
    major_radius: Option<f64>,
    #[serde(default, deserialize_with = "given")]
    minor_radius: Option<f64>,
    #[serde(default, deserialize_with = "vertices")]
    vertices: Option<Vec<[f64; 3]>>,
    #[serde(default, deserialize_with = "given")]
    faces: Option<FaceList>,
    #[serde(default, deserialize_with = "given")]
    position: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "given")]
    format: Option<crate::mesh::Format>,
    #[serde(default, deserialize_with = "given")]
    data: Option<String>,
    #[serde(default, deserialize_with = "given")]
    unit: Option<crate::mesh::Unit>,
    #[serde(default, deserialize_with = "given")]
    merge_coplanar: Option<bool>,
    #[serde(default, deserialize_with = "given")]
    weld: Option<f64>,
    #[serde(default, deserialize_with = "given")]
    coplanar_tolerance: Option<f64>,
    #[serde(default, deserialize_with = "given")]
    check_intersections: Option<bool>,
}

/// A field that is present: `null` is refused as `T` refuses it.
fn given<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<Option<T>, D::Error> {
    T::deserialize(d).map(Some)
}

/// A prism's or pyramid's polygon: its faces are its corners and two more, so it is
/// bounded by [`MAX_BODY_FACES`].
fn polygon<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<[f64; 2]>>, D::Error> {
    seq_at_most(d, "polygon corners", MAX_BODY_FACES).map(Some)
}

/// A polyhedron's vertices, bounded by [`MAX_BODY_VERTICES`].
fn vertices<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<[f64; 3]>>, D::Error> {
    seq_at_most(d, "vertices", MAX_BODY_VERTICES).map(Some)
}

/// `v`, or the error that field `name` is missing.
fn need<T, E: de::Error>(v: Option<T>, name: &'static str) -> Result<T, E> {
    v.ok_or_else(|| E::missing_field(name))
}

impl Fields {
    /// The name of each field besides `type`, and whether it was given.
    fn given(&self) -> [(&'static str, bool); 18] {
        [
            ("size", self.size.is_some()),
            ("radius", self.radius.is_some()),
            ("polygon", self.polygon.is_some()),
            ("height", self.height.is_some()),
            ("segments", self.segments.is_some()),
            ("rings", self.rings.is_some()),
            ("major_radius", self.major_radius.is_some()),
            ("minor_radius", self.minor_radius.is_some()),
            ("vertices", self.vertices.is_some()),
            ("faces", self.faces.is_some()),
            ("position", self.position.is_some()),
            ("format", self.format.is_some()),
            ("data", self.data.is_some()),
            ("unit", self.unit.is_some()),
            ("merge_coplanar", self.merge_coplanar.is_some()),
            ("weld", self.weld.is_some()),
            ("coplanar_tolerance", self.coplanar_tolerance.is_some()),
            ("check_intersections", self.check_intersections.is_some()),
        ]
    }

    /// The shape the fields describe.
    ///
    /// # Errors
    /// `type` missing; a field the type does not take (as an unknown field); a field it
    /// needs missing.
    fn into_shape<E: de::Error>(self) -> Result<Shape, E> {
        let kind = need(self.kind, "type")?;
        let takes = kind.fields();
        if let Some((name, _)) = self
            .given()
            .into_iter()
            .find(|&(name, given)| given && !takes.contains(&name))
        {
            return Err(E::unknown_field(name, takes));
        }
        Ok(match kind {
            ShapeType::Box => Shape::Box {
                size: need(self.size, "size")?,
            },
            ShapeType::Tetrahedron => Shape::Tetrahedron {
                radius: need(self.radius, "radius")?,
            },
            ShapeType::Prism => Shape::Prism {
                polygon: need(self.polygon, "polygon")?,
                height: need(self.height, "height")?,
            },
            ShapeType::Pyramid => Shape::Pyramid {
                polygon: need(self.polygon, "polygon")?,
                height: need(self.height, "height")?,
            },
            ShapeType::Cylinder => Shape::Cylinder {
                radius: need(self.radius, "radius")?,
                height: need(self.height, "height")?,
                segments: self.segments.unwrap_or_else(d32),
            },
            ShapeType::Cone => Shape::Cone {
                radius: need(self.radius, "radius")?,
                height: need(self.height, "height")?,
                segments: self.segments.unwrap_or_else(d32),
            },
            ShapeType::Sphere => Shape::Sphere {
                radius: need(self.radius, "radius")?,
                segments: self.segments.unwrap_or_else(d32),
                rings: self.rings.unwrap_or_else(d16),
            },
            ShapeType::Torus => Shape::Torus {
                major_radius: need(self.major_radius, "major_radius")?,
                minor_radius: need(self.minor_radius, "minor_radius")?,
                segments: self.segments.unwrap_or_else(d32),
                rings: self.rings.unwrap_or_else(d16),
            },
            ShapeType::Polyhedron => Shape::Polyhedron {
                vertices: need(self.vertices, "vertices")?,
                faces: need(self.faces, "faces")?,
            },
            ShapeType::Seminal => Shape::Seminal {
                position: self.position.unwrap_or_default(),
            },
            ShapeType::Mesh => Shape::Mesh(Box::new(super::MeshShape {
                format: need(self.format, "format")?,
                data: need(self.data, "data")?,
                options: super::MeshOptions {
                    unit: self.unit,
                    merge_coplanar: self.merge_coplanar,
                    weld: self.weld,
                    coplanar_tolerance: self.coplanar_tolerance,
                    check_intersections: self.check_intersections,
                },
            })),
        })
    }
}

impl<'de> Deserialize<'de> for Shape {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Fields::deserialize(d)?.into_shape()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn read(v: serde_json::Value) -> Result<Shape, String> {
        serde_json::from_value(v).map_err(|e| e.to_string())
    }

    #[test]
    fn every_shape_reads_back_as_written() {
        let shapes = [
            Shape::Box {
                size: [1.0, 2.0, 3.0],
            },
            Shape::Tetrahedron { radius: 1.5 },
            Shape::Prism {
                polygon: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
                height: 2.0,
            },
            Shape::Pyramid {
                polygon: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
                height: 2.0,
            },
            Shape::Cylinder {
                radius: 1.0,
                height: 2.0,
                segments: 7,
            },
            Shape::Cone {
                radius: 1.0,
                height: 2.0,
                segments: 9,
            },
            Shape::Sphere {
                radius: 1.0,
                segments: 12,
                rings: 6,
            },
            Shape::Torus {
                major_radius: 2.0,
                minor_radius: 0.5,
                segments: 10,
                rings: 5,
            },
            Shape::Polyhedron {
                vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                faces: [[0u32, 1, 2], [0, 2, 1]].into_iter().collect(),
            },
            Shape::Seminal {
                position: [1.0, 2.0, 3.0],
            },
        ];
        for s in shapes {
            let text = serde_json::to_string(&s).expect("JSON");
            let back: Shape = serde_json::from_str(&text).expect(&text);
            assert_eq!(back, s, "{text}");
        }
    }

    #[test]
    fn fields_may_come_in_any_order_and_defaults_apply() {
        assert_eq!(
            read(json!({"radius": 1, "type": "sphere"})),
            Ok(Shape::Sphere {
                radius: 1.0,
                segments: 32,
                rings: 16
            })
        );
        assert_eq!(
            read(json!({"type": "seminal"})),
            Ok(Shape::Seminal { position: [0.0; 3] })
        );
    }

    #[test]
    fn wrong_missing_foreign_and_null_fields_are_refused() {
        let refused = |v: serde_json::Value, says: &str| {
            let e = read(v.clone()).expect_err(&v.to_string());
            assert!(e.contains(says), "{v}: {e}");
        };
        refused(json!({"size": [1, 1, 1]}), "missing field `type`");
        refused(json!({"type": "blob"}), "unknown variant `blob`");
        refused(json!({"type": "box"}), "missing field `size`");
        refused(
            json!({"type": "box", "size": [1, 1, 1], "radius": 1}),
            "unknown field `radius`, expected `size`",
        );
        refused(
            json!({"type": "box", "size": [1, 1, 1], "colour": 1}),
            "unknown field `colour`",
        );
        refused(
            json!({"type": "sphere", "radius": 1, "segments": null}),
            "invalid type: null",
        );
        refused(
            json!({"type": "seminal", "position": null}),
            "invalid type: null",
        );
        refused(json!({"type": "box", "size": [1, 1]}), "invalid length 2");
    }
}
