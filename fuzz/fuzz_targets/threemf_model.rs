//! Fuzzes the 3MF importer's model XML: the bytes (up to the first NUL) become the
//! package's `3D/3dmodel.model` part, what follows a `3D/other.model` part (for
//! components' `p:path`), in a stored zip with correct checksums, so that mutations
//! reach the XML reader instead of the zip reader's checksum test.
#![no_main]

use std::io::{Cursor, Write};

use libfuzzer_sys::fuzz_target;
use winged::mesh::{Format, ImportOptions, import};
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, ZipWriter};

fuzz_target!(|data: &[u8]| {
    let (model, other) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], Some(&data[i + 1..])),
        None => (data, None),
    };
    let mut zip = ZipWriter::new(Cursor::new(Vec::new()));
    let stored = SimpleFileOptions::default().compression_method(CompressionMethod::Stored);
    let mut part = |name: &str, bytes: &[u8]| {
        zip.start_file(name, stored).expect("start");
        zip.write_all(bytes).expect("write");
    };
    part("3D/3dmodel.model", model);
    if let Some(other) = other {
        part("3D/other.model", other);
    }
    let package = zip.finish().expect("finish").into_inner();
    let _ = import(Format::ThreeMf, &package, &ImportOptions::default());
});
