#!/usr/bin/env bash
# Frames per second of the browser viewer, end to end: builds the release binary, sets
# up the Python environment (clients/setup.sh: Selenium, and Debian's chromium and
# chromium-driver when missing), starts `winged serve --memory --demo` on an ephemeral
# loopback port and runs bench/viewer/fps.py against it (an 800 × 600 picture orbiting
# for 10 s in headless Chromium).
#
#   bash bench/viewer/run.sh
#   SECONDS_TO_ORBIT=20 MODE=wire bash bench/viewer/run.sh
#
# The browser, the server and the script share this machine's cores.
set -euo pipefail
cd "$(dirname "$0")/../.."
source bench/server.sh

cargo build --release --locked --bin winged
python=$(bash clients/setup.sh | tail -n 1)

logdir=$(mktemp -d)
pid=""
cleanup() {
    if [ -n "$pid" ]; then
        kill "$pid" 2>/dev/null || true
        wait "$pid" 2>/dev/null || true
    fi
    rm -rf "$logdir"
}
trap cleanup EXIT

start_winged "$logdir/server.log" env RUST_LOG="warn,winged=info" \
    target/release/winged serve --memory --demo --addr 127.0.0.1:0
echo "== server pid $pid at $url; $(nproc) cores; load average $(cut -d' ' -f1-3 /proc/loadavg)"
"$python" bench/viewer/fps.py "$url" --seconds "${SECONDS_TO_ORBIT:-10}" --mode "${MODE:-shaded}"
