//! The reached marker: `DIR/reached`, how far the journal has ever been acknowledged.
//!
//! SQLite keeps the newest commits in its write-ahead log (`journal.db-wal`) until a
//! checkpoint folds them into `journal.db`. A lost or damaged WAL therefore takes the
//! last acknowledged writes with it, and the journal that is left is a consistent,
//! older one: nothing in it says that writes are missing. The marker does. After every
//! committed group, before the writers are answered, the store records the revision
//! the journal reached and the world's next serial here; on start, a journal that
//! recovers to less is refused (see [`super::Store::recover`]).
//!
//! The file holds two slots of [`SLOT_LEN`] bytes, written in turn, so a write torn by a
//! crash leaves the other slot whole:
//!
//! | bytes | field |
//! |---|---|
//! | 8 | magic `WREACHED` |
//! | 8 | revision, little-endian `u64` |
//! | 8 | next serial, little-endian `u64` |
//! | 4 | CRC-32 of the 24 bytes before it, little-endian |
//! | 4 | zero |
//!
//! The valid slot with the higher revision counts. With [`Durability::Full`] each
//! record is flushed to disk (`fdatasync`) before it returns; with
//! [`Durability::Normal`] it is left to the operating system, like the journal's own
//! commits.

use std::fs::{File, OpenOptions};
use std::io::Read;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use super::Durability;
use super::error::StoreError;

/// The marker's file name inside a data directory.
pub const FILE_NAME: &str = "reached";
/// The first bytes of a valid slot.
const MAGIC: [u8; 8] = *b"WREACHED";
/// Bytes per slot.
pub const SLOT_LEN: usize = 32;
/// Bytes of a slot covered by its checksum.
const CHECKED: usize = 24;

/// How far the journal was acknowledged: a revision and the world's next serial then.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Reached {
    /// The highest acknowledged revision.
    pub revision: u64,
    /// The serial the next new entity would have taken at that revision.
    pub next_serial: u64,
}

/// What reading the marker found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Found {
    /// No marker file, or an empty one (a directory from before markers, or one whose
    /// journal never committed a write).
    Absent,
    /// The newest valid record.
    Reached(Reached),
    /// A marker file whose slots are all damaged.
    Damaged,
}

/// The open marker file.
#[derive(Debug)]
pub struct Marker {
    file: File,
    path: PathBuf,
    /// The slot the next record goes to: the one not holding the newest record.
    next_slot: u64,
    durability: Durability,
}

impl Marker {
    /// Opens (creating if needed) the marker of data directory `dir` and reads it.
    pub fn open(dir: &Path, durability: Durability) -> Result<(Marker, Found), StoreError> {
        let path = dir.join(FILE_NAME);
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| StoreError::io("opening the reached marker", &path, e))?;
        let mut bytes = Vec::with_capacity(2 * SLOT_LEN);
        (&mut file)
            .take(2 * SLOT_LEN as u64)
            .read_to_end(&mut bytes)
            .map_err(|e| StoreError::io("reading the reached marker", &path, e))?;
        let (found, newest_slot) = parse(&bytes);
        let marker = Marker {
            file,
            path,
            next_slot: newest_slot.map_or(0, |s| 1 - s),
            durability,
        };
        Ok((marker, found))
    }

    /// The marker file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Records `reached` in the older slot (flushed with [`Durability::Full`]).
    /// Postcondition on `Ok`: a later [`Marker::open`] finds `reached` or a later record.
    pub fn record(&mut self, reached: Reached) -> Result<(), StoreError> {
        let slot = encode(reached);
        self.file
            .write_all_at(&slot, self.next_slot * SLOT_LEN as u64)
            .map_err(|e| StoreError::io("writing the reached marker", &self.path, e))?;
        if self.durability == Durability::Full {
            self.file
                .sync_data()
                .map_err(|e| StoreError::io("flushing the reached marker", &self.path, e))?;
        }
        self.next_slot = 1 - self.next_slot;
        Ok(())
    }
}

/// One slot's bytes for `r`.
fn encode(r: Reached) -> [u8; SLOT_LEN] {
    let mut s = [0u8; SLOT_LEN];
    s[..8].copy_from_slice(&MAGIC);
    s[8..16].copy_from_slice(&r.revision.to_le_bytes());
    s[16..24].copy_from_slice(&r.next_serial.to_le_bytes());
    let crc = crc32fast::hash(&s[..CHECKED]);
    s[CHECKED..CHECKED + 4].copy_from_slice(&crc.to_le_bytes());
    s
}

/// The record of one slot, if it is whole.
fn decode(s: &[u8]) -> Option<Reached> {
    if s.len() != SLOT_LEN || s[..8] != MAGIC {
        return None;
    }
    let word = |i: usize| u64::from_le_bytes(s[i..i + 8].try_into().unwrap_or([0; 8]));
    let crc = u32::from_le_bytes(s[CHECKED..CHECKED + 4].try_into().unwrap_or([0; 4]));
    (crc == crc32fast::hash(&s[..CHECKED])).then(|| Reached {
        revision: word(8),
        next_serial: word(16),
    })
}

/// The newest record in a marker file's bytes, and its slot.
fn parse(bytes: &[u8]) -> (Found, Option<u64>) {
    if bytes.iter().all(|&b| b == 0) {
        // Empty, or created and never written (a crash between the two).
        return (Found::Absent, None);
    }
    let newest = bytes
        .chunks(SLOT_LEN)
        .take(2)
        .enumerate()
        .filter_map(|(i, s)| decode(s).map(|r| (i as u64, r)))
        .max_by_key(|(_, r)| r.revision);
    match newest {
        Some((slot, r)) => (Found::Reached(r), Some(slot)),
        None => (Found::Damaged, None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reached(revision: u64) -> Reached {
        Reached {
            revision,
            next_serial: revision * 10,
        }
    }

    #[test]
    fn records_alternate_slots_and_the_newest_wins() {
        let dir = tempfile::tempdir().unwrap();
        let (mut m, found) = Marker::open(dir.path(), Durability::Normal).unwrap();
        assert_eq!(found, Found::Absent);
        for r in 1..=5 {
            m.record(reached(r)).unwrap();
        }
        drop(m);
        let (_, found) = Marker::open(dir.path(), Durability::Normal).unwrap();
        assert_eq!(found, Found::Reached(reached(5)));
    }

    #[test]
    fn a_torn_slot_leaves_the_other_one() {
        let dir = tempfile::tempdir().unwrap();
        let (mut m, _) = Marker::open(dir.path(), Durability::Normal).unwrap();
        m.record(reached(7)).unwrap();
        m.record(reached(8)).unwrap();
        drop(m);
        let path = dir.path().join(FILE_NAME);
        let mut bytes = std::fs::read(&path).unwrap();
        // Slot 1 holds revision 8: damage it.
        bytes[SLOT_LEN + 9] ^= 0xff;
        std::fs::write(&path, &bytes).unwrap();
        let (mut m, found) = Marker::open(dir.path(), Durability::Normal).unwrap();
        assert_eq!(found, Found::Reached(reached(7)));
        // The next record goes over the damaged slot, not over the good one.
        m.record(reached(9)).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(decode(&bytes[..SLOT_LEN]), Some(reached(7)));
        assert_eq!(decode(&bytes[SLOT_LEN..]), Some(reached(9)));
    }

    #[test]
    fn all_slots_damaged_is_told_apart_from_absent() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(FILE_NAME);
        std::fs::write(&path, [0x5a; 2 * SLOT_LEN]).unwrap();
        let (_, found) = Marker::open(dir.path(), Durability::Normal).unwrap();
        assert_eq!(found, Found::Damaged);
    }
}
