#!/usr/bin/env bash
# The boolean side-by-side with manifold3d: writes the scenes' meshes, times winged on
# them, then manifold3d, and prints the comparison table.
#
#   bash bench/boolean/run.sh [DIR]     # DIR defaults to /tmp/boolean-side
#
# PYTHON names the interpreter with manifold3d installed (see README.md); REPEAT the
# runs per scene (best kept); SIZES the spheres' segment counts.
set -euo pipefail
cd "$(dirname "$0")/../.."
DIR=${1:-/tmp/boolean-side}
PYTHON=${PYTHON:-python3}
REPEAT=${REPEAT:-5}
SIZES=${SIZES:-64,128,256,512}
cargo build --release --example boolean_side
bin=${CARGO_TARGET_DIR:-target}/release/examples/boolean_side
"$bin" write --dir "$DIR" --sizes "$SIZES"
"$bin" run --dir "$DIR" --repeat "$REPEAT" || echo "(winged's side failed; the table shows manifold3d alone)"
"$PYTHON" bench/boolean/peer.py "$DIR" --repeat "$REPEAT"
