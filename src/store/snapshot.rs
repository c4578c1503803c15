//! Snapshot files: the whole world at one revision, in `DIR/snapshots/`.
//!
//! One file per snapshot, named by its revision zero-padded to twelve digits
//! (`000000001234.snap`), so names sort by revision. A file is
//!
//! | bytes | field |
//! |---|---|
//! | 8 | magic `WINGSNAP` |
//! | 4 | format version, little-endian `u32` ([`FORMAT_VERSION`]) |
//! | 8 | revision, little-endian `u64` |
//! | 8 | payload length in bytes, little-endian `u64` |
//! | 4 | CRC-32 of the 28 header bytes before it and of the payload, little-endian |
//! | n | payload: the [`World`] in `postcard` |
//!
//! A file is written under a temporary name, flushed to disk, renamed into place and the
//! directory flushed, so a crash leaves either the whole new file or none. The newest
//! [`KEEP`] snapshots are kept and older ones deleted. One file alone is a complete
//! backup: put it into the `snapshots/` directory of an empty data directory to restore.
//!
//! Reading trusts nothing: the magic, version, length, checksum and revision are
//! checked, and the decoded world is checked as a whole (see [`check_world`]) before it
//! is used, so a damaged file is an error, never a panic or a wrong world.

use std::fs::{self, File};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use crate::model::parts::validate_name;
use crate::model::range::{self, MAX_COORDINATE};
use crate::model::{Serial, World, check_topology};

use super::error::StoreError;

/// The first bytes of every snapshot file.
pub const MAGIC: [u8; 8] = *b"WINGSNAP";
/// The snapshot format this build writes and reads. Version 2 added bodies' material
/// colours, version 3 the records of provisional bodies perception made; an older
/// snapshot is refused, and recovery falls back to an older snapshot or to replaying the
/// journal (whose entries are version-independent JSON edits).
pub const FORMAT_VERSION: u32 = 3;
/// How many snapshots are kept; older ones are deleted after a new one is written.
pub const KEEP: usize = 2;
/// The snapshot directory's name inside a data directory.
pub const DIR_NAME: &str = "snapshots";
/// The extension of a snapshot file.
const EXTENSION: &str = "snap";
/// Header bytes before the payload.
const HEADER_LEN: usize = 8 + 4 + 8 + 8 + 4;
/// Header bytes covered by the checksum (all but the checksum itself).
const CHECKED_HEADER_LEN: usize = HEADER_LEN - 4;

/// Why one snapshot file cannot be used. Recovery passes over such a file (with a
/// warning) and tries the next older one.
#[derive(Debug, thiserror::Error)]
pub enum SnapshotError {
    /// The file could not be read.
    #[error("cannot read the file: {0}")]
    Io(#[from] std::io::Error),
    /// The file does not start with [`MAGIC`].
    #[error("not a snapshot file (wrong magic bytes)")]
    BadMagic,
    /// A format version this build does not read.
    #[error("format version {found} is not the one this program reads ({FORMAT_VERSION})")]
    UnsupportedVersion {
        /// The version in the header.
        found: u32,
    },
    /// The file is shorter or longer than its header says.
    #[error("the file has {found} bytes but its header promises {expected}")]
    Length {
        /// Bytes the header promises (header and payload).
        expected: u64,
        /// Bytes the file has.
        found: u64,
    },
    /// The checksum does not match: the file is damaged.
    #[error("checksum mismatch: stored {stored:08x}, computed {computed:08x}")]
    Checksum {
        /// The checksum in the header.
        stored: u32,
        /// The checksum of the bytes read.
        computed: u32,
    },
    /// The payload is not an encoded world.
    #[error("the payload does not decode: {0}")]
    Decode(#[from] postcard::Error),
    /// The payload decodes to a world that breaks the model's invariants.
    #[error("the world it holds is not sound: {0}")]
    Invalid(String),
    /// The header, the file name and the world disagree about the revision.
    #[error("revision mismatch: {0}")]
    Revision(String),
}

/// A snapshot just written by [`write_snapshot`].
#[derive(Clone, Debug)]
pub struct SnapshotWritten {
    /// The world's revision in it.
    pub revision: u64,
    /// The file.
    pub path: PathBuf,
    /// Its size in bytes.
    pub bytes: u64,
    /// How long encoding, writing and flushing took.
    pub duration: Duration,
    /// The revision of the oldest snapshot still kept. Journal entries up to this
    /// revision are no longer needed even if the newest snapshot turns out damaged, so
    /// this is the safe argument for [`Store::prune_through`](super::Store::prune_through).
    pub oldest_kept: u64,
}

/// A snapshot file found in a data directory, by the revision in its name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SnapshotFile {
    /// The revision its name gives.
    pub revision: u64,
    /// The file.
    pub path: PathBuf,
}

/// The snapshot directory of data directory `dir`.
pub fn snapshots_dir(dir: &Path) -> PathBuf {
    dir.join(DIR_NAME)
}

/// The file name of the snapshot at `revision`.
pub fn file_name(revision: u64) -> String {
    format!("{revision:012}.{EXTENSION}")
}

/// Writes a snapshot of `world` into `DIR/snapshots/` (creating it if needed), durably,
/// then deletes all but the newest [`KEEP`] snapshots.
///
/// Verified before it replaces anything: the world is checked with the loader's rules
/// ([`check_world`]) and the file written is read back and checksummed; either failing
/// is [`StoreError::SnapshotRefused`] and leaves the older snapshots as they were.
///
/// Callable from any thread, given a world it may read (a cloned snapshot of the live
/// world does: bodies are shared, not copied). Postcondition on `Ok`: the file is on
/// disk under its final name and the directory entry is flushed, so it survives a power
/// loss. On `Err` no file under a snapshot name was created or changed (a temporary file
/// may be left if even its removal failed; [`Store::open`](super::Store::open) removes
/// those). Failing to delete an old snapshot is only logged.
pub fn write_snapshot(dir: &Path, world: &World) -> Result<SnapshotWritten, StoreError> {
    let started = Instant::now();
    let snaps = snapshots_dir(dir);
    fs::create_dir_all(&snaps)
        .map_err(|e| StoreError::io("creating snapshot directory", &snaps, e))?;
    let revision = world.revision();
    // The loader's own rules, before the file can replace an older good one.
    check_world(world).map_err(|reason| StoreError::SnapshotRefused { revision, reason })?;
    let (header, payload) = encode_parts(world);
    let path = snaps.join(file_name(revision));
    let tmp = snaps.join(temp_name(revision));
    if let Err(e) = write_synced(&tmp, &[&header, &payload]) {
        let _ = fs::remove_file(&tmp);
        return Err(StoreError::io("writing snapshot", &tmp, e));
    }
    // The file as the file system holds it, read back and checksummed.
    if let Err(reason) = verify_written(&tmp, &header) {
        let _ = fs::remove_file(&tmp);
        return Err(StoreError::SnapshotRefused { revision, reason });
    }
    if let Err(e) = fs::rename(&tmp, &path) {
        let _ = fs::remove_file(&tmp);
        return Err(StoreError::io("renaming snapshot into place", &path, e));
    }
    sync_dir(&snaps).map_err(|e| StoreError::io("flushing snapshot directory", &snaps, e))?;
    // The data directory's entry for snapshots/ itself, in case it was just made.
    sync_dir(dir).map_err(|e| StoreError::io("flushing data directory", dir, e))?;
    let oldest_kept = prune_old(&snaps)?.unwrap_or(revision);
    Ok(SnapshotWritten {
        revision,
        path,
        bytes: (header.len() + payload.len()) as u64,
        duration: started.elapsed(),
        oldest_kept,
    })
}

/// Reads a just-written snapshot file back and checks its length and checksum against
/// the `header` it was written with.
fn verify_written(path: &Path, header: &[u8; HEADER_LEN]) -> Result<(), String> {
    let h = Header::parse(header).map_err(|e| e.to_string())?;
    let mut file = File::open(path).map_err(|e| format!("reading it back: {e}"))?;
    let mut head = [0u8; HEADER_LEN];
    file.read_exact(&mut head)
        .map_err(|e| format!("reading it back: {e}"))?;
    if &head != header {
        return Err("the header read back differs from the one written".to_owned());
    }
    let mut crc = crc32fast::Hasher::new();
    crc.update(&head[..CHECKED_HEADER_LEN]);
    let mut buf = vec![0u8; 1 << 20];
    let mut read = 0u64;
    loop {
        let n = file
            .read(&mut buf)
            .map_err(|e| format!("reading it back: {e}"))?;
        if n == 0 {
            break;
        }
        crc.update(&buf[..n]);
        read += n as u64;
    }
    if read != h.payload_len {
        return Err(format!(
            "{read} payload bytes read back, {} written",
            h.payload_len
        ));
    }
    let computed = crc.finalize();
    if computed != h.crc {
        return Err(format!(
            "the checksum read back is {computed:08x}, {:08x} was written",
            h.crc
        ));
    }
    Ok(())
}

/// Reads and checks one snapshot file (see the [module documentation](self)). If the
/// file's name is a snapshot name, the revision in it must agree with the header.
pub fn read_snapshot(path: &Path) -> Result<World, SnapshotError> {
    let mut file = File::open(path)?;
    let len = file.metadata()?.len();
    let mut header = [0u8; HEADER_LEN];
    if len < HEADER_LEN as u64 {
        return Err(SnapshotError::Length {
            expected: HEADER_LEN as u64,
            found: len,
        });
    }
    file.read_exact(&mut header)?;
    let h = Header::parse(&header)?;
    let expected = (HEADER_LEN as u64).saturating_add(h.payload_len);
    if expected != len {
        return Err(SnapshotError::Length {
            expected,
            found: len,
        });
    }
    // The length matches the file's, so this allocation is no bigger than the file.
    let mut payload = Vec::with_capacity(h.payload_len as usize);
    file.read_to_end(&mut payload)?;
    if payload.len() as u64 != h.payload_len {
        // The file changed size while being read.
        return Err(SnapshotError::Length {
            expected,
            found: HEADER_LEN as u64 + payload.len() as u64,
        });
    }
    if let Some(named) = revision_of(path)
        && named != h.revision
    {
        return Err(SnapshotError::Revision(format!(
            "the file is named for revision {named} but its header says {}",
            h.revision
        )));
    }
    decode_payload(&header, &h, &payload)
}

/// Encodes `world` as a complete snapshot file (header and payload).
pub fn encode(world: &World) -> Vec<u8> {
    let (header, payload) = encode_parts(world);
    let mut out = Vec::with_capacity(HEADER_LEN + payload.len());
    out.extend_from_slice(&header);
    out.extend_from_slice(&payload);
    out
}

/// The header and the payload of `world`'s snapshot file.
fn encode_parts(world: &World) -> ([u8; HEADER_LEN], Vec<u8>) {
    let payload = postcard::to_allocvec(world).expect("encoding to memory cannot fail");
    let mut header = [0u8; HEADER_LEN];
    header[..8].copy_from_slice(&MAGIC);
    header[8..12].copy_from_slice(&FORMAT_VERSION.to_le_bytes());
    header[12..20].copy_from_slice(&world.revision().to_le_bytes());
    header[20..28].copy_from_slice(&(payload.len() as u64).to_le_bytes());
    let mut crc = crc32fast::Hasher::new();
    crc.update(&header[..CHECKED_HEADER_LEN]);
    crc.update(&payload);
    header[CHECKED_HEADER_LEN..].copy_from_slice(&crc.finalize().to_le_bytes());
    (header, payload)
}

/// Decodes and checks a complete snapshot file held in memory.
pub fn decode(bytes: &[u8]) -> Result<World, SnapshotError> {
    let header: &[u8; HEADER_LEN] = bytes
        .get(..HEADER_LEN)
        .and_then(|h| h.try_into().ok())
        .ok_or(SnapshotError::Length {
            expected: HEADER_LEN as u64,
            found: bytes.len() as u64,
        })?;
    let h = Header::parse(header)?;
    let expected = (HEADER_LEN as u64).saturating_add(h.payload_len);
    if expected != bytes.len() as u64 {
        return Err(SnapshotError::Length {
            expected,
            found: bytes.len() as u64,
        });
    }
    decode_payload(header, &h, &bytes[HEADER_LEN..])
}

/// The fixed-size fields of a snapshot header.
struct Header {
    revision: u64,
    payload_len: u64,
    crc: u32,
}

impl Header {
    /// Checks the magic and version and reads the other fields.
    fn parse(b: &[u8; HEADER_LEN]) -> Result<Header, SnapshotError> {
        let u32_at = |i: usize| u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
        let u64_at = |i: usize| {
            let mut a = [0u8; 8];
            a.copy_from_slice(&b[i..i + 8]);
            u64::from_le_bytes(a)
        };
        if b[..8] != MAGIC {
            return Err(SnapshotError::BadMagic);
        }
        let version = u32_at(8);
        if version != FORMAT_VERSION {
            return Err(SnapshotError::UnsupportedVersion { found: version });
        }
        Ok(Header {
            revision: u64_at(12),
            payload_len: u64_at(20),
            crc: u32_at(28),
        })
    }
}

/// Checks the checksum, decodes the payload and checks the world.
fn decode_payload(
    header: &[u8; HEADER_LEN],
    h: &Header,
    payload: &[u8],
) -> Result<World, SnapshotError> {
    let mut crc = crc32fast::Hasher::new();
    crc.update(&header[..CHECKED_HEADER_LEN]);
    crc.update(payload);
    let computed = crc.finalize();
    if computed != h.crc {
        return Err(SnapshotError::Checksum {
            stored: h.crc,
            computed,
        });
    }
    let (world, rest): (World, &[u8]) = postcard::take_from_bytes(payload)?;
    if !rest.is_empty() {
        return Err(SnapshotError::Invalid(format!(
            "{} bytes follow the encoded world",
            rest.len()
        )));
    }
    if world.revision() != h.revision {
        return Err(SnapshotError::Revision(format!(
            "the header says {} but the world is at {}",
            h.revision,
            world.revision()
        )));
    }
    check_world(&world).map_err(SnapshotError::Invalid)?;
    Ok(world)
}

/// Checks a world read from outside against the invariants every [`World`] keeps: a
/// sound parts tree with an empty root, every body a valid winged-edge polyhedron with
/// finite loci in the world's range and its origin in range (see
/// [`crate::model::range`]), every serial in use issued by the world's counter (so
/// none is issued twice), and valid camera and light names and values (which includes
/// their range). Returns the first problem.
///
/// These are the rules every write of the world keeps, so a world the server accepted
/// passes them; the snapshot writer checks them before a snapshot replaces an older one.
pub fn check_world(world: &World) -> Result<(), String> {
    let tree = world.tree();
    if let Some(p) = tree.check().into_iter().next() {
        return Err(format!("parts tree: {p}"));
    }
    let next = world.next_serial();
    let issued = |s: Serial| s != Serial::NONE && s < next;
    let root = world.root();
    if world.body(root).is_none_or(|b| !b.is_empty()) {
        return Err("the world body has geometry".to_owned());
    }
    for (id, node) in tree.iter() {
        if !issued(id.serial()) {
            return Err(format!(
                "body {id} has a serial the counter ({next}) never issued"
            ));
        }
        let b = &node.body;
        let serials = b
            .faces()
            .map(|f| b.face_serial(f))
            .chain(b.edges().map(|e| b.edge_serial(e)))
            .chain(b.vertices().map(|v| b.vertex_serial(v)));
        if let Some(s) = serials.into_iter().find(|&s| !issued(s)) {
            return Err(format!(
                "body {id}: serial {s} was never issued by the counter ({next})"
            ));
        }
        let report = check_topology(b);
        if !report.is_ok() {
            return Err(format!("body {id}: {report}"));
        }
        if let Some(v) = b.vertices().find(|&v| !b.position(v).is_finite()) {
            return Err(format!(
                "body {id}: the locus of vertex {} is not finite",
                b.vertex_serial(v)
            ));
        }
        if let Some(v) = b
            .vertices()
            .find(|&v| !range::is_within(b.position(v), MAX_COORDINATE))
        {
            return Err(format!(
                "body {id}: the locus of vertex {} is {}, beyond the range of ±{MAX_COORDINATE:e} m",
                b.vertex_serial(v),
                b.position(v)
            ));
        }
        let origin = world.world_pose_of(id, node).position;
        if id != root && !range::is_within(origin, MAX_COORDINATE) {
            return Err(format!(
                "body {id}: its origin is at {origin}, beyond the range of ±{MAX_COORDINATE:e} m"
            ));
        }
    }
    for (name, camera) in world.cameras() {
        validate_name(name).map_err(|r| format!("camera {name:?}: {r}"))?;
        camera
            .validated()
            .map_err(|e| format!("camera {name:?}: {e}"))?;
    }
    for (name, light) in world.lights() {
        validate_name(name).map_err(|r| format!("light {name:?}: {r}"))?;
        light
            .validated()
            .map_err(|e| format!("light {name:?}: {e}"))?;
    }
    Ok(())
}

/// The snapshot files in data directory `dir`, oldest first, by the revision in their
/// names. Files in `snapshots/` whose names are not snapshot names are ignored. A data
/// directory without `snapshots/` has none.
pub fn list(dir: &Path) -> Result<Vec<SnapshotFile>, StoreError> {
    list_in(&snapshots_dir(dir))
}

/// The snapshot files in the snapshot directory `snaps`, oldest first.
fn list_in(snaps: &Path) -> Result<Vec<SnapshotFile>, StoreError> {
    let entries = match fs::read_dir(snaps) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(StoreError::io("listing snapshots", snaps, e)),
    };
    let mut out = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| StoreError::io("listing snapshots", snaps, e))?;
        let path = entry.path();
        if let Some(revision) = revision_of(&path) {
            out.push(SnapshotFile { revision, path });
        }
    }
    out.sort_by_key(|s| s.revision);
    Ok(out)
}

/// A world loaded from the newest usable snapshot.
pub(crate) struct Loaded {
    /// The world.
    pub world: World,
    /// The file it came from.
    pub path: PathBuf,
}

/// Loads the newest snapshot in data directory `dir` that passes every check, passing
/// over (with a warning) each newer one that does not. Returns it, if any, and the files
/// passed over, newest first.
pub(crate) fn load_newest(dir: &Path) -> Result<(Option<Loaded>, Vec<SnapshotFile>), StoreError> {
    let mut skipped = Vec::new();
    for snap in list(dir)?.into_iter().rev() {
        match read_snapshot(&snap.path) {
            Ok(world) => {
                let path = snap.path;
                return Ok((Some(Loaded { world, path }), skipped));
            }
            Err(e) => {
                tracing::warn!(
                    path = %snap.path.display(),
                    error = %e,
                    "snapshot unusable, trying the next older one"
                );
                skipped.push(snap);
            }
        }
    }
    Ok((None, skipped))
}

/// Removes temporary files left in `DIR/snapshots/` by writes that never finished.
/// Precondition: no snapshot is being written into `dir` meanwhile.
pub(crate) fn remove_stale_temps(dir: &Path) -> Result<(), StoreError> {
    let snaps = snapshots_dir(dir);
    let entries = match fs::read_dir(&snaps) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(StoreError::io("listing snapshots", &snaps, e)),
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        if name.to_str().is_some_and(is_temp_name) {
            let path = entry.path();
            if let Err(e) = fs::remove_file(&path) {
                tracing::warn!(path = %path.display(), error = %e, "cannot remove a stale temporary snapshot");
            }
        }
    }
    Ok(())
}

/// The revision a snapshot file's name gives: twelve or more digits, then `.snap`.
fn revision_of(path: &Path) -> Option<u64> {
    let name = path.file_name()?.to_str()?;
    let digits = name.strip_suffix(".snap")?;
    if digits.len() < 12 || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

/// A unique temporary name for a snapshot being written (hidden, not a snapshot name).
fn temp_name(revision: u64) -> String {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    format!(".{revision:012}.{}.{n}.tmp", std::process::id())
}

fn is_temp_name(name: &str) -> bool {
    name.starts_with('.') && name.ends_with(".tmp")
}

/// Writes `parts` one after another to a new file at `path` and flushes it to disk.
fn write_synced(path: &Path, parts: &[&[u8]]) -> std::io::Result<()> {
    let mut f = File::create(path)?;
    for part in parts {
        f.write_all(part)?;
    }
    f.sync_all()
}

/// Flushes a directory's entries (a rename or a new file in it) to disk.
fn sync_dir(dir: &Path) -> std::io::Result<()> {
    File::open(dir)?.sync_all()
}

/// Deletes all but the newest [`KEEP`] snapshots in `snaps`; returns the oldest kept
/// one's revision.
fn prune_old(snaps: &Path) -> Result<Option<u64>, StoreError> {
    let all = list_in(snaps)?;
    let cut = all.len().saturating_sub(KEEP);
    for old in &all[..cut] {
        if let Err(e) = fs::remove_file(&old.path) {
            tracing::warn!(path = %old.path.display(), error = %e, "cannot delete an old snapshot");
        }
    }
    if cut > 0
        && let Err(e) = sync_dir(snaps)
    {
        tracing::warn!(path = %snaps.display(), error = %e, "cannot flush the snapshot directory");
    }
    Ok(all.get(cut).map(|s| s.revision))
}
