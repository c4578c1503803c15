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
///
/// Snapshots keep it in a flat form (see [`Flat`]): their encoding cannot read the
/// tagged form [`Maker`] has in JSON.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(from = "Flat", into = "Flat")]
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

/// [`Perceived`] as snapshots keep it: each maker as its kind's number (0 wall, 1 near,
/// 2 far, 3 bound, 4 unrecorded) and its view, ring and edge (0 where it has none).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Flat {
    views: u32,
    outline_px: f64,
    makers: Vec<(Serial, u8, u32, u32, u32)>,
}

impl From<Perceived> for Flat {
    fn from(p: Perceived) -> Flat {
        let makers = p
            .makers
            .into_iter()
            .map(|(s, m)| match m {
                Maker::Wall { view, ring, edge } => (s, 0, view, ring, edge),
                Maker::Near { view } => (s, 1, view, 0, 0),
                Maker::Far { view } => (s, 2, view, 0, 0),
                Maker::Bound { view } => (s, 3, view, 0, 0),
                Maker::Unrecorded => (s, 4, 0, 0, 0),
            })
            .collect();
        Flat {
            views: p.views,
            outline_px: p.outline_px,
            makers,
        }
    }
}

impl From<Flat> for Perceived {
    fn from(f: Flat) -> Perceived {
        let makers = f
            .makers
            .into_iter()
            .map(|(s, kind, view, ring, edge)| {
                let m = match kind {
                    0 => Maker::Wall { view, ring, edge },
                    1 => Maker::Near { view },
                    2 => Maker::Far { view },
                    3 => Maker::Bound { view },
                    _ => Maker::Unrecorded,
                };
                (s, m)
            })
            .collect();
        Perceived {
            views: f.views,
            outline_px: f.outline_px,
            makers,
        }
    }
}
