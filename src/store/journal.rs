//! The journal: every applied edit, by revision, in `DIR/journal.db` (SQLite, WAL mode).
//!
//! ```sql
//! CREATE TABLE meta(key TEXT PRIMARY KEY, value INTEGER NOT NULL);  -- format_version
//! CREATE TABLE journal(revision INTEGER PRIMARY KEY, edit TEXT NOT NULL, change TEXT);
//! ```
//!
//! `edit` is the JSON of a [`Edit`](crate::edit::Edit), so the journal reads in the `sqlite3` shell:
//! `SELECT revision, edit FROM journal ORDER BY revision DESC LIMIT 10;`. The geometry of
//! an import, a boolean's result and perception's carvings is packed in base64 inside
//! that JSON (see [`crate::edit::command::packed`]).
//!
//! Versions: 1 wrote that geometry as JSON lists; 2 packs it. This build reads both and
//! marks a journal of version 1 as version 2 with its first append, so that an older
//! build refuses it at open instead of failing on a packed entry while it replays.
//!
//! A batch of entries is one transaction (group commit): after [`Journal::append`]
//! returns `Ok` every entry is durable (with [`Durability::Full`]), and if it fails none
//! of them is in the journal.

use std::path::{Path, PathBuf};

use rusqlite::types::ValueRef;
use rusqlite::{Connection, ErrorCode, OpenFlags, OptionalExtension, TransactionBehavior};

use super::entry::Entry;
use super::error::StoreError;
use super::{Durability, StoreOptions};

/// The journal format this build writes and the newest it reads: the tables above, each
/// entry's edit in the serde form of the edit language's version
/// [`crate::edit::command::FORMAT`]. A new form of either is a new version.
pub const FORMAT_VERSION: i64 = 2;
const _: () = assert!(
    FORMAT_VERSION == crate::edit::command::FORMAT as i64,
    "the journal's version names the edits' serde form"
);
/// The journal's file name inside a data directory.
pub const FILE_NAME: &str = "journal.db";
/// Entries deleted per transaction by [`Journal::prune_through`], so that pruning never
/// holds the write lock for long.
const PRUNE_CHUNK: i64 = 10_000;
/// Free pages returned to the file system per transaction after pruning.
const VACUUM_CHUNK: i64 = 4_096;

/// An open journal and what is known of its contents.
pub(crate) struct Journal {
    conn: Connection,
    path: PathBuf,
    /// The smallest revision journaled, if any.
    first: Option<u64>,
    /// The largest revision journaled, if any.
    last: Option<u64>,
    /// The revision the next append must start with, once known (after recovery or
    /// an append).
    next: Option<u64>,
    /// The format version the file declares; raised to [`FORMAT_VERSION`] by the first
    /// append.
    version: i64,
}

impl Journal {
    /// Opens (creating if needed) the journal at `path`.
    ///
    /// Refused when the file is not an SQLite database, is a database of something
    /// else, or declares a newer format than [`FORMAT_VERSION`].
    pub(crate) fn open(path: &Path, options: &StoreOptions) -> Result<Journal, StoreError> {
        let sql = |what| move |e| sqlite_error(path, what, e);
        let conn = Connection::open(path).map_err(sql("opening"))?;
        conn.busy_timeout(options.busy_timeout)
            .map_err(sql("setting the busy timeout"))?;
        // Refuse another program's database before changing any of its settings.
        inspect(&conn, path)?;
        // Takes effect only in a new, empty database: lets pruning give pages back.
        conn.pragma_update(None, "auto_vacuum", "INCREMENTAL")
            .map_err(sql("opening"))?;
        let mode: String = conn
            .query_row("PRAGMA journal_mode=WAL", [], |r| r.get(0))
            .map_err(sql("switching to WAL mode"))?;
        if !mode.eq_ignore_ascii_case("wal") {
            return Err(StoreError::NotAJournal {
                path: path.to_owned(),
                reason: format!("SQLite cannot use WAL mode here (it stays in {mode:?} mode)"),
            });
        }
        let sync = match options.durability {
            Durability::Full => "FULL",
            Durability::Normal => "NORMAL",
        };
        conn.pragma_update(None, "synchronous", sync)
            .map_err(sql("setting synchronous"))?;
        let version = init_schema(&conn, path)?;
        // Two queries: SQLite answers a lone min() or max() from the key's b-tree in
        // O(log n), but scans the whole table for both at once.
        let end = |q| {
            conn.query_row(q, [], |r| r.get::<_, Option<i64>>(0))
                .map_err(sql("reading the journal's extent"))?
                .map(|r| stored_revision(path, r))
                .transpose()
        };
        let first = end("SELECT min(revision) FROM journal")?;
        let last = end("SELECT max(revision) FROM journal")?;
        Ok(Journal {
            conn,
            path: path.to_owned(),
            first,
            last,
            next: last.map(|r| r + 1),
            version,
        })
    }

    /// The database file.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// Entries in the journal: its revisions are consecutive (appends continue the
    /// last one, pruning removes a prefix, and recovery drops a journal that ends
    /// before the snapshot it recovered from), so this is `last − first + 1`.
    pub(crate) fn len(&self) -> u64 {
        match (self.first, self.last) {
            (Some(first), Some(last)) => last.saturating_sub(first) + 1,
            _ => 0,
        }
    }

    /// The smallest revision journaled.
    pub(crate) fn first(&self) -> Option<u64> {
        self.first
    }

    /// The largest revision journaled.
    pub(crate) fn last(&self) -> Option<u64> {
        self.last
    }

    /// Declares the revision the next append must start with (the recovered world's
    /// revision plus one).
    pub(crate) fn expect_next(&mut self, revision: u64) {
        self.next = Some(revision);
    }

    /// Appends `entries` in one transaction, each with the description of what it
    /// changed, if any (stored as given, for [`recent_changes`] to read back after a
    /// restart).
    ///
    /// Preconditions (checked, refused with [`StoreError::OutOfOrder`]): the revisions
    /// are consecutive, the first is the expected next one (see [`Self::expect_next`];
    /// before anything is known, any revision after the journal's last), and no other
    /// process has appended meanwhile. Postcondition on `Ok`: every entry is committed.
    /// On `Err` none is.
    pub(crate) fn append(&mut self, entries: &[Entry<'_>]) -> Result<(), StoreError> {
        let Some(first) = entries.first().map(|e| e.revision) else {
            return Ok(());
        };
        // Bounds every revision below by 2^63, so the sums below cannot overflow.
        key(first)?;
        if let Some(next) = self.next
            && first != next
        {
            return Err(StoreError::OutOfOrder {
                expected: next,
                found: first,
            });
        }
        for (i, r) in entries.iter().map(|e| e.revision).enumerate() {
            let expected = first + i as u64;
            if r != expected {
                return Err(StoreError::OutOfOrder { expected, found: r });
            }
        }
        let last = first + entries.len() as u64 - 1;
        key(last)?;
        let path = &self.path;
        let sql = |what| move |e| sqlite_error(path, what, e);
        let tx = self
            .conn
            .transaction_with_behavior(TransactionBehavior::Immediate)
            .map_err(sql("starting an append"))?;
        let stored_last: Option<i64> = tx
            .query_row("SELECT max(revision) FROM journal", [], |r| r.get(0))
            .map_err(sql("appending"))?;
        if let Some(stored) = stored_last
            && stored >= key(first)?
        {
            // Another writer appended, or the caller repeats revisions.
            return Err(StoreError::OutOfOrder {
                expected: stored as u64 + 1,
                found: first,
            });
        }
        if self.version < FORMAT_VERSION {
            // This build writes entries of its own version from here on.
            tx.execute(
                "UPDATE meta SET value = ?1 WHERE key = 'format_version'",
                [FORMAT_VERSION],
            )
            .map_err(sql("raising the format version"))?;
        }
        {
            let mut insert = tx
                .prepare_cached("INSERT INTO journal(revision, edit, change) VALUES (?1, ?2, ?3)")
                .map_err(sql("appending"))?;
            for &Entry {
                revision,
                edit,
                change,
            } in entries
            {
                let json = serde_json::to_string(edit)
                    .map_err(|source| StoreError::Encode { revision, source })?;
                insert
                    .execute((key(revision)?, json, change))
                    .map_err(sql("appending"))?;
            }
        }
        tx.commit().map_err(sql("committing an append"))?;
        self.version = FORMAT_VERSION;
        self.first = self.first.or(Some(first));
        self.last = Some(last);
        self.next = Some(last + 1);
        Ok(())
    }

    /// Deletes every entry with a revision up to `revision`, [`PRUNE_CHUNK`] entries per
    /// transaction, then returns freed pages to the file system in chunks too. Returns
    /// how many entries were deleted. Precondition: a snapshot at `revision` or later is
    /// durable (else recovery will find a gap).
    pub(crate) fn prune_through(&mut self, revision: u64) -> Result<u64, StoreError> {
        let upto = key(revision.min(i64::MAX as u64))?;
        let sql = |e| sqlite_error(&self.path, "pruning", e);
        let mut deleted = 0u64;
        loop {
            let n = self
                .conn
                .execute(
                    "DELETE FROM journal WHERE revision IN \
                     (SELECT revision FROM journal WHERE revision <= ?1 ORDER BY revision LIMIT ?2)",
                    (upto, PRUNE_CHUNK),
                )
                .map_err(sql)?;
            deleted += n as u64;
            if (n as i64) < PRUNE_CHUNK {
                break;
            }
        }
        loop {
            let free: i64 = self
                .conn
                .query_row("PRAGMA freelist_count", [], |r| r.get(0))
                .map_err(sql)?;
            let vacuumable: i64 = self
                .conn
                .query_row("PRAGMA auto_vacuum", [], |r| r.get(0))
                .map_err(sql)?;
            // 2 is INCREMENTAL; other modes cannot give pages back without VACUUM.
            if free == 0 || vacuumable != 2 {
                break;
            }
            self.conn
                .execute_batch(&format!("PRAGMA incremental_vacuum({VACUUM_CHUNK})"))
                .map_err(sql)?;
            if free <= VACUUM_CHUNK {
                break;
            }
        }
        let first: Option<i64> = self
            .conn
            .query_row("SELECT min(revision) FROM journal", [], |r| r.get(0))
            .map_err(sql)?;
        self.first = first.map(|r| stored_revision(&self.path, r)).transpose()?;
        if self.first.is_none() {
            self.last = None;
        }
        Ok(deleted)
    }

    /// The stored change descriptions of the entries after `after`, oldest first.
    pub(crate) fn recent_changes(&self, after: u64) -> Result<Vec<(u64, String)>, StoreError> {
        let path = &self.path;
        let sql = |what| move |e| sqlite_error(path, what, e);
        let mut stmt = self
            .conn
            .prepare(
                "SELECT revision, change FROM journal \
                 WHERE revision > ?1 AND change IS NOT NULL ORDER BY revision",
            )
            .map_err(sql("reading recent changes"))?;
        let after = key(after.min(i64::MAX as u64))?;
        let rows = stmt
            .query_map([after], |r| {
                Ok((r.get::<_, i64>(0)?, r.get::<_, String>(1)?))
            })
            .map_err(sql("reading recent changes"))?;
        let mut out = Vec::new();
        for row in rows {
            let (stored, change) = row.map_err(sql("reading recent changes"))?;
            out.push((stored_revision(path, stored)?, change));
        }
        Ok(out)
    }

    /// Bytes the journal occupies on disk (the database and its write-ahead log).
    pub(crate) fn bytes(&self) -> u64 {
        let size = |p: &Path| std::fs::metadata(p).map_or(0, |m| m.len());
        let mut wal = self.path.clone().into_os_string();
        wal.push("-wal");
        size(&self.path) + size(Path::new(&wal))
    }
}

/// Reads the journal at `path` through a connection of its own (so it may run on
/// another thread than the journal's owner) and calls `f` with each entry whose revision
/// is greater than `after`, in revision order, with the edit's stored JSON, until `f`
/// returns `false`.
pub(crate) fn read_after(
    path: &Path,
    after: u64,
    mut f: impl FnMut(u64, &[u8]) -> bool,
) -> Result<(), StoreError> {
    let sql = |e| sqlite_error(path, "reading", e);
    // One thread uses this connection: SQLite need not lock it.
    let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX;
    let conn = Connection::open_with_flags(path, flags).map_err(sql)?;
    let mut stmt = conn
        .prepare("SELECT revision, edit FROM journal WHERE revision > ?1 ORDER BY revision")
        .map_err(sql)?;
    let mut rows = stmt.query([key(after)?]).map_err(sql)?;
    while let Some(row) = rows.next().map_err(sql)? {
        let stored: i64 = row.get(0).map_err(sql)?;
        let revision = stored_revision(path, stored)?;
        let bytes = match row.get_ref(1).map_err(sql)? {
            ValueRef::Text(b) | ValueRef::Blob(b) => b,
            other => {
                return Err(StoreError::Decode {
                    path: path.to_owned(),
                    revision: stored,
                    reason: format!("the edit is stored as {:?}, not text", other.data_type()),
                });
            }
        };
        if !f(revision, bytes) {
            break;
        }
    }
    Ok(())
}

/// Checks that the database is empty (`Ok(None)`) or a journal in a format this build
/// reads (`Ok(Some(version))`).
fn inspect(conn: &Connection, path: &Path) -> Result<Option<i64>, StoreError> {
    let sql = |what| move |e| sqlite_error(path, what, e);
    let not_journal = |reason: &str| StoreError::NotAJournal {
        path: path.to_owned(),
        reason: reason.to_owned(),
    };
    let tables: Vec<String> = {
        let mut stmt = conn
            .prepare("SELECT name FROM sqlite_master WHERE type = 'table'")
            .map_err(sql("reading the schema"))?;
        let names = stmt
            .query_map([], |r| r.get(0))
            .map_err(sql("reading the schema"))?;
        names
            .collect::<Result<_, _>>()
            .map_err(sql("reading the schema"))?
    };
    if tables.is_empty() {
        return Ok(None);
    }
    if !tables.iter().any(|t| t == "meta") {
        return Err(not_journal("it has tables but no meta table"));
    }
    let version: Option<i64> = conn
        .query_row(
            "SELECT value FROM meta WHERE key = 'format_version'",
            [],
            |r| r.get(0),
        )
        .optional()
        .map_err(sql("reading the format version"))?;
    match version {
        None => Err(not_journal("its meta table has no format_version")),
        Some(v) if v > FORMAT_VERSION => Err(StoreError::UnsupportedVersion {
            path: path.to_owned(),
            found: v,
            supported: FORMAT_VERSION,
        }),
        Some(v) if v < 1 => Err(not_journal(&format!("format version {v} is not one"))),
        Some(_) if !tables.iter().any(|t| t == "journal") => {
            Err(not_journal("it has no journal table"))
        }
        Some(v) => Ok(Some(v)),
    }
}

/// Creates the tables in an empty database, or checks that an existing one is a
/// journal in a format this build reads, in one write transaction (so two processes
/// creating the same journal do not both create it). Returns the format version the
/// file declares.
fn init_schema(conn: &Connection, path: &Path) -> Result<i64, StoreError> {
    let sql = |what| move |e| sqlite_error(path, what, e);
    conn.execute_batch("BEGIN IMMEDIATE")
        .map_err(sql("opening"))?;
    let result = inspect(conn, path).and_then(|version| {
        if version.is_none() {
            conn.execute_batch(
                "CREATE TABLE meta(key TEXT PRIMARY KEY, value INTEGER NOT NULL);
                 CREATE TABLE journal(revision INTEGER PRIMARY KEY, edit TEXT NOT NULL, change TEXT);",
            )
            .map_err(sql("creating the tables"))?;
            conn.execute(
                "INSERT INTO meta(key, value) VALUES ('format_version', ?1)",
                [FORMAT_VERSION],
            )
            .map_err(sql("creating the tables"))?;
        }
        Ok(version.unwrap_or(FORMAT_VERSION))
    });
    let end = if result.is_ok() { "COMMIT" } else { "ROLLBACK" };
    conn.execute_batch(end).map_err(sql("opening"))?;
    result
}

/// A revision as an SQLite integer key.
fn key(revision: u64) -> Result<i64, StoreError> {
    i64::try_from(revision).map_err(|_| StoreError::RevisionRange { revision })
}

/// A revision read from the journal: never negative in a journal this program wrote.
fn stored_revision(path: &Path, stored: i64) -> Result<u64, StoreError> {
    u64::try_from(stored).map_err(|_| StoreError::Decode {
        path: path.to_owned(),
        revision: stored,
        reason: "a negative revision".to_owned(),
    })
}

/// An SQLite error as a [`StoreError`]; a file that is not a database says so.
fn sqlite_error(path: &Path, what: &'static str, source: rusqlite::Error) -> StoreError {
    if source.sqlite_error_code() == Some(ErrorCode::NotADatabase) {
        return StoreError::NotAJournal {
            path: path.to_owned(),
            reason: "it is not an SQLite database".to_owned(),
        };
    }
    StoreError::Sqlite {
        what,
        path: path.to_owned(),
        source,
    }
}
