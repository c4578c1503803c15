//! The packed form of a body's polygons, for the edits whose geometry is a computed
//! result rather than a request (an import, a boolean's pieces, perception's carvings):
//! vertex loci and faces as base64 strings of little-endian binary, about a third of the
//! size of JSON numbers and written without formatting a number.
//!
//! - **Loci** ([`loci`]): standard base64 (padded) of each vertex's `x`, `y`, `z` as
//!   little-endian `f64`, 24 bytes per vertex. Bit-exact both ways.
//! - **Faces** ([`faces`]): standard base64 (padded) of little-endian `u32`s: for each
//!   face its number of corners, then its vertex indices.
//!
//! Both read the list form of format version 1 too (`[[x, y, z], ...]` and
//! `[[i, j, k], ...]`), so that journals written before the packed form still replay.
//! Reading is bounded like the list form: at most [`MAX_BODY_VERTICES`] loci,
//! [`MAX_BODY_FACES`] faces and [`MAX_BODY_CORNERS`] corners, and every locus finite.

use std::fmt;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;
use glam::DVec3;
use serde::de::value::SeqAccessDeserializer;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::{Deserialize, Serializer};

use super::bounded::{exceeded, seq_at_most};
use super::{FaceList, MAX_BODY_CORNERS, MAX_BODY_FACES, MAX_BODY_VERTICES};

/// Bytes per packed locus.
const LOCUS_BYTES: usize = 24;

/// Vertex loci, packed (see the module's documentation).
pub mod loci {
    use super::*;

    /// Writes `loci` packed.
    pub fn serialize<S: Serializer>(loci: &[DVec3], s: S) -> Result<S::Ok, S::Error> {
        let mut bytes = Vec::with_capacity(loci.len() * LOCUS_BYTES);
        for p in loci {
            for c in p.to_array() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        s.serialize_str(&STANDARD.encode(bytes))
    }

    /// Reads loci packed or as a list of `[x, y, z]`.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<DVec3>, D::Error> {
        d.deserialize_any(Loci)
    }

    struct Loci;

    impl<'de> Visitor<'de> for Loci {
        type Value = Vec<DVec3>;

        fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str("vertex loci: packed in base64, or a list of [x, y, z]")
        }

        fn visit_str<E: de::Error>(self, text: &str) -> Result<Vec<DVec3>, E> {
            let bytes = decode(text)?;
            if bytes.len() % LOCUS_BYTES != 0 {
                return Err(E::custom(format!(
                    "packed loci take {LOCUS_BYTES} bytes each; {} bytes is no whole number of them",
                    bytes.len()
                )));
            }
            if bytes.len() / LOCUS_BYTES > MAX_BODY_VERTICES {
                return Err(exceeded("vertices", MAX_BODY_VERTICES));
            }
            let f = |b: &[u8]| f64::from_le_bytes(b.try_into().expect("8 bytes"));
            bytes
                .chunks_exact(LOCUS_BYTES)
                .map(|c| {
                    let p = DVec3::new(f(&c[0..8]), f(&c[8..16]), f(&c[16..24]));
                    if p.is_finite() {
                        Ok(p)
                    } else {
                        Err(E::custom(format!("a packed locus is not finite: {p}")))
                    }
                })
                .collect()
        }

        fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Vec<DVec3>, A::Error> {
            seq_at_most(
                SeqAccessDeserializer::new(seq),
                "vertices",
                MAX_BODY_VERTICES,
            )
        }
    }
}

/// Faces, packed (see the module's documentation).
pub mod faces {
    use super::*;

    /// Writes `faces` packed.
    pub fn serialize<S: Serializer>(faces: &FaceList, s: S) -> Result<S::Ok, S::Error> {
        let mut bytes = Vec::with_capacity((faces.len() + faces.corners()) * 4);
        for face in faces.iter() {
            let n = u32::try_from(face.len()).map_err(serde::ser::Error::custom)?;
            bytes.extend_from_slice(&n.to_le_bytes());
            for &i in face {
                bytes.extend_from_slice(&i.to_le_bytes());
            }
        }
        s.serialize_str(&STANDARD.encode(bytes))
    }

    /// Reads faces packed or as a list of lists of indices.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<FaceList, D::Error> {
        d.deserialize_any(Faces)
    }

    struct Faces;

    impl<'de> Visitor<'de> for Faces {
        type Value = FaceList;

        fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str("faces: packed in base64, or a list of lists of vertex indices")
        }

        fn visit_str<E: de::Error>(self, text: &str) -> Result<FaceList, E> {
            let bytes = decode(text)?;
            if bytes.len() % 4 != 0 {
                return Err(E::custom(format!(
                    "packed faces are 4-byte integers; {} bytes is no whole number of them",
                    bytes.len()
                )));
            }
            let words: Vec<u32> = bytes
                .chunks_exact(4)
                .map(|w| u32::from_le_bytes(w.try_into().expect("4 bytes")))
                .collect();
            let mut list = FaceList::new();
            let mut rest = &words[..];
            while let Some((&n, tail)) = rest.split_first() {
                let n = n as usize;
                if n > tail.len() {
                    return Err(E::custom(format!(
                        "packed face {} claims {n} corners but only {} integers follow",
                        list.len(),
                        tail.len()
                    )));
                }
                if list.len() == MAX_BODY_FACES {
                    return Err(exceeded("faces", MAX_BODY_FACES));
                }
                if list.corners() + n > MAX_BODY_CORNERS {
                    return Err(exceeded(
                        "face corners (vertex indices in all faces)",
                        MAX_BODY_CORNERS,
                    ));
                }
                let (face, after) = tail.split_at(n);
                list.push(face);
                rest = after;
            }
            Ok(list)
        }

        fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<FaceList, A::Error> {
            FaceList::deserialize(SeqAccessDeserializer::new(seq))
        }
    }
}

/// Decodes standard base64.
fn decode<E: de::Error>(text: &str) -> Result<Vec<u8>, E> {
    STANDARD
        .decode(text)
        .map_err(|e| E::custom(format!("packed geometry is not base64: {e}")))
}

#[cfg(test)]
mod tests {
    use serde::{Deserialize, Serialize};
    use serde_json::json;

    use super::*;

    #[derive(Serialize, Deserialize, Debug, PartialEq)]
    struct Piece {
        #[serde(with = "loci")]
        positions: Vec<DVec3>,
        #[serde(with = "faces")]
        faces: FaceList,
    }

    fn tetrahedron() -> Piece {
        Piece {
            positions: vec![
                DVec3::ZERO,
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.1, 0.7 + f64::EPSILON, -0.0),
                DVec3::new(1e-300, -3.5, 1e300),
            ],
            faces: [[0u32, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]
                .into_iter()
                .collect(),
        }
    }

    #[test]
    fn packed_polygons_round_trip_bit_for_bit() {
        let piece = tetrahedron();
        let text = serde_json::to_string(&piece).expect("JSON");
        let back: Piece = serde_json::from_str(&text).expect("reads back");
        assert_eq!(back, piece);
        for (a, b) in back.positions.iter().zip(&piece.positions) {
            for (x, y) in a.to_array().iter().zip(b.to_array()) {
                assert_eq!(x.to_bits(), y.to_bits());
            }
        }
        // Packed: strings, not lists.
        let value: serde_json::Value = serde_json::from_str(&text).expect("JSON");
        assert!(value["positions"].is_string() && value["faces"].is_string());
    }

    #[test]
    fn the_list_form_of_version_one_still_reads() {
        let old = json!({
            "positions": [[0, 0, 0], [1, 0, 0], [0.1, 0.7, 0], [0, 0, 1]],
            "faces": [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        });
        let piece: Piece = serde_json::from_value(old).expect("reads");
        assert_eq!(piece.positions[2], DVec3::new(0.1, 0.7, 0.0));
        assert_eq!(piece.faces.iter().nth(3), Some(&[0u32, 3, 2][..]));
    }

    #[test]
    fn broken_packed_geometry_is_refused() {
        let ok = serde_json::to_value(tetrahedron()).expect("JSON");
        let with = |key: &str, v: serde_json::Value| {
            let mut piece = ok.clone();
            piece[key] = v;
            serde_json::from_value::<Piece>(piece).expect_err("refused")
        };
        assert!(
            with("positions", json!("not base64!"))
                .to_string()
                .contains("base64")
        );
        let short = STANDARD.encode([0u8; 23]);
        assert!(
            with("positions", json!(short))
                .to_string()
                .contains("24 bytes")
        );
        let nan = STANDARD.encode(f64::NAN.to_le_bytes().repeat(3));
        assert!(
            with("positions", json!(nan))
                .to_string()
                .contains("not finite")
        );
        let claims = STANDARD.encode([5u32, 0, 1, 2].map(u32::to_le_bytes).concat());
        assert!(
            with("faces", json!(claims))
                .to_string()
                .contains("claims 5 corners")
        );
        let odd = STANDARD.encode([1u8, 0, 0]);
        assert!(with("faces", json!(odd)).to_string().contains("4-byte"));
        assert!(
            with("faces", json!(7))
                .to_string()
                .contains("packed in base64")
        );
    }

    #[test]
    fn too_many_packed_faces_are_refused() {
        let words = vec![0u32; MAX_BODY_FACES + 1];
        let text = STANDARD.encode(
            words
                .iter()
                .flat_map(|w| w.to_le_bytes())
                .collect::<Vec<_>>(),
        );
        let mut piece = serde_json::to_value(tetrahedron()).expect("JSON");
        piece["faces"] = json!(text);
        let e = serde_json::from_value::<Piece>(piece).expect_err("refused");
        assert!(e.to_string().contains("faces"), "{e}");
    }
}
