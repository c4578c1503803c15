//! The bodies a region query finds, within its budget, and their order in the answer.
//!
//! A query pushes each body it finds as a small record (id, distance, inside flag,
//! where its name and features are). The records are put in the answer's order first
//! and each [`BodyHit`] is made once, in place, so that no answer-sized value is
//! moved by the sort.

use super::query::{BodyHit, QueryError};
use super::reach::Features;
use crate::model::BodyId;

/// The order of an answer's bodies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// Nearest first (a missing distance taken as 0), ties by id: sphere queries.
    Distance,
    /// By id: box queries.
    Id,
}

/// A body found, its answer still to be made.
#[derive(Clone, Copy, Debug)]
struct Found {
    id: BodyId,
    distance: Option<f64>,
    /// The entry the name is read from, when the body has one.
    named: Option<u32>,
    inside: bool,
    /// The body's place in [`Hits::features`] (none at `bodies` detail).
    features: Option<u32>,
}

/// The bodies a region query found, within its budget of features and bodies.
pub struct Hits {
    /// Whether features are kept (above `bodies` detail).
    keep_features: bool,
    found: Vec<Found>,
    features: Vec<Features>,
    counted: usize,
    limit: usize,
    max_bodies: usize,
    /// Whether the budget ran out (the query is refused).
    pub full: bool,
    /// The largest chord deviation of the portions drawn.
    pub tolerance: f64,
}

impl Hits {
    /// No hits yet, with room for `room` bodies (at most `max_bodies`); features are
    /// kept when `keep_features` (a detail above `bodies`).
    pub fn new(keep_features: bool, limit: usize, max_bodies: usize, room: usize) -> Hits {
        let room = room.min(max_bodies);
        Hits {
            keep_features,
            found: Vec::with_capacity(room),
            features: Vec::with_capacity(if keep_features { room } else { 0 }),
            counted: 0,
            limit,
            max_bodies,
            full: false,
            tolerance: 0.0,
        }
    }

    /// Adds body `id` with its features (dropped unless kept). `named` is the entry
    /// its name is read from by [`Hits::finish`], when it has one. Once the budget runs
    /// out, sets [`Hits::full`] and adds nothing more.
    pub fn push(
        &mut self,
        id: BodyId,
        named: Option<u32>,
        distance: Option<f64>,
        inside: bool,
        f: Features,
    ) {
        self.counted += f.count();
        if !self.has_room() {
            return;
        }
        let features = self.keep_features.then(|| {
            self.tolerance = self.tolerance.max(f.tolerance);
            self.features.push(f);
            (self.features.len() - 1) as u32
        });
        self.found.push(Found {
            id,
            distance,
            named,
            inside,
            features,
        });
    }

    /// Adds body `id` without features, as [`Hits::push`] adds it at `bodies` detail.
    #[inline]
    pub fn push_body(
        &mut self,
        id: BodyId,
        named: Option<u32>,
        distance: Option<f64>,
        inside: bool,
    ) {
        if self.has_room() {
            self.found.push(Found {
                id,
                distance,
                named,
                inside,
                features: None,
            });
        }
    }

    /// Whether the budget has room for one more body with the features counted so far;
    /// when not, the hits become [full](Hits::full).
    #[inline]
    fn has_room(&mut self) -> bool {
        if self.counted > self.limit || self.found.len() >= self.max_bodies {
            self.full = true;
        }
        !self.full
    }

    /// The answer's bodies in `order`, each with its name (`name_of` the entry given
    /// to [`Hits::push`]) and its features sorted by id; or the refusal when the
    /// budget ran out.
    pub fn finish<'a>(
        mut self,
        order: Order,
        name_of: impl Fn(u32) -> Option<&'a str>,
    ) -> Result<Vec<BodyHit>, QueryError> {
        if self.full && self.counted > self.limit {
            return Err(QueryError::TooManyFeatures { limit: self.limit });
        }
        if self.full {
            return Err(QueryError::TooManyBodies {
                limit: self.max_bodies,
            });
        }
        let ranks = match order {
            Order::Distance => by_distance(&self.found),
            Order::Id => {
                self.found.sort_unstable_by_key(|f| f.id);
                (0..self.found.len() as u32).collect()
            }
        };
        Ok(ranks
            .into_iter()
            .map(|k| {
                let f = self.found[k as usize];
                let mut hit = BodyHit {
                    id: f.id.get(),
                    name: f.named.and_then(&name_of).map(str::to_owned),
                    distance: f.distance,
                    inside: f.inside,
                    faces: None,
                    edges: None,
                    vertices: None,
                };
                if let Some(at) = f.features {
                    let mut features = std::mem::take(&mut self.features[at as usize]);
                    features.sort();
                    hit.faces = Some(features.faces);
                    hit.edges = Some(features.edges);
                    hit.vertices = Some(features.vertices);
                }
                hit
            })
            .collect())
    }
}

/// The indices of `found` nearest first (a missing distance taken as 0), ties by id.
///
/// Each body's key is one `u64`: the distance's [`ordered_bits`] with their lowest bits
/// replaced by the body's index, which sorts without branches. Runs of bodies whose
/// distances agree above those bits (equal, or within a few parts in 10¹¹), found by one
/// pass over neighbours, are then put in exact order by their whole distance and id.
fn by_distance(found: &[Found]) -> Vec<u32> {
    let n = found.len();
    let full = |k: usize| {
        let f = &found[k];
        (ordered_bits(f.distance.unwrap_or(0.0)), f.id)
    };
    let index_bits = usize::BITS - n.saturating_sub(1).leading_zeros();
    if n < 2 || index_bits > 24 {
        let mut ranks: Vec<u32> = (0..n as u32).collect();
        ranks.sort_by_cached_key(|&k| full(k as usize));
        return ranks;
    }
    let low = (1u64 << index_bits) - 1;
    let mut keys: Vec<u64> = found
        .iter()
        .enumerate()
        .map(|(k, f)| ordered_bits(f.distance.unwrap_or(0.0)) & !low | k as u64)
        .collect();
    keys.sort_unstable();
    let mut start = 0;
    for end in 1..=n {
        if end < n && (keys[end] ^ keys[start]) & !low == 0 {
            continue;
        }
        if end - start > 1 {
            keys[start..end].sort_unstable_by_key(|&k| full((k & low) as usize));
        }
        start = end;
    }
    keys.into_iter().map(|k| (k & low) as u32).collect()
}

/// A key that orders floats as [`f64::total_cmp`] does: the sign bit flipped for
/// positive numbers, every bit for negative ones.
fn ordered_bits(x: f64) -> u64 {
    let bits = x.to_bits();
    if bits >> 63 == 0 {
        bits | 1 << 63
    } else {
        !bits
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Serial;
    use crate::spatial::query::FaceHit;
    use crate::spatial::testing::xorshift;

    #[test]
    fn hits_sort_by_distance_then_id_through_ties_and_near_ties() {
        let mut next = xorshift(0x9e37_79b9_7f4a_7c15);
        for n in [0, 1, 2, 3, 17, 120, 300, 5000] {
            let mut hits = Hits::new(false, usize::MAX, usize::MAX, n);
            let mut expected = Vec::new();
            for _ in 0..n {
                let r = next();
                // Few distinct distances (many ties), neighbours a few ulps apart
                // (equal in the packed key's high bits), and some missing.
                let base: f64 = [0.0, 0.5, 1.25, 3.0][(r % 4) as usize];
                let distance =
                    (!r.is_multiple_of(11)).then(|| f64::from_bits(base.to_bits() + (r >> 8) % 3));
                let id = next() % 1000;
                hits.push(
                    BodyId(Serial(id)),
                    None,
                    distance,
                    false,
                    Features::default(),
                );
                expected.push((ordered_bits(distance.unwrap_or(0.0)), id));
            }
            expected.sort_unstable();
            let got: Vec<(u64, u64)> = hits
                .finish(Order::Distance, |_| None)
                .expect("within the budget")
                .iter()
                .map(|b| (ordered_bits(b.distance.unwrap_or(0.0)), b.id))
                .collect();
            assert_eq!(got, expected, "{n} hits");
        }
    }

    #[test]
    fn each_body_keeps_its_own_name_and_sorted_features_through_the_sort() {
        let mut hits = Hits::new(true, usize::MAX, usize::MAX, 0);
        let names = ["far", "near", "middle"];
        for (k, distance) in [3.0, 1.0, 2.0].into_iter().enumerate() {
            let face = |id: u64| FaceHit {
                id,
                distance: Some(distance),
                portion: None,
            };
            let f = Features {
                faces: vec![face(10 * k as u64 + 2), face(10 * k as u64 + 1)],
                ..Features::default()
            };
            hits.push(
                BodyId(Serial(7 - k as u64)),
                Some(k as u32),
                Some(distance),
                false,
                f,
            );
        }
        let answer = hits
            .finish(Order::Distance, |k| Some(names[k as usize]))
            .expect("within the budget");
        let got: Vec<(u64, &str, Vec<u64>)> = answer
            .iter()
            .map(|b| {
                let faces = b.faces.as_ref().expect("faces kept");
                (
                    b.id,
                    b.name.as_deref().unwrap_or(""),
                    faces.iter().map(|f| f.id).collect(),
                )
            })
            .collect();
        assert_eq!(
            got,
            [
                (6, "near", vec![11, 12]),
                (5, "middle", vec![21, 22]),
                (7, "far", vec![1, 2])
            ]
        );
    }

    #[test]
    fn box_hits_sort_by_id_and_a_spent_budget_refuses() {
        let mut hits = Hits::new(false, usize::MAX, usize::MAX, 0);
        for id in [9, 3, 5] {
            hits.push(BodyId(Serial(id)), None, None, true, Features::default());
        }
        let ids: Vec<u64> = hits
            .finish(Order::Id, |_| None)
            .expect("within the budget")
            .iter()
            .map(|b| b.id)
            .collect();
        assert_eq!(ids, [3, 5, 9]);

        let mut hits = Hits::new(false, usize::MAX, 2, 0);
        for id in [1, 2, 3] {
            hits.push(BodyId(Serial(id)), None, None, false, Features::default());
        }
        assert!(hits.full);
        assert!(matches!(
            hits.finish(Order::Id, |_| None),
            Err(QueryError::TooManyBodies { limit: 2 })
        ));
    }

    #[test]
    fn ordered_bits_order_floats_as_total_cmp_does() {
        let xs = [
            f64::NEG_INFINITY,
            -3.5,
            -1e-300,
            -0.0,
            0.0,
            1e-300,
            2.0,
            7.25,
            f64::INFINITY,
        ];
        for a in xs {
            for b in xs {
                assert_eq!(
                    ordered_bits(a).cmp(&ordered_bits(b)),
                    a.total_cmp(&b),
                    "{a} {b}"
                );
            }
        }
    }
}
