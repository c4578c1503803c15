//! What made a perceived body: the views that carved it and, face by face, the view and
//! silhouette edge that made each face (perception, `vision::perceive`).
//!
//! A body perception inserts is *provisional*: further views may carve it again, until a
//! user makes it an ordinary body. The record keeps each face's maker by the face's
//! serial, so an edit that keeps faces keeps their makers, and faces an edit makes have
//! none.

use serde::{Deserialize, Serialize};

use super::ids::Serial;

/// What made a face of a perceived body.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Maker {
    /// A wall of a view's cone: the plane through the camera's centre and one edge of a
    /// silhouette ring (`ring` 0 is the outer boundary, then the holes; `edge` `k` runs
    /// from the ring's point `k` to point `k + 1`).
    Wall {
        /// The view, numbered across every request that carved the body.
        view: u32,
        /// The silhouette ring.
        ring: u32,
        /// The edge of that ring.
        edge: u32,
    },
    /// The plane at a view's `near` depth.
    Near {
        /// The view.
        view: u32,
    },
    /// The plane at a view's `far` depth.
    Far {
        /// The view.
        view: u32,
    },
    /// A face of the convex bound carving starts from; a complete carving leaves none.
    Bound {
        /// The view whose (widened) silhouette hull the face bounds.
        view: u32,
    },
    /// A face no view made: an edit made it after perception.
    Unrecorded,
}

impl Maker {
    /// The view that made the face, if a view made it.
    pub fn view(&self) -> Option<u32> {
        match *self {
            Maker::Wall { view, .. }
            | Maker::Near { view }
            | Maker::Far { view }
            | Maker::Bound { view } => Some(view),
            Maker::Unrecorded => None,
        }
    }
}

/// The record of a provisional body: how many views carved it and what made each face.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct Perceived {
    /// Views that carved the body, over every request (views are numbered from 0).
    pub views: u32,
    /// How far, in pixels, the body's outline may lie outside the object's in the views
    /// that carved it: the silhouettes were widened by this much (the request's
    /// tolerance and the outward simplification of the traced outline).
    pub outline_px: f64,
    /// Each face's serial and its maker, by serial.
    pub makers: Vec<(Serial, Maker)>,
}

impl Perceived {
    /// The maker of the face with serial `face`, if it has one.
    pub fn maker(&self, face: Serial) -> Option<Maker> {
        self.makers
            .binary_search_by_key(&face, |(s, _)| *s)
            .ok()
            .map(|i| self.makers[i].1)
    }
}
