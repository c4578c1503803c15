//! Fuzzes the GLB importer: any bytes must give `Ok` or a clean `Err` (no panic,
//! overflow, out-of-memory or hang).
#![no_main]

use libfuzzer_sys::fuzz_target;
use winged::mesh::{Format, ImportOptions, import};

fuzz_target!(|data: &[u8]| {
    let _ = import(Format::Glb, data, &ImportOptions::default());
});
