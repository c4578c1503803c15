#!/usr/bin/env bash
# Appearance benchmark, side by side in one run: winged's renderer and Mesa's llvmpipe
# (through moderngl, from PyPI) on the same block worlds (30, 3,000 and 100,000 bodies),
# the same 20 cameras at 1280x960.
#
#   bash bench/render/run.sh [--sizes 30,3000]
#
# Needs python3 with venv and Mesa's EGL (libegl-mesa0) for the peer.
set -euo pipefail
cd "$(dirname "$0")/../.."
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
venv="${WINGED_BENCH_VENV:-target/bench-venv}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install -q moderngl numpy
fi
cargo build --release --example render_bench
echo "## winged"
target/release/examples/render_bench --dump "$dir" "$@"
echo
echo "## Mesa llvmpipe (moderngl)"
LIBGL_ALWAYS_SOFTWARE=1 GALLIUM_DRIVER=llvmpipe "$venv/bin/python" bench/render/peer.py "$dir"
