//! A polyhedron's faces as lists of vertex indices, stored flat.
//!
//! In JSON a face list is a list of lists (`[[0, 1, 2], [0, 2, 3], ...]`). In memory the
//! indices of all faces lie in one array, with the end of each face in another: two
//! allocations for the whole list instead of one per face, about a third of the memory
//! for triangles. Read from JSON, the list is bounded while it is read (see
//! [`super::bounded`]): at most [`MAX_BODY_FACES`] faces and [`MAX_BODY_CORNERS`]
//! indices in all.

use std::fmt;

use serde::de::{DeserializeSeed, Deserializer, SeqAccess, Visitor};
use serde::ser::{SerializeSeq, Serializer};
use serde::{Deserialize, Serialize};

use super::bounded::exceeded;
use super::{MAX_BODY_CORNERS, MAX_BODY_FACES};

/// Faces, each a list of vertex indices.
///
/// Invariant: `ends` is non-decreasing and its last element (if any) is `corners.len()`;
/// face `i` is `corners[ends[i - 1]..ends[i]]` (from 0 for face 0).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FaceList {
    corners: Vec<u32>,
    ends: Vec<usize>,
}

impl FaceList {
    /// An empty list.
    pub fn new() -> Self {
        FaceList::default()
    }

    /// The number of faces.
    pub fn len(&self) -> usize {
        self.ends.len()
    }

    /// Whether there are no faces.
    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }

    /// The number of vertex indices in all faces.
    pub fn corners(&self) -> usize {
        self.corners.len()
    }

    /// Appends a face.
    ///
    /// Postcondition: `len()` is one more and the last face is `face`.
    pub fn push(&mut self, face: &[u32]) {
        self.corners.extend_from_slice(face);
        self.ends.push(self.corners.len());
    }

    /// The faces in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = &[u32]> + '_ {
        self.ends.iter().enumerate().map(|(i, &end)| {
            let start = if i == 0 { 0 } else { self.ends[i - 1] };
            &self.corners[start..end]
        })
    }
}

impl<F: AsRef<[u32]>> FromIterator<F> for FaceList {
    fn from_iter<I: IntoIterator<Item = F>>(faces: I) -> Self {
        let mut list = FaceList::new();
        for f in faces {
            list.push(f.as_ref());
        }
        list
    }
}

impl Serialize for FaceList {
    /// As a list of lists of indices.
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut seq = s.serialize_seq(Some(self.len()))?;
        for face in self.iter() {
            seq.serialize_element(face)?;
        }
        seq.end()
    }
}

impl<'de> Deserialize<'de> for FaceList {
    /// From a list of lists of indices, refused (see [`super::bounded::exceeded`]) as soon
    /// as it holds more than [`MAX_BODY_FACES`] faces or [`MAX_BODY_CORNERS`] indices.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_seq(Faces)
    }
}

/// Reads the outer list.
struct Faces;

impl<'de> Visitor<'de> for Faces {
    type Value = FaceList;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a list of faces, each a list of vertex indices")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<FaceList, A::Error> {
        let mut list = FaceList::new();
        while seq
            .next_element_seed(Face {
                corners: &mut list.corners,
            })?
            .is_some()
        {
            if list.ends.len() == MAX_BODY_FACES {
                return Err(exceeded("faces", MAX_BODY_FACES));
            }
            list.ends.push(list.corners.len());
        }
        Ok(list)
    }
}

/// Reads one face, appending its indices to `corners`.
struct Face<'a> {
    corners: &'a mut Vec<u32>,
}

impl<'de> DeserializeSeed<'de> for Face<'_> {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_seq(self)
    }
}

impl<'de> Visitor<'de> for Face<'_> {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a face: a list of vertex indices")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        while let Some(i) = seq.next_element::<u32>()? {
            if self.corners.len() == MAX_BODY_CORNERS {
                return Err(exceeded(
                    "face corners (vertex indices in all faces)",
                    MAX_BODY_CORNERS,
                ));
            }
            self.corners.push(i);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::bounded::{Exceeded, watch};
    use super::*;

    #[test]
    fn faces_round_trip_through_json() {
        let text = "[[0,1,2],[0,2,3,4],[5,6,7]]";
        let list: FaceList = serde_json::from_str(text).expect("faces");
        assert_eq!(list.len(), 3);
        assert_eq!(list.corners(), 10);
        let faces: Vec<&[u32]> = list.iter().collect();
        assert_eq!(faces, vec![&[0, 1, 2][..], &[0, 2, 3, 4], &[5, 6, 7]]);
        assert_eq!(serde_json::to_string(&list).expect("JSON"), text);
        assert_eq!(list, faces.into_iter().collect::<FaceList>());
    }

    #[test]
    fn empty_faces_and_lists_are_kept() {
        let list: FaceList = serde_json::from_str("[[],[1]]").expect("faces");
        let faces: Vec<&[u32]> = list.iter().collect();
        assert_eq!(faces, vec![&[][..], &[1]]);
        assert!(
            serde_json::from_str::<FaceList>("[]")
                .expect("faces")
                .is_empty()
        );
    }

    #[test]
    fn a_face_that_is_no_list_is_refused() {
        let e = serde_json::from_str::<FaceList>("[[0,1,2],7]").expect_err("refused");
        assert!(
            e.to_string().contains("a face: a list of vertex indices"),
            "{e}"
        );
        assert!(serde_json::from_str::<FaceList>("[[0,-1,2]]").is_err());
    }

    #[test]
    fn too_many_faces_are_refused_while_reading() {
        let mut text = String::from("[");
        for _ in 0..MAX_BODY_FACES {
            text.push_str("[],");
        }
        text.push_str("[], not JSON");
        let (r, ex) = watch(|| serde_json::from_str::<FaceList>(&text));
        assert!(r.is_err());
        assert_eq!(
            ex,
            Some(Exceeded {
                what: "faces",
                max: MAX_BODY_FACES
            })
        );
    }

    #[test]
    fn too_many_corners_are_refused_while_reading() {
        // One face one index longer than all faces may be together; the text after it
        // is never reached.
        let mut text = String::from("[[");
        for _ in 0..MAX_BODY_CORNERS {
            text.push_str("0,");
        }
        text.push_str("0], not JSON");
        let (r, ex) = watch(|| serde_json::from_str::<FaceList>(&text));
        assert!(r.is_err());
        assert_eq!(
            ex,
            Some(Exceeded {
                what: "face corners (vertex indices in all faces)",
                max: MAX_BODY_CORNERS
            })
        );
    }
}
