#!/usr/bin/env bash
# The mesh side-by-side: writes million-triangle binary STLs, times winged's import
# (read, weld, check, merge coplanar faces, build the body) and exports on them, then
# trimesh's load and exports of the same files, and prints both.
#
#   bash bench/mesh/run.sh [DIR]     # DIR defaults to /tmp/mesh-side; REPEAT runs each (5)
#
# trimesh comes from the venv bench/mesh/readers.sh keeps ($CARGO_TARGET_DIR/mesh-venv),
# made when missing.
set -euo pipefail
cd "$(dirname "$0")/../.."
DIR=${1:-/tmp/mesh-side}
REPEAT=${REPEAT:-5}
target=${CARGO_TARGET_DIR:-target}
venv=$target/mesh-venv
if ! "$venv/bin/python" -c 'import trimesh; assert trimesh.__version__ == "5.2.0"' 2>/dev/null; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check \
        "trimesh==5.2.0" "numpy==2.4.6" "lxml==6.1.3" "networkx==3.6.1"
fi
cargo build --locked --release --example mesh_side
bin=$target/release/examples/mesh_side
"$bin" write --dir "$DIR"
echo "winged:"
"$bin" run --dir "$DIR" --repeat "$REPEAT"
echo "trimesh:"
"$venv/bin/python" bench/mesh/peers.py "$DIR" --repeat "$REPEAT"
