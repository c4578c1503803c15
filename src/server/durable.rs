//! The world's owner's journal on disk: a [`Store`] (SQLite journal plus snapshot
//! files), with snapshots written in the background every so many revisions and the
//! journal pruned behind them.
//!
//! Each journal entry carries the [`Change`] it made, so that after a restart
//! [`open`] reads the recent changes back and `GET /v1/world/changes` and the event
//! stream continue where they were (up to `--history` revisions), even for revisions
//! already folded into a snapshot.

use std::path::Path;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::Instant;

use super::actor::{Checkpoint, Entry, Journal, Observer};
use super::changes::Change;
use crate::model::World;
use crate::store::{SnapshotWritten, Store, StoreError, StoreOptions};

/// Journal entries deleted after one commit, at most: a short transaction.
const PRUNE_STEP: u64 = 2_000;

/// When snapshots are taken and how much journal is kept behind them.
#[derive(Debug, Clone, Copy)]
pub struct SnapshotPolicy {
    /// Revisions between background snapshots.
    pub every: u64,
    /// Journal entries kept behind the oldest snapshot, so recent changes can still be
    /// listed after a restart.
    pub keep: u64,
}

impl Default for SnapshotPolicy {
    fn default() -> Self {
        SnapshotPolicy {
            every: 100_000,
            keep: 100_000,
        }
    }
}

/// A [`Journal`] backed by a data directory.
pub struct Durable {
    store: Store,
    policy: SnapshotPolicy,
    /// The revision of the newest snapshot written (or being written).
    last_snapshot: u64,
    /// A background snapshot's result, while one is being written.
    writing: Option<Receiver<Result<SnapshotWritten, StoreError>>>,
    /// Journal entries up to this revision are no longer needed; they are deleted a
    /// few at a time after each commit, so no write waits for a long delete.
    prune_to: u64,
    observer: Arc<dyn Observer>,
}

/// A recovered data directory, ready to serve.
pub struct Opened {
    /// The journal for the world's owner.
    pub journal: Durable,
    /// The world as of the last durable write.
    pub world: World,
    /// The most recent changes, oldest first, ending at the world's revision.
    pub recent: Vec<Change>,
}

/// Opens data directory `dir`, seeding a fresh one with `seed()` (written as its first
/// snapshot), and recovers the world from it.
///
/// `history` is how many recent changes to read back for the change feed.
pub fn open(
    dir: &Path,
    options: StoreOptions,
    policy: SnapshotPolicy,
    history: usize,
    observer: Arc<dyn Observer>,
    seed: impl FnOnce() -> Option<World>,
) -> Result<Opened, StoreError> {
    let mut store = Store::open(dir, options)?;
    if store.is_fresh()?
        && let Some(world) = seed()
    {
        let w = store.write_snapshot(&world)?;
        tracing::info!(revision = w.revision, path = %w.path.display(), "seeded a fresh data directory");
    }
    let recovered = store.recover(|_, _, _, _| {})?;
    let revision = recovered.world.revision();
    let recent = recent_changes(&store, revision, history)?;
    let last_snapshot = recovered.snapshot.unwrap_or(0);
    Ok(Opened {
        journal: Durable {
            store,
            policy,
            last_snapshot,
            writing: None,
            prune_to: 0,
            observer,
        },
        world: recovered.world,
        recent,
    })
}

/// The stored changes of the last `history` revisions up to `revision`: the longest
/// run of consecutive, readable ones that ends at `revision` (older entries may have
/// been written without one).
fn recent_changes(store: &Store, revision: u64, history: usize) -> Result<Vec<Change>, StoreError> {
    let after = revision.saturating_sub(history as u64);
    let mut run: Vec<Change> = Vec::new();
    for (r, text) in store.recent_changes(after)? {
        match serde_json::from_str::<Change>(&text) {
            Ok(c) if c.revision == r && run.last().is_none_or(|p| p.revision + 1 == r) => {
                run.push(c)
            }
            Ok(c) if c.revision == r => run = vec![c],
            _ => run.clear(),
        }
    }
    if run.last().is_some_and(|c| c.revision != revision) {
        run.clear();
    }
    Ok(run)
}

impl Durable {
    /// Collects a finished background snapshot and prunes the journal behind it.
    fn collect(&mut self) {
        let Some(rx) = &self.writing else { return };
        let result = match rx.try_recv() {
            Ok(r) => r,
            Err(TryRecvError::Empty) => return,
            Err(TryRecvError::Disconnected) => {
                self.writing = None;
                tracing::error!("the snapshot writer stopped without a result");
                return;
            }
        };
        self.writing = None;
        match result {
            Ok(w) => self.written(&w),
            Err(e) => tracing::error!(error = %e, "snapshot failed; the journal is kept whole"),
        }
    }

    /// Notes a written snapshot and prunes the journal behind the oldest one kept.
    fn written(&mut self, w: &SnapshotWritten) {
        self.observer.snapshotted(w.duration, w.bytes);
        tracing::info!(
            revision = w.revision,
            bytes = w.bytes,
            seconds = w.duration.as_secs_f64(),
            "snapshot written"
        );
        self.prune_to = self
            .prune_to
            .max(w.oldest_kept.saturating_sub(self.policy.keep));
    }

    /// Deletes up to [`PRUNE_STEP`] journal entries no longer needed.
    fn prune_step(&mut self) {
        let Some(first) = self.store.first_revision() else {
            return;
        };
        if first > self.prune_to {
            return;
        }
        let through = self.prune_to.min(first.saturating_add(PRUNE_STEP - 1));
        match self.store.prune_through(through) {
            Ok(_) if through == self.prune_to => {
                tracing::info!(through, "journal pruned behind the snapshots")
            }
            Ok(_) => {}
            Err(e) => {
                tracing::warn!(error = %e, "journal pruning failed; will retry");
            }
        }
    }
}

impl Journal for Durable {
    type Error = StoreError;

    fn append(&mut self, entries: &[Entry<'_>], world: &World) -> Result<(), StoreError> {
        let changes: Vec<Option<String>> = entries
            .iter()
            .map(|e| serde_json::to_string(e.change).ok())
            .collect();
        let batch: Vec<crate::store::Entry<'_>> = entries
            .iter()
            .zip(&changes)
            .map(|(e, c)| crate::store::Entry::new(e.revision, e.edit).with_change(c.as_deref()))
            .collect();
        self.store.append(&batch, world.next_serial())
    }

    fn committed(&mut self, world: &World) {
        self.collect();
        self.prune_step();
        let due = world.revision() >= self.last_snapshot.saturating_add(self.policy.every);
        if !due || self.writing.is_some() {
            return;
        }
        let (tx, rx) = std::sync::mpsc::channel();
        let dir = self.store.dir().to_owned();
        // Copies the parts tree and shares the bodies: later writes copy what they change.
        let world = Arc::new(world.clone());
        self.last_snapshot = world.revision();
        let spawned = std::thread::Builder::new()
            .name("snapshot".into())
            .spawn(move || {
                let _ = tx.send(crate::store::write_snapshot(&dir, &world));
            });
        match spawned {
            Ok(_) => self.writing = Some(rx),
            Err(e) => tracing::error!(error = %e, "cannot start the snapshot writer"),
        }
    }

    fn reload(&mut self) -> Result<World, StoreError> {
        // A background snapshot holds only durable state; let it finish first.
        if let Some(rx) = self.writing.take()
            && let Ok(Ok(w)) = rx.recv()
        {
            self.written(&w);
        }
        Ok(self.store.recover(|_, _, _, _| {})?.world)
    }

    fn checkpoint(&mut self, world: &World) -> Result<Checkpoint, StoreError> {
        if let Some(rx) = self.writing.take()
            && let Ok(Ok(w)) = rx.recv()
        {
            self.written(&w);
        }
        let started = Instant::now();
        let w = self.store.write_snapshot(world)?;
        self.last_snapshot = w.revision;
        self.written(&w);
        Ok(Checkpoint {
            revision: w.revision,
            path: w.path.display().to_string(),
            bytes: w.bytes,
            seconds: started.elapsed().as_secs_f64(),
        })
    }

    fn close(&mut self, world: &World) {
        if let Some(rx) = self.writing.take()
            && let Ok(Ok(w)) = rx.recv()
        {
            self.written(&w);
        }
        if world.revision() > self.last_snapshot {
            // The next start then loads one file instead of replaying the journal.
            match self.store.write_snapshot(world) {
                Ok(w) => self.written(&w),
                Err(e) => {
                    tracing::error!(error = %e, "final snapshot failed; the journal is whole")
                }
            }
        }
    }
}
