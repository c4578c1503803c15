//! Identifiers: typed 32-bit slot ids inside one body, and world-unique serial numbers.
//!
//! A [`FaceId`], [`EdgeId`] or [`VertexId`] is the index of a slot in its body's arena.
//! Slots are reused after a kill, so a slot id is only meaningful while the entity lives
//! and only inside its own body. A [`Serial`] is Baumgart's serial number: unique across
//! the whole world, never reused, and what the HTTP API exposes as an entity's id.

use std::fmt;

use serde::{Deserialize, Serialize};

macro_rules! slot_id {
    ($(#[$doc:meta])* $name:ident, $prefix:literal) => {
        $(#[$doc])*
        #[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
        pub struct $name(pub(crate) u32);

        impl $name {
            /// The "no entity" value, used where Baumgart's links would be empty
            /// (the PED of a seminal face or vertex).
            pub const NONE: Self = Self(u32::MAX);

            /// The slot index.
            #[inline]
            pub fn index(self) -> usize {
                self.0 as usize
            }

            /// Builds an id from a slot index (no liveness check: the body checks).
            #[inline]
            pub fn from_index(index: usize) -> Self {
                Self(index as u32)
            }

            /// Whether this is [`Self::NONE`].
            #[inline]
            pub fn is_none(self) -> bool {
                self.0 == u32::MAX
            }
        }

        impl fmt::Debug for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                if self.is_none() {
                    write!(f, concat!($prefix, "-"))
                } else {
                    write!(f, concat!($prefix, "{}"), self.0)
                }
            }
        }
    };
}

slot_id!(
    /// A face slot in a body.
    FaceId,
    "f"
);
slot_id!(
    /// An edge slot in a body.
    EdgeId,
    "e"
);
slot_id!(
    /// A vertex slot in a body.
    VertexId,
    "v"
);

/// A world-unique serial number, never reused. Zero is never issued.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Debug, Serialize, Deserialize)]
pub struct Serial(pub u64);

impl Serial {
    /// The value stored in a dead slot.
    pub const NONE: Serial = Serial(0);

    /// The number itself, as the API shows it.
    pub fn get(self) -> u64 {
        self.0
    }
}

impl fmt::Display for Serial {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// The source of serial numbers for one world: a counter that only goes up.
///
/// Every operation that makes an entity takes `&mut Serials`, so that serial numbers
/// stay unique across all the bodies of a world and replaying the same operations on a
/// fresh counter gives the same numbers.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Serials {
    next: u64,
}

impl Default for Serials {
    fn default() -> Self {
        Self::new()
    }
}

impl Serials {
    /// A counter whose first serial is 1.
    pub fn new() -> Self {
        Self { next: 1 }
    }

    /// Takes the next serial number.
    #[inline]
    pub fn take(&mut self) -> Serial {
        let s = Serial(self.next);
        self.next += 1;
        s
    }

    /// The serial the next [`Self::take`] will return.
    pub fn peek(&self) -> Serial {
        Serial(self.next)
    }

    /// Makes sure no serial up to and including `seen` is issued again (for loading a
    /// saved world).
    pub fn skip_past(&mut self, seen: Serial) {
        self.next = self.next.max(seen.0 + 1);
    }
}

/// The two sides of an edge: Baumgart's N (negative) and P (positive) link positions.
///
/// Seen from outside the solid with the edge drawn upward from NVT to PVT, NFACE is on
/// the left and PFACE on the right. Writing the code once over a `Side` halves the
/// branches: side `s` of an edge is the *use* of that edge by the face `face[s]`, running
/// from `vt[s]` to `vt[!s]` counter-clockwise about that face.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Side {
    /// The NFACE/NVT/NCW/NCCW side.
    N = 0,
    /// The PFACE/PVT/PCW/PCCW side.
    P = 1,
}

impl Side {
    /// Both sides, N first.
    pub const BOTH: [Side; 2] = [Side::N, Side::P];

    /// Array index of this side.
    #[inline]
    pub fn ix(self) -> usize {
        self as usize
    }
}

impl std::ops::Not for Side {
    type Output = Side;
    #[inline]
    fn not(self) -> Side {
        match self {
            Side::N => Side::P,
            Side::P => Side::N,
        }
    }
}
