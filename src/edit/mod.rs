//! The edit language: every write to the world as data, and how it is applied.
//!
//! [`command`] holds what a write asks for (a shape, an Euler operator, a transform, a
//! camera, a light) in the serde form the journal stores; [`apply`](mod@apply) holds the
//! [`Edit`] that names one write and the [`apply`](fn@apply) that carries it out or refuses
//! it, changing nothing; [`plan`](mod@plan) splits that in two, the work that needs no
//! world (done anywhere, e.g. beside the world's owner) and the rest. An edit is
//! journaled as applied, which is not always as asked: a boolean is asked for by its
//! operands and journaled as the geometry it made (see [`Planned::apply`]). The store journals
//! edits and replays them through this module; the HTTP layer turns requests into them.
//! Neither is imported here.

pub mod apply;
mod boolean;
pub mod command;
pub mod plan;

pub use apply::{Edit, EditError, MAX_BODY_FACES, Outcome, PieceOutcome, Place, apply};
pub use plan::{HEAVY_FACES, Planned, plan, plan_expecting, plan_import, plan_on};
