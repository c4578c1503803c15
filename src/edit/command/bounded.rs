//! Sequences read with a bound on their length, enforced while they are read.
//!
//! A list past its bound is refused as soon as its first element too many has been read,
//! so that a request naming millions of elements costs at most the bound's memory, not
//! the request's. The refusal is a deserializer error like any other (serde has no other
//! way out of a visitor); to let the caller answer it as "too large" rather than "bad
//! request", the bound that was exceeded is also recorded on the parsing thread, where
//! [`watch`] collects it.

use std::cell::Cell;
use std::fmt;
use std::marker::PhantomData;

use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};

/// A bound on a list's length that a request went past.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the shape has more than {max} {what}; at most {max} are allowed per request")]
pub struct Exceeded {
    /// What was counted (plural), e.g. `"faces"`.
    pub what: &'static str,
    /// The bound.
    pub max: usize,
}

thread_local! {
    /// The bound the current parse on this thread went past, if any.
    static EXCEEDED: Cell<Option<Exceeded>> = const { Cell::new(None) };
}

/// Runs `parse` and tells which bound, if any, it went past.
///
/// Postcondition: the second value is `Some` only if a bounded list was refused during
/// `parse` (whatever `parse` made of that error); a record left by an earlier parse on
/// this thread is cleared first, so it cannot leak into this answer.
pub fn watch<R>(parse: impl FnOnce() -> R) -> (R, Option<Exceeded>) {
    EXCEEDED.set(None);
    let r = parse();
    (r, EXCEEDED.take())
}

/// The error that refuses a list past `max` elements of `what`, recorded for [`watch`].
pub fn exceeded<E: de::Error>(what: &'static str, max: usize) -> E {
    let e = Exceeded { what, max };
    EXCEEDED.set(Some(e));
    E::custom(e)
}

/// Deserializes a sequence of at most `max` elements of `what` into a `Vec`.
///
/// Postcondition: on success `len() <= max`. The sequence is refused with [`exceeded`]
/// once element `max + 1` has been read: no more than `max + 1` elements are ever held.
pub fn seq_at_most<'de, D, T>(d: D, what: &'static str, max: usize) -> Result<Vec<T>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    d.deserialize_seq(AtMost {
        what,
        max,
        element: PhantomData,
    })
}

struct AtMost<T> {
    what: &'static str,
    max: usize,
    element: PhantomData<T>,
}

impl<'de, T: Deserialize<'de>> Visitor<'de> for AtMost<T> {
    type Value = Vec<T>;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "a list of at most {} {}", self.max, self.what)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<T>, A::Error> {
        let mut out = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(self.max));
        while let Some(x) = seq.next_element()? {
            if out.len() == self.max {
                return Err(exceeded(self.what, self.max));
            }
            out.push(x);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn three(text: &str) -> (Result<Vec<u8>, serde_json::Error>, Option<Exceeded>) {
        watch(|| {
            let mut d = serde_json::Deserializer::from_str(text);
            seq_at_most(&mut d, "bytes", 3)
        })
    }

    #[test]
    fn a_list_within_its_bound_is_read() {
        let (r, ex) = three("[1, 2, 3]");
        assert_eq!(r.expect("read"), vec![1, 2, 3]);
        assert_eq!(ex, None);
    }

    #[test]
    fn a_list_past_its_bound_is_refused_and_recorded() {
        // The rest is not valid JSON: the refusal comes before it is reached.
        let (r, ex) = three("[1, 2, 3, 4, this is never read");
        let e = r.expect_err("refused");
        assert!(e.to_string().contains("more than 3 bytes"), "{e}");
        assert_eq!(
            ex,
            Some(Exceeded {
                what: "bytes",
                max: 3
            })
        );
        // A later parse on the same thread starts clean.
        assert_eq!(three("[]").1, None);
    }

    #[test]
    fn other_errors_are_not_recorded() {
        let (r, ex) = three("[1, \"two\"]");
        assert!(r.is_err());
        assert_eq!(ex, None);
    }
}
