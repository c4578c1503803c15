//! The single owner of the world: a thread that applies edits one at a time, makes them
//! durable in groups, and hands out immutable snapshots.
//!
//! Handlers talk to it through a bounded channel and get their answers on oneshot
//! channels. The owner takes every command waiting (up to a batch), applies the writes
//! in order, appends the applied ones to the [`Journal`] in one commit (group commit: one
//! fsync for the whole group), and only then acknowledges them and publishes their
//! [`Change`]s. A refused write is answered at once and never journaled.
//!
//! Reads ask for a snapshot (an `Arc<World>` of durable state) and do their work outside
//! the owner, so a long read never delays a write and a write never tears a read. A
//! snapshot is made only when a read asks for one after a write: cloning the world
//! copies the parts tree and shares every body (`Arc`), and a later write copies only the
//! body it changes. The newest snapshot is also kept where handlers can take it without
//! queueing, until the next write.
//!
//! An edit is planned before it is queued ([`crate::edit::plan`]): the work that needs
//! no world runs on the requester's task, or, for a large body, on a blocking thread (at
//! most one per core), so the owner only inserts what was built and other writes are not
//! held up behind the build. A boolean is solved the same way on the newest snapshot;
//! the owner places its result if both bodies are still as the snapshot had them, and
//! solves it again itself otherwise.
//!
//! When the queue is full, writes are refused at once with [`WriteError::Busy`] (the HTTP
//! layer answers 503 with `Retry-After`) rather than queued without bound.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use tokio::sync::{Semaphore, mpsc, oneshot};

use super::changes::{self, Change};
use super::events::Feed;
use crate::edit::{Edit, EditError, Outcome, Planned, plan, plan_expecting, plan_on};
use crate::model::{Serial, World};

/// How many requests may wait for the owner by default.
pub const QUEUE: usize = 1024;

/// The most writes committed together.
pub const MAX_BATCH: usize = 1024;

/// One applied edit on its way to the journal.
#[derive(Debug, Clone, Copy)]
pub struct Entry<'a> {
    /// The world revision the edit produced.
    pub revision: u64,
    /// The edit, as applied.
    pub edit: &'a Edit,
    /// What it changed.
    pub change: &'a Change,
}

/// Where the world's owner makes applied edits durable before acknowledging them.
pub trait Journal: Send + 'static {
    /// Why the journal failed.
    type Error: std::error::Error;

    /// Makes `entries` (consecutive revisions, oldest first) durable: all of them when
    /// `Ok`, none of them when `Err` (or, if only recording how far the journal reached
    /// failed, all of them; the writes are still refused). `world` is the world after
    /// the last entry: its revision and next serial are recorded as reached.
    fn append(&mut self, entries: &[Entry<'_>], world: &World) -> Result<(), Self::Error>;

    /// Called after every committed group with the world as it now is (it may start a
    /// snapshot of it).
    fn committed(&mut self, world: &World);

    /// The world as durable, after an append failed (its edits are dropped).
    fn reload(&mut self) -> Result<World, Self::Error>;

    /// Whether appends reach storage (false for [`InMemory`]).
    fn is_durable(&self) -> bool {
        true
    }

    /// Writes a snapshot of `world` now (for a backup).
    fn checkpoint(&mut self, world: &World) -> Result<Checkpoint, Self::Error>;

    /// Called once when the owner stops, with the final world.
    fn close(&mut self, world: &World);
}

/// A snapshot written on request.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Checkpoint {
    /// The world revision it holds.
    pub revision: u64,
    /// Its file.
    pub path: String,
    /// Its size.
    pub bytes: u64,
    /// Time taken.
    pub seconds: f64,
}

/// Why a checkpoint was not written.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// The server keeps its world in memory only.
    #[error("the world is held in memory only (the server was started with --memory)")]
    InMemory,
    /// The snapshot could not be written.
    #[error("the snapshot could not be written: {0}")]
    Storage(String),
    /// The owner is gone.
    #[error("the world's owner has stopped")]
    Stopped,
}

/// No durability: the world lives in memory only.
#[derive(Debug, Default, Clone, Copy)]
pub struct InMemory;

/// [`InMemory`] has nowhere to write a snapshot.
#[derive(Debug, Clone, Copy, thiserror::Error)]
#[error("the world is held in memory only")]
pub struct NoStorage;

impl Journal for InMemory {
    type Error = NoStorage;
    fn is_durable(&self) -> bool {
        false
    }
    fn append(&mut self, _: &[Entry<'_>], _: &World) -> Result<(), Self::Error> {
        Ok(())
    }
    fn committed(&mut self, _: &World) {}
    fn reload(&mut self) -> Result<World, Self::Error> {
        Err(NoStorage)
    }
    fn checkpoint(&mut self, _: &World) -> Result<Checkpoint, Self::Error> {
        Err(NoStorage)
    }
    fn close(&mut self, _: &World) {}
}

/// What the owner reports as it works (for metrics).
pub trait Observer: Send + Sync + 'static {
    /// A group of `entries` was committed in `elapsed`.
    fn committed(&self, elapsed: Duration, entries: usize);
    /// A write was refused because the queue was full.
    fn overloaded(&self);
    /// A snapshot of `bytes` was written in `elapsed`.
    fn snapshotted(&self, _elapsed: Duration, _bytes: u64) {}
    /// Edits being planned beside the owner went up (`+1`) or down (`-1`).
    fn planning(&self, _change: i64) {}
}

/// An observer that ignores everything.
pub struct Unobserved;

impl Observer for Unobserved {
    fn committed(&self, _: Duration, _: usize) {}
    fn overloaded(&self) {}
}

/// A message to the owner.
enum Command {
    /// Apply an edit (if the world is at `expected`) and answer once it is durable.
    Apply {
        planned: Planned,
        expected: Option<u64>,
        reply: oneshot::Sender<Result<Applied, WriteError>>,
    },
    /// Answer with a snapshot of the world.
    Snapshot { reply: oneshot::Sender<Arc<World>> },
    /// Write a snapshot file of the world now.
    Checkpoint {
        reply: oneshot::Sender<Result<Checkpoint, CheckpointError>>,
    },
}

/// An applied edit's outcome and the world revision after it.
#[derive(Debug, Clone)]
pub struct Applied {
    /// What the edit made or changed.
    pub outcome: Outcome,
    /// The world's revision after the edit.
    pub revision: u64,
}

/// Why a write was not applied. In every case the world is unchanged by it.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The world refused the edit.
    #[error(transparent)]
    Refused(#[from] EditError),
    /// The write's precondition failed: the world has moved on.
    #[error("the world is at revision {actual}, not the expected {expected}")]
    Conflict {
        /// The revision the client expected.
        expected: u64,
        /// The world's revision.
        actual: u64,
    },
    /// The journal could not be written; the edit was dropped.
    #[error("the write could not be made durable ({0}); it was not applied")]
    Storage(String),
    /// Too many requests are waiting for the owner.
    #[error("the server is busy: {0} requests are waiting for the world")]
    Busy(usize),
    /// The owner is gone: the server is shutting down.
    #[error("the world's owner has stopped")]
    Stopped,
}

/// The actor is gone: the server is shutting down.
#[derive(Debug, Clone, Copy, thiserror::Error)]
#[error("the world's owner has stopped")]
pub struct Stopped;

/// The newest snapshot, kept for handlers to take without queueing.
type Latest = Arc<Mutex<Option<Arc<World>>>>;

/// A cheap, cloneable handle for talking to the owner.
#[derive(Clone)]
pub struct Handle {
    tx: mpsc::Sender<Command>,
    /// Turns for planning large edits on blocking threads: one per core.
    planners: Arc<Semaphore>,
    /// The world's next serial after the last write applied, for plans to number their
    /// bodies by.
    next_serial: Arc<AtomicU64>,
    latest: Latest,
    observer: Arc<dyn Observer>,
    failure: Failure,
}

/// One edit being planned beside the owner, counted by the observer while it lasts.
struct Planning(Arc<dyn Observer>);

impl Planning {
    fn start(observer: Arc<dyn Observer>) -> Self {
        observer.planning(1);
        Planning(observer)
    }
}

impl Drop for Planning {
    fn drop(&mut self) {
        self.0.planning(-1);
    }
}

/// Why the owner refuses writes for good, once its storage failed beyond repair.
type Failure = Arc<Mutex<Option<String>>>;

impl Handle {
    /// Applies `edit` if the world's revision is `expected` (any revision when `None`),
    /// and answers once it is durable. The edit is planned first (a large body is built
    /// on a blocking thread), then queued for the owner.
    pub async fn apply_if(&self, edit: Edit, expected: Option<u64>) -> Result<Applied, WriteError> {
        let planned = self.plan(edit).await?;
        self.apply_planned_if(planned, expected).await
    }

    /// [`Handle::apply_if`] for an edit already planned (an import whose bodies were
    /// built where the file was read).
    pub async fn apply_planned_if(
        &self,
        planned: Planned,
        expected: Option<u64>,
    ) -> Result<Applied, WriteError> {
        let (reply, rx) = oneshot::channel();
        let cmd = Command::Apply {
            planned,
            expected,
            reply,
        };
        match self.tx.try_send(cmd) {
            Ok(()) => {}
            Err(mpsc::error::TrySendError::Full(_)) => {
                self.observer.overloaded();
                return Err(WriteError::Busy(self.tx.max_capacity()));
            }
            Err(mpsc::error::TrySendError::Closed(_)) => return Err(WriteError::Stopped),
        }
        rx.await.map_err(|_| WriteError::Stopped)?
    }

    /// Plans `edit`: here if it is light, else on a blocking thread once one of the
    /// planners' turns is free; a boolean is solved there on the newest snapshot, so the
    /// owner only places its result. A requester that stops waiting does not stop a
    /// build under way; its turn is given back when the build ends.
    async fn plan(&self, edit: Edit) -> Result<Planned, WriteError> {
        let edit = Box::new(edit);
        if !edit.is_heavy() {
            return plan(edit).map_err(WriteError::Refused);
        }
        let snapshot = if edit.wants_snapshot() {
            Some(self.snapshot().await.map_err(|_| WriteError::Stopped)?)
        } else {
            None
        };
        let turn = self
            .planners
            .clone()
            .acquire_owned()
            .await
            .map_err(|_| WriteError::Stopped)?;
        let counted = Planning::start(self.observer.clone());
        let next = Serial(self.next_serial.load(Ordering::Relaxed));
        let built = tokio::task::spawn_blocking(move || {
            let _turn = turn;
            let _counted = counted;
            match snapshot {
                Some(world) => plan_on(edit, &world, next),
                None => plan_expecting(edit, next),
            }
        })
        .await;
        match built {
            Ok(planned) => planned.map_err(WriteError::Refused),
            Err(e) if e.is_panic() => std::panic::resume_unwind(e.into_panic()),
            Err(_) => Err(WriteError::Stopped),
        }
    }

    /// Applies `edit` whatever the world's revision.
    pub async fn apply(&self, edit: Edit) -> Result<Applied, WriteError> {
        self.apply_if(edit, None).await
    }

    /// A snapshot of the world as of the last durable write.
    pub async fn snapshot(&self) -> Result<Arc<World>, Stopped> {
        if let Some(w) = self
            .latest
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone()
        {
            return Ok(w);
        }
        let (reply, rx) = oneshot::channel();
        self.tx
            .send(Command::Snapshot { reply })
            .await
            .map_err(|_| Stopped)?;
        rx.await.map_err(|_| Stopped)
    }

    /// Writes a snapshot file of the durable world now, waiting its turn in the queue.
    pub async fn checkpoint(&self) -> Result<Checkpoint, CheckpointError> {
        let (reply, rx) = oneshot::channel();
        self.tx
            .send(Command::Checkpoint { reply })
            .await
            .map_err(|_| CheckpointError::Stopped)?;
        rx.await.map_err(|_| CheckpointError::Stopped)?
    }

    /// Requests waiting for the owner now.
    pub fn queue_depth(&self) -> usize {
        self.tx.max_capacity() - self.tx.capacity()
    }

    /// Whether the owner is still running.
    pub fn is_running(&self) -> bool {
        !self.tx.is_closed()
    }

    /// Why writes are refused for good, if storage failed and the world could not be
    /// reloaded from it.
    pub fn storage_failure(&self) -> Option<String> {
        self.failure
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone()
    }
}

/// Settings of the owner.
#[derive(Debug, Clone, Copy)]
pub struct ActorConfig {
    /// Requests that may wait before writes are refused as busy.
    pub queue: usize,
    /// The most writes committed together.
    pub max_batch: usize,
}

impl Default for ActorConfig {
    fn default() -> Self {
        ActorConfig {
            queue: QUEUE,
            max_batch: MAX_BATCH,
        }
    }
}

/// Starts the owner on a thread of its own, owning `world` and `journal`, publishing to
/// `feed`. It stops when every [`Handle`] is dropped, after calling
/// [`Journal::close`]; join the returned thread to wait for that.
pub fn spawn<J: Journal>(
    world: World,
    journal: J,
    feed: Arc<Feed>,
    observer: Arc<dyn Observer>,
    config: ActorConfig,
) -> std::io::Result<(Handle, std::thread::JoinHandle<()>)> {
    let (tx, rx) = mpsc::channel(config.queue.max(1));
    let latest: Latest = Arc::new(Mutex::new(None));
    let failure: Failure = Arc::new(Mutex::new(None));
    let next_serial = Arc::new(AtomicU64::new(world.next_serial().get()));
    let owner = Owner {
        next_serial: next_serial.clone(),
        world,
        journal,
        feed,
        observer: observer.clone(),
        latest: latest.clone(),
        max_batch: config.max_batch.max(1),
        failed: failure.clone(),
    };
    let thread = std::thread::Builder::new()
        .name("world-owner".into())
        .spawn(move || owner.run(rx))?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let handle = Handle {
        tx,
        planners: Arc::new(Semaphore::new(cores)),
        next_serial,
        latest,
        observer,
        failure,
    };
    Ok((handle, thread))
}

/// Starts an owner of `world` with no durability (tests, `--memory`).
pub fn spawn_in_memory(world: World) -> Handle {
    let feed = Feed::new(1, world.revision(), Vec::new());
    spawn(
        world,
        InMemory,
        feed,
        Arc::new(Unobserved),
        ActorConfig::default(),
    )
    .expect("a thread can be started")
    .0
}

struct Owner<J> {
    world: World,
    /// Where handles read the world's next serial.
    next_serial: Arc<AtomicU64>,
    journal: J,
    feed: Arc<Feed>,
    observer: Arc<dyn Observer>,
    latest: Latest,
    max_batch: usize,
    /// Set when the journal failed and the world could not be reloaded: writes are
    /// refused from then on.
    failed: Failure,
}

/// An applied write waiting for its commit.
struct Pending {
    reply: oneshot::Sender<Result<Applied, WriteError>>,
    edit: Box<Edit>,
    applied: Applied,
    change: Change,
}

/// What applying one write left to do.
enum Step {
    /// It changed the world: journal it, then answer and publish its change.
    Changed(Pending),
    /// It changed nothing: answer with the revision the world is at, journal nothing.
    Unchanged(oneshot::Sender<Result<Applied, WriteError>>, Outcome),
}

impl<J: Journal> Owner<J> {
    fn run(mut self, mut rx: mpsc::Receiver<Command>) {
        let mut batch = Vec::with_capacity(self.max_batch);
        while let Some(first) = rx.blocking_recv() {
            batch.push(first);
            while batch.len() < self.max_batch {
                match rx.try_recv() {
                    Ok(cmd) => batch.push(cmd),
                    Err(_) => break,
                }
            }
            self.handle(&mut batch);
        }
        self.journal.close(&self.world);
    }

    /// Applies the writes of `batch`, commits them together, then answers everyone.
    fn handle(&mut self, batch: &mut Vec<Command>) {
        let mut pending: Vec<Pending> = Vec::new();
        let mut unchanged = Vec::new();
        let mut readers = Vec::new();
        let mut checkpoints = Vec::new();
        for cmd in batch.drain(..) {
            match cmd {
                Command::Apply {
                    planned,
                    expected,
                    reply,
                } => match self.apply_one(planned, expected, reply) {
                    Some(Step::Changed(p)) => pending.push(p),
                    Some(Step::Unchanged(reply, outcome)) => unchanged.push((reply, outcome)),
                    None => {}
                },
                Command::Snapshot { reply } => readers.push(reply),
                Command::Checkpoint { reply } => checkpoints.push(reply),
            }
        }
        if !pending.is_empty() {
            self.commit(pending);
        }
        // After the commit, so that the revision they name is durable (or, if the
        // commit failed, the one the world went back to).
        for (reply, outcome) in unchanged {
            let revision = self.world.revision();
            let _ = reply.send(Ok(Applied { outcome, revision }));
        }
        if !readers.is_empty() {
            let snap = self.snapshot();
            for r in readers {
                let _ = r.send(snap.clone());
            }
        }
        for reply in checkpoints {
            let result = self.journal.checkpoint(&self.world).map_err(|e| {
                if !self.journal.is_durable() {
                    CheckpointError::InMemory
                } else {
                    CheckpointError::Storage(e.to_string())
                }
            });
            let _ = reply.send(result);
        }
    }

    /// Applies one write; answers a refusal at once, or returns it pending its commit,
    /// or, when it changed nothing (the revision did not move), pending its answer
    /// without a journal entry or a change.
    fn apply_one(
        &mut self,
        planned: Planned,
        expected: Option<u64>,
        reply: oneshot::Sender<Result<Applied, WriteError>>,
    ) -> Option<Step> {
        let failed = self
            .failed
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone();
        if let Some(why) = failed {
            let _ = reply.send(Err(WriteError::Storage(why)));
            return None;
        }
        let actual = self.world.revision();
        if let Some(expected) = expected
            && expected != actual
        {
            let _ = reply.send(Err(WriteError::Conflict { expected, actual }));
            return None;
        }
        let before = changes::before(&self.world, planned.edit());
        let (edit, outcome) = planned.apply(&mut self.world);
        self.next_serial
            .store(self.world.next_serial().get(), Ordering::Relaxed);
        match outcome {
            Ok(outcome) if self.world.revision() == actual => Some(Step::Unchanged(reply, outcome)),
            Ok(outcome) => {
                let revision = self.world.revision();
                let change = changes::describe(revision, &edit, &outcome, &before, &self.world);
                Some(Step::Changed(Pending {
                    reply,
                    edit,
                    applied: Applied { outcome, revision },
                    change,
                }))
            }
            Err(e) => {
                // A requester that gave up waiting is no reason to stop.
                let _ = reply.send(Err(WriteError::Refused(e)));
                None
            }
        }
    }

    /// Journals the applied writes in one commit, then acknowledges and publishes them;
    /// if the journal fails, refuses them all and goes back to the durable world.
    fn commit(&mut self, pending: Vec<Pending>) {
        // Readers must not see these writes before they are durable.
        self.latest.lock().unwrap_or_else(|p| p.into_inner()).take();
        let started = Instant::now();
        let entries: Vec<Entry<'_>> = pending
            .iter()
            .map(|p| Entry {
                revision: p.applied.revision,
                edit: &p.edit,
                change: &p.change,
            })
            .collect();
        let result = self.journal.append(&entries, &self.world);
        drop(entries);
        match result {
            Ok(()) => {
                self.observer.committed(started.elapsed(), pending.len());
                // Published before acknowledged: a writer that reads the feed after its
                // answer finds its own change there.
                let (replies, changes): (Vec<_>, Vec<_>) = pending
                    .into_iter()
                    .map(|p| ((p.reply, p.applied), p.change))
                    .unzip();
                self.feed.publish(changes);
                for (reply, applied) in replies {
                    let _ = reply.send(Ok(applied));
                }
                self.journal.committed(&self.world);
            }
            Err(e) => {
                let why = e.to_string();
                tracing::error!(error = %why, writes = pending.len(), "journal append failed; the writes are refused");
                for p in pending {
                    let _ = p.reply.send(Err(WriteError::Storage(why.clone())));
                }
                match self.journal.reload() {
                    Ok(world) => {
                        tracing::warn!(revision = world.revision(), "world reloaded from storage");
                        self.feed.reset_revision(world.revision());
                        self.next_serial
                            .store(world.next_serial().get(), Ordering::Relaxed);
                        self.world = world;
                    }
                    Err(e) => {
                        tracing::error!(error = %e, "the world cannot be reloaded; writes are refused until restart");
                        *self.failed.lock().unwrap_or_else(|p| p.into_inner()) =
                            Some(format!("storage failed and could not recover: {e}"));
                    }
                }
            }
        }
    }

    /// A snapshot of the world now, made once per write and kept for later readers.
    fn snapshot(&mut self) -> Arc<World> {
        let mut latest = self.latest.lock().unwrap_or_else(|p| p.into_inner());
        latest
            .get_or_insert_with(|| Arc::new(self.world.clone()))
            .clone()
    }
}
