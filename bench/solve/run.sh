#!/usr/bin/env bash
# Camera solution side by side in one run: winged's SQPnP and solve_pnp and OpenCV's
# solvePnP (SQPNP, EPNP) and solvePnPRansac (default and USAC_MAGSAC), from PyPI's
# opencv-python-headless, on identical problems of the EPnP paper's protocol
# (bench/solve/data.py), then the table and the goals' checks (bench/solve/report.py).
#
#   bash bench/solve/run.sh [--trials 300] [--seed 2020]
#
# Needs python3 with venv; the peer is installed into target/bench-venv on first use
# (WINGED_BENCH_VENV to use another).
set -euo pipefail
cd "$(dirname "$0")/../.."
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
venv="${WINGED_BENCH_VENV:-target/bench-venv}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
if ! "$venv/bin/python" -c "import cv2, numpy" 2>/dev/null; then
    "$venv/bin/pip" install -q opencv-python-headless numpy
fi
cargo build --release --example solve_bench
echo "## camera solution: winged and OpenCV ($(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg))"
"$venv/bin/python" bench/solve/data.py "$dir" "$@"
echo "### winged"
target/release/examples/solve_bench "$dir" "$dir/winged.json"
echo "### OpenCV"
"$venv/bin/python" bench/solve/peer.py "$dir" "$dir/opencv.json"
echo
"$venv/bin/python" bench/solve/report.py "$dir/winged.json" "$dir/opencv.json"
