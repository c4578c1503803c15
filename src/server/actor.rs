//! The single owner of the world: a tokio task that applies edits one at a time and
//! hands out immutable snapshots.
//!
//! Handlers talk to it through a bounded channel and get their answers on oneshot
//! channels. A write is applied and answered with the world's revision after it. A read
//! asks for a snapshot (an `Arc<World>` at some revision) and does its work outside the
//! actor, so a long read never delays a write and a write never tears a read. A snapshot
//! is made only when a read asks for one after a write: cloning the world copies the
//! parts tree and shares every body (`Arc`), and a later write copies only the body it
//! changes.

use std::sync::Arc;

use tokio::sync::{mpsc, oneshot};

use super::edit::{Edit, EditError, Outcome, apply};
use crate::model::World;

/// How many requests may wait for the actor before senders wait too.
pub const QUEUE: usize = 1024;

/// A message to the actor.
enum Command {
    /// Apply an edit and answer with its outcome and the revision after it.
    Apply {
        edit: Box<Edit>,
        reply: oneshot::Sender<Result<Applied, EditError>>,
    },
    /// Answer with a snapshot of the world.
    Snapshot { reply: oneshot::Sender<Arc<World>> },
}

/// An applied edit's outcome and the world revision after it.
#[derive(Debug, Clone)]
pub struct Applied {
    /// What the edit made or changed.
    pub outcome: Outcome,
    /// The world's revision after the edit.
    pub revision: u64,
}

/// The actor is gone: the server is shutting down.
#[derive(Debug, Clone, Copy, thiserror::Error)]
#[error("the world's owner has stopped")]
pub struct Stopped;

/// A cheap, cloneable handle for talking to the actor.
#[derive(Clone)]
pub struct Handle {
    tx: mpsc::Sender<Command>,
}

impl Handle {
    /// Applies `edit`; `Ok(Err(_))` is the world's refusal (the world is unchanged).
    pub async fn apply(&self, edit: Edit) -> Result<Result<Applied, EditError>, Stopped> {
        let (reply, rx) = oneshot::channel();
        self.tx
            .send(Command::Apply {
                edit: Box::new(edit),
                reply,
            })
            .await
            .map_err(|_| Stopped)?;
        rx.await.map_err(|_| Stopped)
    }

    /// A snapshot of the world as of the last applied edit.
    pub async fn snapshot(&self) -> Result<Arc<World>, Stopped> {
        let (reply, rx) = oneshot::channel();
        self.tx
            .send(Command::Snapshot { reply })
            .await
            .map_err(|_| Stopped)?;
        rx.await.map_err(|_| Stopped)
    }
}

/// Starts the actor on the current tokio runtime, owning `world`. It stops when every
/// [`Handle`] is dropped.
pub fn spawn(world: World) -> Handle {
    let (tx, rx) = mpsc::channel(QUEUE);
    tokio::spawn(run(world, rx));
    Handle { tx }
}

async fn run(mut world: World, mut rx: mpsc::Receiver<Command>) {
    let mut snapshot: Option<Arc<World>> = None;
    while let Some(cmd) = rx.recv().await {
        match cmd {
            Command::Apply { edit, reply } => {
                let result = apply(&mut world, &edit).map(|outcome| Applied {
                    outcome,
                    revision: world.revision(),
                });
                if result.is_ok() {
                    snapshot = None;
                }
                // A requester that gave up waiting is no reason to stop.
                let _ = reply.send(result);
            }
            Command::Snapshot { reply } => {
                let snap = snapshot
                    .get_or_insert_with(|| Arc::new(world.clone()))
                    .clone();
                let _ = reply.send(snap);
            }
        }
    }
}
