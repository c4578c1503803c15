//! What the reached marker costs a durable commit: single-entry commits to a fresh
//! journal with `synchronous=FULL` (each followed by its marker record, as the server
//! does), then the same number of marker records alone, both fsync'd.
//!
//! ```sh
//! cargo run --release --example marker_cost -- [commits]
//! ```

use std::time::Instant;

use serde_json::json;
use winged::edit::{Edit, apply};
use winged::model::World;
use winged::store::marker::{Marker, Reached};
use winged::store::{Durability, Entry, Store, StoreOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let commits: u64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(2000);
    let dir = tempfile::tempdir()?;
    let options = StoreOptions {
        durability: Durability::Full,
        ..StoreOptions::default()
    };
    let mut store = Store::open(&dir.path().join("journal"), options)?;
    let mut world = World::new();
    let create: Edit = serde_json::from_value(
        json!({"edit": "create_body", "name": "b", "shape": {"type": "box", "size": [1, 1, 1]}}),
    )?;
    apply(&mut world, &create)?;
    store.append(
        &[Entry::new(world.revision(), &create)],
        world.next_serial(),
    )?;
    let body = world.bodies().map(|(id, _)| id.get()).max().unwrap_or(2);

    let started = Instant::now();
    for i in 0..commits {
        let edit: Edit = serde_json::from_value(json!({"edit": "patch_body", "body": body,
            "patch": {"pose": {"position": [i as f64 + 1.0, 0, 0], "rotation": [0, 0, 0, 1]}}}))?;
        apply(&mut world, &edit)?;
        store.append(&[Entry::new(world.revision(), &edit)], world.next_serial())?;
    }
    let with_marker = started.elapsed().as_secs_f64();

    let alone_dir = dir.path().join("alone");
    std::fs::create_dir_all(&alone_dir)?;
    let (mut marker, _) = Marker::open(&alone_dir, Durability::Full)?;
    let started = Instant::now();
    for i in 0..commits {
        marker.record(Reached {
            revision: i + 1,
            next_serial: i + 100,
        })?;
    }
    let alone = started.elapsed().as_secs_f64();

    let ms = |s: f64| s * 1e3 / commits as f64;
    println!(
        "{commits} commits: {:.3} ms each with the marker ({:.0}/s); the marker alone {:.3} ms \
         per record, {:.0}% of a commit",
        ms(with_marker),
        commits as f64 / with_marker,
        ms(alone),
        100.0 * alone / with_marker
    );
    Ok(())
}
