#!/usr/bin/env bash
# Spatial access side by side, in one process on the same data: winged's index, rstar's
# R*-tree and parry3d's BVH on a 1,000,000-triangle terrain solid and a 100,000-box
# city (bench/spatial/data.rs, shared with benches/spatial.rs). Prints each figure as it
# is measured, then a table.
#
#   bash bench/spatial/run.sh            # both data sets (a few minutes)
#   bash bench/spatial/run.sh terrain    # or: city
#
# The peer project builds into the main target directory, reusing winged's compiled
# dependencies.
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --manifest-path bench/spatial/Cargo.toml --target-dir target
echo "## spatial access: winged, rstar, parry3d ($(date -u +%Y-%m-%d), $(nproc) cores)"
target/release/spatial-peers "$@"
