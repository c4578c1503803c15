//! Why a store operation failed.

use std::path::PathBuf;

use crate::edit::EditError;

/// A store operation that failed. Each variant names the file involved, so the message
/// alone tells an operator where to look (a full disk, a permission, a damaged file).
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// A file-system operation failed (disk full, permission denied, missing directory).
    #[error("{what} {}: {source}", path.display())]
    Io {
        /// What was being done ("writing snapshot", "creating directory", ...).
        what: &'static str,
        /// The file or directory.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// Another process (another server, or `winged check`) has the data directory open.
    #[error(
        "{} is in use by another process (a running server?); stop it first",
        dir.display()
    )]
    InUse {
        /// The data directory.
        dir: PathBuf,
    },
    /// SQLite refused an operation on the journal (disk full, locked, damaged file).
    #[error("journal {}: {what}: {source}", path.display())]
    Sqlite {
        /// What was being done ("appending", "opening", ...).
        what: &'static str,
        /// The journal database.
        path: PathBuf,
        /// SQLite's error.
        #[source]
        source: rusqlite::Error,
    },
    /// The journal was written by a newer version of this software.
    #[error(
        "journal {}: format version {found} is newer than this program reads (up to {supported}); \
         upgrade the program, or restore from a snapshot into an empty data directory",
        path.display()
    )]
    UnsupportedVersion {
        /// The journal database.
        path: PathBuf,
        /// The version the file declares.
        found: i64,
        /// The newest version this build reads.
        supported: i64,
    },
    /// The file at the journal's place is not a journal of this program.
    #[error("{}: not a winged journal: {reason}", path.display())]
    NotAJournal {
        /// The file.
        path: PathBuf,
        /// What gave it away.
        reason: String,
    },
    /// A journal entry could not be encoded (an edit with a number JSON cannot hold).
    #[error("revision {revision}: the edit cannot be encoded: {source}")]
    Encode {
        /// The entry's revision.
        revision: u64,
        /// The encoder's error.
        #[source]
        source: serde_json::Error,
    },
    /// A journal entry could not be decoded: the journal is damaged.
    #[error("journal {}: revision {revision} is not a readable edit: {reason}", path.display())]
    Decode {
        /// The journal database.
        path: PathBuf,
        /// The entry's revision as stored.
        revision: i64,
        /// What is wrong with it.
        reason: String,
    },
    /// A revision beyond what the journal's integer keys hold (2^63 − 1).
    #[error("revision {revision} is too large for the journal")]
    RevisionRange {
        /// The revision given.
        revision: u64,
    },
    /// A batch given to [`Store::append`](super::Store::append) does not continue the
    /// journal: its revisions must be consecutive and follow the last one journaled.
    #[error("journal append: expected revision {expected}, got {found}")]
    OutOfOrder {
        /// The revision that would continue the journal.
        expected: u64,
        /// The revision given.
        found: u64,
    },
    /// Revisions are missing between the snapshot recovery starts from and the journal,
    /// or inside the journal: replaying across the hole would build a wrong world.
    #[error(
        "journal {}: revision {expected} is missing (next journaled revision: {found}); \
         recovery started from {}",
        path.display(),
        start_of(*.snapshot, *.skipped_snapshots)
    )]
    Gap {
        /// The journal database.
        path: PathBuf,
        /// The snapshot revision recovery started from, if any.
        snapshot: Option<u64>,
        /// The revision that should have come next.
        expected: u64,
        /// The revision that came instead.
        found: u64,
        /// Snapshots that failed their checks and were passed over.
        skipped_snapshots: usize,
    },
    /// The directory recovers to an older revision than it once acknowledged: writes
    /// that clients were told are durable are missing (a lost or damaged write-ahead log,
    /// a journal or snapshot restored from an older copy).
    #[error(
        "{} recovers to revision {recovered}, but revision {reached} was acknowledged \
         (recorded in {}): {} acknowledged write(s) are missing, probably with a lost or \
         damaged write-ahead log (journal.db-wal). Put the missing files back if you can; \
         or start with --accept-loss to continue from revision {recovered} (the world \
         then resumes at revision {reached}, and no acknowledged id is issued again)",
        dir.display(),
        evidence.display(),
        reached - recovered
    )]
    Behind {
        /// The data directory.
        dir: PathBuf,
        /// The revision the journal and snapshots recover to.
        recovered: u64,
        /// The highest revision known to have been acknowledged.
        reached: u64,
        /// The file that records it (the reached marker, or an unreadable snapshot).
        evidence: PathBuf,
    },
    /// A snapshot was not written because the world, or the file written for it, failed
    /// the checks a snapshot is loaded with; the older snapshots are kept.
    #[error("the snapshot at revision {revision} was not written: {reason}")]
    SnapshotRefused {
        /// The world's revision.
        revision: u64,
        /// The check that failed.
        reason: String,
    },
    /// The reached marker is damaged in both its slots, so whether writes are missing
    /// cannot be told.
    #[error(
        "the reached marker {} is damaged, so it cannot be told whether acknowledged \
         writes are missing; start with --accept-loss to continue from what the journal \
         and snapshots hold",
        path.display()
    )]
    MarkerDamaged {
        /// The marker file.
        path: PathBuf,
    },
    /// The newest snapshot is unreadable and neither an older snapshot nor the journal
    /// reaches its revision: the writes between cannot be recovered from this directory.
    #[error(
        "snapshot {} (revision {newest}) is unreadable, and the older snapshots and the \
         journal reach only revision {recovered}; restore that snapshot from a backup",
        snapshot.display()
    )]
    Unrecoverable {
        /// The unreadable snapshot.
        snapshot: PathBuf,
        /// Its revision.
        newest: u64,
        /// The revision the rest of the directory reaches.
        recovered: u64,
    },
    /// Pruning the journal past the newest snapshot would delete the only record of
    /// some writes.
    #[error(
        "cannot prune the journal through revision {revision}: the newest snapshot is at {}",
        match .newest { Some(r) => r.to_string(), None => "none".to_owned() }
    )]
    PruneBeyondSnapshot {
        /// The revision asked for.
        revision: u64,
        /// The newest snapshot's revision, if any.
        newest: Option<u64>,
    },
    /// A journaled edit was refused on replay: the journal does not describe a world
    /// this program can rebuild.
    #[error("replaying revision {revision}: the edit was refused: {source}")]
    Refused {
        /// The entry's revision.
        revision: u64,
        /// Why it was refused.
        #[source]
        source: EditError,
    },
    /// After replaying an entry the world's revision is not the entry's revision.
    #[error("replay diverged: after applying revision {revision} the world is at revision {world}")]
    Diverged {
        /// The entry's revision.
        revision: u64,
        /// The world's revision after applying it.
        world: u64,
    },
}

impl StoreError {
    /// A file-system error on `path` while doing `what`.
    pub(crate) fn io(what: &'static str, path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        StoreError::Io {
            what,
            path: path.into(),
            source,
        }
    }
}

/// Where recovery started, for [`StoreError::Gap`]'s message.
fn start_of(snapshot: Option<u64>, skipped: usize) -> String {
    let from = match snapshot {
        Some(r) => format!("the snapshot at revision {r}"),
        None => "an empty world (no usable snapshot)".to_owned(),
    };
    if skipped > 0 {
        format!("{from}, after passing over {skipped} unreadable snapshot(s)")
    } else {
        from
    }
}
