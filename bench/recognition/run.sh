#!/usr/bin/env bash
# Recognition benchmark: 300 scenes of 5-15 bodies on a table, the truth (bodies pushed,
# taken away, distractors added) drawn by Mesa's llvmpipe through moderngl with its own
# lights, anti-aliasing, gain, blur and noise, recognized by winged against the model.
#
#   bash bench/recognition/run.sh [DIR] [--count N]
#
# Needs python3 with venv and Mesa's EGL (libegl-mesa0). Prints the figures table.
set -euo pipefail
cd "$(dirname "$0")/../.."
dir="${1:-$(mktemp -d)}"
shift || true
venv="${WINGED_RECOGNITION_VENV:-target/recognition-venv}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install -q -r bench/recognition/requirements.txt
fi
cargo build --release --example recognition_bench
target/release/examples/recognition_bench scenes "$dir" "$@"
LIBGL_ALWAYS_SOFTWARE=1 GALLIUM_DRIVER=llvmpipe "$venv/bin/python" bench/recognition/render.py "$dir"
target/release/examples/recognition_bench run "$dir"
"$venv/bin/python" bench/recognition/report.py "$dir"
"$venv/bin/python" bench/recognition/chamfer.py "$dir"
"$venv/bin/python" bench/recognition/linemod.py "$dir"
