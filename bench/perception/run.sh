#!/usr/bin/env bash
# The perception side-by-side: writes the scenes' masks, rings and cones, times and
# checks winged's visual hulls on them, then manifold3d and Open3D on the same inputs,
# and prints the tables; then the random trials and the robustness runs.
#
#   bash bench/perception/run.sh [DIR]     # DIR defaults to /tmp/perception-side
#
# PYTHON names an interpreter with manifold3d and open3d-cpu (default: the venv
# target/bench-venv, created and filled from requirements.txt when missing); REPEAT the
# runs per case (best kept; Open3D runs once per case, see PEERS_ARGS); PEERS_ARGS more
# arguments for peers.py (e.g. "--o3d-max-views 64"); CHECKS=0 skips the trials and the
# robustness runs.
set -euo pipefail
cd "$(dirname "$0")/../.."
DIR=${1:-/tmp/perception-side}
REPEAT=${REPEAT:-5}
PEERS_ARGS=${PEERS_ARGS:-}
CHECKS=${CHECKS:-1}
target=${CARGO_TARGET_DIR:-target}
if [ -z "${PYTHON:-}" ]; then
    venv=$target/bench-venv
    [ -x "$venv/bin/python" ] || python3 -m venv "$venv"
    "$venv/bin/python" -c "import manifold3d, open3d, numpy" 2>/dev/null ||
        "$venv/bin/pip" install -q -r bench/perception/requirements.txt
    PYTHON=$venv/bin/python
fi
if ! "$PYTHON" -c "import open3d" 2>/dev/null; then
    echo "Open3D does not load (its wheel needs libusb-1.0: apt-get install libusb-1.0-0); its columns stay empty" >&2
fi
cargo build --release --example perception_side
bin=$target/release/examples/perception_side
"$bin" write --dir "$DIR"
"$bin" run --dir "$DIR" --repeat "$REPEAT" || echo "(winged's side failed; the peers' table has no winged columns)"
# shellcheck disable=SC2086
"$PYTHON" bench/perception/peers.py "$DIR" --repeat "$REPEAT" $PEERS_ARGS
if [ "$CHECKS" != 0 ]; then
    "$bin" trials --n 1000 --seed 1 || true
    "$bin" robust --draws 3 --seed 1 --dump "$DIR/robust" || true
fi
