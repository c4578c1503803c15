//! Durability for the world: a journal of applied edits plus snapshots, in one data
//! directory.
//!
//! ```text
//! DIR/journal.db                 SQLite (WAL): every applied edit by revision, as JSON
//! DIR/reached                    the highest acknowledged revision and serial (marker)
//! DIR/snapshots/000000001234.snap  the whole world at revision 1234 (the newest two kept)
//! ```
//!
//! The world's owner appends each batch of applied edits with [`Store::append`] before
//! it answers the writers (one transaction per batch: group commit). From time to time,
//! on any thread, it writes a [`write_snapshot`] of a cloned world and then calls
//! [`Store::prune_through`] with the [`SnapshotWritten::oldest_kept`] revision. On
//! start, [`Store::recover`] loads the newest snapshot that passes its checks and
//! replays the journal entries after it through [`apply`](fn@crate::edit::apply),
//! which rebuilds the same world with the same ids because every serial comes from the
//! world's own counter.
//!
//! Everything read from disk is checked (snapshot checksums, the decoded world's
//! invariants, the journal's format version, each entry's revision): damage gives a
//! [`StoreError`] or, for a snapshot with an older one to fall back to, a warning, never
//! a panic or a silently different world. A directory that recovers to less than it
//! once acknowledged (see [`marker`]) is refused unless the operator accepts the loss
//! ([`StoreOptions::accept_loss`]).
//!
//! A snapshot file alone is a complete backup: copy the newest file in `snapshots/`;
//! to restore, put it into the `snapshots/` directory of an empty data directory.

mod entry;
mod error;
mod journal;
pub mod marker;
mod recover;
pub mod snapshot;

use std::path::{Path, PathBuf};
use std::time::Duration;

pub use entry::Entry;
pub use error::StoreError;
pub use recover::Recovered;
pub use snapshot::{
    SnapshotError, SnapshotFile, SnapshotWritten, check_world, read_snapshot, write_snapshot,
};

use crate::edit::{Edit, Outcome};
use crate::model::{Serial, World};
use journal::Journal;
use marker::{Found, Marker, Reached};

/// How hard an append works to survive a power loss.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Durability {
    /// Every append is on disk when it returns (SQLite `synchronous=FULL`).
    #[default]
    Full,
    /// Appends are safe from a crash of the process but the last few may be lost on a
    /// power loss or an operating system crash (SQLite `synchronous=NORMAL` in WAL
    /// mode). The journal stays consistent either way.
    Normal,
}

/// How to open a [`Store`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StoreOptions {
    /// What an append guarantees.
    pub durability: Durability,
    /// How long an operation waits for another connection's lock on the journal (a
    /// `sqlite3` shell reading it, say) before it fails.
    pub busy_timeout: Duration,
    /// Start even when the directory recovers to less than it once acknowledged (see
    /// [`StoreError::Behind`]): the world resumes at the acknowledged revision and
    /// serial, so no revision or id is issued twice, and the loss is logged.
    pub accept_loss: bool,
}

impl Default for StoreOptions {
    fn default() -> Self {
        StoreOptions {
            durability: Durability::Full,
            busy_timeout: Duration::from_secs(5),
            accept_loss: false,
        }
    }
}

/// A data directory: the journal, open, and the snapshot files. Used by the world's
/// owner on its own thread (all calls are synchronous); snapshots may be written from
/// any thread with [`write_snapshot`].
pub struct Store {
    dir: PathBuf,
    journal: Journal,
    /// `DIR/reached`: how far the journal was ever acknowledged.
    marker: Marker,
    /// What the marker held when the store was opened.
    found: Found,
    options: StoreOptions,
    /// `DIR/lock`, held exclusively while the store is open: one process per directory.
    _lock: std::fs::File,
}

/// The lock file in a data directory.
const LOCK_FILE: &str = "lock";

impl Store {
    /// Opens the data directory `dir`, creating it, its journal and its `snapshots/`
    /// directory as needed, takes its lock (one process per directory, released when
    /// the store is dropped or the process dies), and removes temporary files of
    /// snapshot writes that never finished.
    ///
    /// Refused when another process holds the directory ([`StoreError::InUse`]), a
    /// directory cannot be created, the journal cannot be opened
    /// (permission, not an SQLite database, not a journal) or declares a newer format
    /// ([`StoreError::UnsupportedVersion`]).
    pub fn open(dir: &Path, options: StoreOptions) -> Result<Store, StoreError> {
        std::fs::create_dir_all(dir)
            .map_err(|e| StoreError::io("creating data directory", dir, e))?;
        let snaps = snapshot::snapshots_dir(dir);
        std::fs::create_dir_all(&snaps)
            .map_err(|e| StoreError::io("creating snapshot directory", &snaps, e))?;
        let lock_path = dir.join(LOCK_FILE);
        let lock = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&lock_path)
            .map_err(|e| StoreError::io("opening lock file", &lock_path, e))?;
        match lock.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                return Err(StoreError::InUse {
                    dir: dir.to_owned(),
                });
            }
            Err(std::fs::TryLockError::Error(e)) => {
                return Err(StoreError::io("locking", &lock_path, e));
            }
        }
        snapshot::remove_stale_temps(dir)?;
        let journal = Journal::open(&dir.join(journal::FILE_NAME), &options)?;
        let (marker, found) = Marker::open(dir, options.durability)?;
        Ok(Store {
            dir: dir.to_owned(),
            journal,
            marker,
            found,
            options,
            _lock: lock,
        })
    }

    /// The data directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The journal's database file.
    pub fn journal_path(&self) -> &Path {
        self.journal.path()
    }

    /// Whether the directory holds nothing yet: no snapshot file and no journal entry.
    /// A server seeds a fresh directory by writing a snapshot of its starting world.
    pub fn is_fresh(&self) -> Result<bool, StoreError> {
        Ok(self.journal.len() == 0 && snapshot::list(&self.dir)?.is_empty())
    }

    /// Journals `entries` in ONE transaction (group commit), then records in the reached
    /// marker that the journal reached the last entry's revision with `next_serial` as
    /// the world's next serial.
    ///
    /// Preconditions, checked ([`StoreError::OutOfOrder`]): the revisions are
    /// consecutive and continue the journal (after [`Store::recover`], the first is the
    /// recovered world's revision plus one). Postcondition on `Ok`: every entry is
    /// committed and the marker written, durably with [`Durability::Full`]. On `Err`
    /// (disk full, say) before the commit none of the batch is in the journal, and the
    /// same batch may be retried; an `Err` from the marker leaves the batch committed.
    /// An entry's change description is kept as given, and [`Store::recent_changes`]
    /// reads it back after a restart.
    pub fn append(&mut self, entries: &[Entry<'_>], next_serial: Serial) -> Result<(), StoreError> {
        self.journal.append(entries)?;
        self.mark(entries.last().map(|e| e.revision), next_serial)
    }

    /// Records a committed revision in the marker.
    fn mark(&mut self, revision: Option<u64>, next_serial: Serial) -> Result<(), StoreError> {
        match revision {
            Some(revision) => self.marker.record(Reached {
                revision,
                next_serial: next_serial.0,
            }),
            None => Ok(()),
        }
    }

    /// The change descriptions stored with the journal entries after `revision`, oldest
    /// first (entries appended without one are left out).
    pub fn recent_changes(&self, revision: u64) -> Result<Vec<(u64, String)>, StoreError> {
        self.journal.recent_changes(revision)
    }

    /// Rebuilds the world: loads the newest snapshot that passes its checks (passing
    /// over damaged newer ones with a warning), or starts from [`World::new`] if there
    /// is none, then replays every journal entry after the snapshot's revision, in
    /// order, calling `on_applied(revision, edit, outcome, world)` after each (so the
    /// caller can rebuild its change history). Logs progress every 100,000 entries and
    /// a final line with the entries replayed and the seconds taken.
    ///
    /// Refused, rather than yielding a different world, when the journal does not
    /// continue the snapshot or has a hole ([`StoreError::Gap`]), an entry is unreadable
    /// ([`StoreError::Decode`]), refused ([`StoreError::Refused`]) or lands on another
    /// revision ([`StoreError::Diverged`]). Refused, rather than yielding an older world,
    /// when a damaged newer snapshot held revisions nothing else reaches
    /// ([`StoreError::Unrecoverable`]), the reached marker records a later revision
    /// ([`StoreError::Behind`]) or is damaged ([`StoreError::MarkerDamaged`]): unless
    /// [`StoreOptions::accept_loss`] is set, in which case the world resumes at the
    /// highest revision and serial known to have been acknowledged (the loss is logged,
    /// a verified snapshot written there and the journal behind it emptied), so that no
    /// revision or id is ever issued twice. After `Ok`, appends continue from the
    /// recovered world's revision.
    pub fn recover(
        &mut self,
        on_applied: impl FnMut(u64, &Edit, &Outcome, &World),
    ) -> Result<Recovered, StoreError> {
        let mut recovered = recover::recover(
            &self.dir,
            &mut self.journal,
            self.options.accept_loss,
            on_applied,
        )?;
        self.check_reached(&mut recovered)?;
        Ok(recovered)
    }

    /// Compares the recovered world with what was acknowledged (the marker, an
    /// unreadable newer snapshot) and refuses, or with `accept_loss` resumes past it.
    fn check_reached(&mut self, recovered: &mut Recovered) -> Result<(), StoreError> {
        let marker_path = self.marker.path().to_owned();
        let mut reached = Reached {
            revision: 0,
            next_serial: 0,
        };
        let mut evidence = marker_path.clone();
        match self.found {
            Found::Absent => {}
            Found::Reached(r) => reached = r,
            Found::Damaged if self.options.accept_loss => tracing::warn!(
                marker = %marker_path.display(),
                "the reached marker is damaged; continuing from what the journal and snapshots hold (--accept-loss)"
            ),
            Found::Damaged => return Err(StoreError::MarkerDamaged { path: marker_path }),
        }
        if let Some((path, revision)) = &recovered.unreadable_newer
            && *revision > reached.revision
        {
            reached.revision = *revision;
            evidence = path.clone();
        }
        let world = &mut recovered.world;
        let behind = world.revision() < reached.revision;
        if !behind && world.next_serial().0 >= reached.next_serial {
            return Ok(());
        }
        if !self.options.accept_loss {
            return Err(StoreError::Behind {
                dir: self.dir.clone(),
                recovered: world.revision(),
                reached: reached.revision,
                evidence,
            });
        }
        let from = world.revision();
        world.resume_at(reached.revision, Serial(reached.next_serial));
        tracing::warn!(
            recovered = from,
            reached = reached.revision,
            lost = reached.revision.saturating_sub(from),
            next_serial = world.next_serial().0,
            evidence = %evidence.display(),
            "acknowledged writes are missing; resuming at the acknowledged revision (--accept-loss)"
        );
        // The jump must survive the next start: a verified snapshot at the new revision
        // (with the raised serial counter), then the journal behind it emptied.
        let written = self.write_snapshot(world)?;
        self.journal.prune_through(world.revision())?;
        self.journal.expect_next(world.revision() + 1);
        self.marker.record(Reached {
            revision: world.revision(),
            next_serial: world.next_serial().0,
        })?;
        recovered.snapshot = Some(written.revision);
        recovered.snapshot_path = Some(written.path);
        recovered.accepted_loss = Some((from, world.revision()));
        Ok(())
    }

    /// Writes a snapshot of `world` into this data directory: [`write_snapshot`].
    pub fn write_snapshot(&self, world: &World) -> Result<SnapshotWritten, StoreError> {
        write_snapshot(&self.dir, world)
    }

    /// Deletes the journal entries with revisions up to `revision`, in bounded chunks
    /// (each its own short transaction), and returns how many were deleted.
    ///
    /// Refused ([`StoreError::PruneBeyondSnapshot`]) unless a snapshot file at
    /// `revision` or later is in the directory, so the entries deleted are never the
    /// only record of a write. Pruning through [`SnapshotWritten::oldest_kept`] keeps
    /// the directory recoverable even if the newest snapshot is later found damaged.
    pub fn prune_through(&mut self, revision: u64) -> Result<u64, StoreError> {
        let newest = snapshot::list(&self.dir)?.last().map(|s| s.revision);
        if newest.is_none_or(|n| n < revision) {
            return Err(StoreError::PruneBeyondSnapshot { revision, newest });
        }
        self.journal.prune_through(revision)
    }

    /// Entries in the journal.
    pub fn journal_len(&self) -> u64 {
        self.journal.len()
    }

    /// The oldest revision in the journal.
    pub fn first_revision(&self) -> Option<u64> {
        self.journal.first()
    }

    /// The newest revision in the journal.
    pub fn last_revision(&self) -> Option<u64> {
        self.journal.last()
    }

    /// Bytes the journal occupies on disk (database and write-ahead log).
    pub fn journal_bytes(&self) -> u64 {
        self.journal.bytes()
    }

    /// The snapshot files in the data directory, oldest first.
    pub fn snapshots(&self) -> Result<Vec<SnapshotFile>, StoreError> {
        snapshot::list(&self.dir)
    }
}
