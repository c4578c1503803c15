//! Time to read a snapshot of a world of many bodies under the root:
//! `cargo run --release --example snapshot_load -- [bodies]`.
//!
//! Builds a world of `bodies` (default 100,000) unit cubes, each a part of the root,
//! encodes its snapshot, and times (median of three) decoding it, which includes the
//! checks that a loaded world is sound ([`snapshot::check_world`]): the parts tree's
//! links and totals, and every body's topology. It also times those checks alone, and
//! the parts tree's check alone. Prints the snapshot's size.

use std::time::Instant;

use glam::DVec3;
use winged::model::solids::mkcube;
use winged::model::{Pose, World};
use winged::store::snapshot;

/// The median of three runs of `f`, in seconds.
fn median_of_three(mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..3)
        .map(|_| {
            let started = Instant::now();
            f();
            started.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[1]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let bodies: usize = match std::env::args().nth(1) {
        Some(a) => a.parse()?,
        None => 100_000,
    };
    let mut world = World::new();
    let root = world.root();
    for k in 0..bodies {
        let at = DVec3::new((k % 1000) as f64 * 2.0, (k / 1000) as f64 * 2.0, 0.0);
        world.insert_with(None, root, Pose::from_translation(at), |s| {
            mkcube(s, 1.0, 1.0, 1.0)
        })?;
    }
    let bytes = snapshot::encode(&world);
    let decode = median_of_three(|| {
        std::hint::black_box(snapshot::decode(&bytes).expect("a sound snapshot"));
    });
    let checks = median_of_three(|| {
        snapshot::check_world(&world).expect("a sound world");
    });
    let tree = median_of_three(|| {
        assert!(world.tree().check().is_empty());
    });
    println!(
        "{bodies} bodies under the root, snapshot {} bytes: decoded and checked in {decode:.3} s; \
         checks alone {checks:.3} s, of which the parts tree {tree:.3} s (medians of 3)",
        bytes.len()
    );
    Ok(())
}
