//! Recovery: the newest usable snapshot, then the journal replayed on top of it.
//!
//! Decoding the journal's JSON costs about twice as much as applying the edits, so
//! replay is a pipeline: a reader thread pulls batches of rows from SQLite and deals
//! them round-robin to decoder threads; the caller's thread takes the decoded batches
//! back in the same round-robin order, so edits are applied strictly in revision order.
//! Channels are bounded, so memory stays at a few batches per decoder.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::time::{Duration, Instant};

use crate::edit::{Edit, Outcome, apply};
use crate::model::World;

use super::error::StoreError;
use super::journal::{self, Journal};
use super::snapshot;

/// Progress is logged every this many replayed entries.
const PROGRESS_EVERY: u64 = 100_000;
/// Journal rows per batch handed between the pipeline's threads.
const BATCH: usize = 512;
/// Batches that may wait in each channel of the pipeline.
const QUEUED: usize = 4;
/// The most decoder threads recovery starts.
const MAX_DECODERS: usize = 4;

/// The world rebuilt by [`Store::recover`](super::Store::recover), and how.
#[derive(Debug)]
pub struct Recovered {
    /// The world as of the last journaled revision.
    pub world: World,
    /// The revision of the snapshot recovery started from (`None`: an empty world).
    pub snapshot: Option<u64>,
    /// The snapshot file it started from.
    pub snapshot_path: Option<PathBuf>,
    /// Newer snapshot files that failed their checks and were passed over.
    pub skipped_snapshots: usize,
    /// Journal entries replayed on top of the snapshot.
    pub replayed: u64,
    /// Time taken, loading the snapshot included.
    pub elapsed: Duration,
    /// A newer snapshot that could not be read, and its revision, when it proves the
    /// world reached further than it recovered to (only with `accept_loss`; otherwise
    /// recovery is refused).
    pub unreadable_newer: Option<(PathBuf, u64)>,
    /// The revisions from and to which the world was moved on, when acknowledged writes
    /// were missing and the loss was accepted.
    pub accepted_loss: Option<(u64, u64)>,
}

/// Loads the newest usable snapshot in `dir` (or starts from [`World::new`]) and
/// replays every entry of `journal` after its revision, in order, calling `on_applied`
/// after each.
///
/// Refused with [`StoreError::Gap`] when the entries after the snapshot do not start
/// right after it or skip a revision, [`StoreError::Refused`] when an entry is refused,
/// [`StoreError::Diverged`] when an entry does not leave the world at its own revision,
/// [`StoreError::Decode`] for an unreadable entry, and [`StoreError::Unrecoverable`]
/// when an unreadable newer snapshot held revisions nothing else reaches (with
/// `accept_loss`, that snapshot is named in [`Recovered::unreadable_newer`] instead). On
/// success the journal expects the recovered world's revision plus one next.
pub(crate) fn recover(
    dir: &Path,
    journal: &mut Journal,
    accept_loss: bool,
    mut on_applied: impl FnMut(u64, &Edit, &Outcome, &World),
) -> Result<Recovered, StoreError> {
    let started = Instant::now();
    let (loaded, skipped) = snapshot::load_newest(dir)?;
    let (mut world, snapshot_path) = match loaded {
        Some(l) => (l.world, Some(l.path)),
        None => (World::new(), None),
    };
    let snapshot = snapshot_path.as_ref().map(|_| world.revision());
    let from = world.revision();
    if let Some(path) = &snapshot_path {
        tracing::info!(
            revision = from,
            path = %path.display(),
            seconds = started.elapsed().as_secs_f64(),
            "snapshot loaded"
        );
    }
    let mut replayed = 0u64;
    let path = journal.path().to_owned();
    let decoders = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .clamp(1, MAX_DECODERS);
    replay(&path, from, decoders, |revision, edit| {
        let expected = world.revision() + 1;
        if revision != expected {
            return Err(StoreError::Gap {
                path: path.clone(),
                snapshot,
                expected,
                found: revision,
                skipped_snapshots: skipped.len(),
            });
        }
        let edit = edit.map_err(|reason| StoreError::Decode {
            path: path.clone(),
            revision: revision as i64,
            reason,
        })?;
        let outcome =
            apply(&mut world, &edit).map_err(|source| StoreError::Refused { revision, source })?;
        if world.revision() + 1 == revision && matches!(edit, Edit::PatchBody { .. }) {
            // A patch that changed nothing, journaled by an earlier version that counted
            // it as a revision: it keeps its revision, so the entries after it line up.
            world.resume_at(revision, world.next_serial());
        }
        if world.revision() != revision {
            return Err(StoreError::Diverged {
                revision,
                world: world.revision(),
            });
        }
        on_applied(revision, &edit, &outcome, &world);
        replayed += 1;
        if replayed.is_multiple_of(PROGRESS_EVERY) {
            tracing::info!(
                replayed,
                revision,
                seconds = started.elapsed().as_secs_f64(),
                "replaying the journal"
            );
        }
        Ok(())
    })?;
    // A newer snapshot that could not be read still proves the world reached its
    // revision: stopping short of it would silently lose writes.
    let mut unreadable_newer = None;
    if let Some(newest) = skipped.first()
        && newest.revision > world.revision()
    {
        if !accept_loss {
            return Err(StoreError::Unrecoverable {
                snapshot: newest.path.clone(),
                newest: newest.revision,
                recovered: world.revision(),
            });
        }
        unreadable_newer = Some((newest.path.clone(), newest.revision));
    }
    // A journal that ends before the snapshot lags behind it (its last appends were
    // lost, or never made, while the snapshot was written): what it holds is older than
    // the world and cannot reach it from an older snapshot either. Dropping it keeps
    // the journal's revisions consecutive when appends continue from the world.
    if let Some(last) = journal.last()
        && last < world.revision()
    {
        tracing::warn!(
            journal_last = last,
            revision = world.revision(),
            "the journal ends before the snapshot; dropping its older entries"
        );
        journal.prune_through(world.revision())?;
    }
    let elapsed = started.elapsed();
    tracing::info!(
        revision = world.revision(),
        snapshot,
        replayed,
        seconds = elapsed.as_secs_f64(),
        "world recovered"
    );
    journal.expect_next(world.revision() + 1);
    Ok(Recovered {
        world,
        snapshot,
        snapshot_path,
        skipped_snapshots: skipped.len(),
        replayed,
        elapsed,
        unreadable_newer,
        accepted_loss: None,
    })
}

/// Rows as read: each revision with the end of its JSON in one shared buffer.
#[derive(Default)]
struct Rows {
    revisions: Vec<(u64, usize)>,
    bytes: Vec<u8>,
}

/// A batch of rows, or the error that stopped the reader.
type Raw = Result<Rows, StoreError>;
/// Rows decoded: revision and the edit, or why it does not decode.
type Decoded = Vec<(u64, Result<Edit, String>)>;
/// What a decoder hands back: a decoded batch, or the reader's error passed along.
type Cooked = Result<Decoded, StoreError>;

/// Reads the journal at `path` after revision `from` and calls `each` with every entry
/// in revision order, decoding on `decoders` threads. Stops at the first error, from
/// reading or from `each`; all threads have ended when it returns.
fn replay(
    path: &Path,
    from: u64,
    decoders: usize,
    mut each: impl FnMut(u64, Result<Edit, String>) -> Result<(), StoreError>,
) -> Result<(), StoreError> {
    std::thread::scope(|scope| {
        let (raw_tx, raw_rx): (Vec<SyncSender<Raw>>, Vec<Receiver<Raw>>) =
            (0..decoders).map(|_| sync_channel(QUEUED)).unzip();
        let (out_tx, out_rx): (Vec<SyncSender<Cooked>>, Vec<Receiver<Cooked>>) =
            (0..decoders).map(|_| sync_channel(QUEUED)).unzip();
        scope.spawn(move || read_batches(path, from, raw_tx));
        for (rx, tx) in raw_rx.into_iter().zip(out_tx) {
            scope.spawn(move || decode_batches(rx, tx));
        }
        // Batch k went to decoder k mod n, so taking them back in that order restores
        // revision order; the first decoder found finished means every batch is in.
        for k in (0..decoders).cycle() {
            let Ok(batch) = out_rx[k].recv() else {
                return Ok(());
            };
            for (revision, edit) in batch? {
                each(revision, edit)?;
            }
        }
        Ok(())
        // Returning drops the receivers, which stops the other threads.
    })
}

/// The reader thread: sends batches of rows round-robin to `to`, or the error that
/// stopped it. Ends early when a receiver is gone (the replay stopped).
fn read_batches(path: &Path, from: u64, to: Vec<SyncSender<Raw>>) {
    let mut batch = Rows::default();
    let mut k = 0;
    let mut gone = false;
    let result = journal::read_after(path, from, |revision, bytes| {
        batch.bytes.extend_from_slice(bytes);
        batch.revisions.push((revision, batch.bytes.len()));
        if batch.revisions.len() == BATCH {
            gone = to[k].send(Ok(std::mem::take(&mut batch))).is_err();
            k = (k + 1) % to.len();
        }
        !gone
    });
    if gone {
        return;
    }
    let last = match result {
        Ok(()) if batch.revisions.is_empty() => return,
        Ok(()) => Ok(batch),
        Err(e) => Err(e),
    };
    let _ = to[k].send(last);
}

/// A decoder thread: decodes each batch from `from` and sends it on to `to`, in the
/// order received.
fn decode_batches(from: Receiver<Raw>, to: SyncSender<Cooked>) {
    for raw in from {
        let decoded = raw.map(|rows| {
            let mut start = 0;
            rows.revisions
                .iter()
                .map(|&(revision, end)| {
                    let json = &rows.bytes[start..end];
                    start = end;
                    (
                        revision,
                        serde_json::from_slice(json).map_err(|e| e.to_string()),
                    )
                })
                .collect()
        });
        if to.send(decoded).is_err() {
            return;
        }
    }
}
