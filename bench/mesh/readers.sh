#!/usr/bin/env bash
# Independent readers of the meshes winged writes: trimesh (PyPI) loads every STL, PLY,
# OFF, OBJ, GLB and 3MF in DIR, finds it watertight and, where a `NAME.volume` file
# says what winged reported, the same volume (to 1e-6 relative, 1e-4 for the f32
# formats STL, GLB and 3MF); the Khronos glTF Validator (npm `gltf-validator`) finds 0
# errors in every GLB. Fails on any failure.
#
# Usage: bench/mesh/readers.sh DIR   (tests/mesh_http.rs writes its exports to
#        $CARGO_TARGET_DIR/tmp/mesh-exports)
#
# Needs python3 with venv and pip, and node with npm: trimesh and the validator are
# installed, at the versions pinned below, under $CARGO_TARGET_DIR the first time.
set -euo pipefail
cd "$(dirname "$0")/../.."

dir=${1:?usage: $0 DIR}
[[ -d $dir ]] || { echo "$dir: no such directory (run cargo test first)" >&2; exit 2; }

target=${CARGO_TARGET_DIR:-target}
venv=$target/mesh-venv
if ! "$venv/bin/python" -c 'import trimesh, lxml, networkx; assert trimesh.__version__ == "5.2.0"' 2>/dev/null; then
    echo "mesh readers: installing trimesh into $venv"
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check \
        "trimesh==5.2.0" "numpy==2.4.6" "lxml==6.1.3" "networkx==3.6.1"
fi
npm_dir=$target/mesh-npm
if [[ ! -f $npm_dir/node_modules/gltf-validator/package.json ]]; then
    echo "mesh readers: installing gltf-validator into $npm_dir"
    mkdir -p "$npm_dir"
    npm install --silent --prefix "$npm_dir" gltf-validator@2.0.0-dev.3.10 >/dev/null
fi

"$venv/bin/python" bench/mesh/readers.py "$dir"
NODE_PATH=$npm_dir/node_modules node bench/mesh/validate_gltf.js "$dir"
