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

RUST_LOG="warn,winged=info" target/release/winged serve --memory --demo --addr 127.0.0.1:0 \
    >"$logdir/server.log" 2>&1 &
pid=$!
bound=""
for _ in $(seq 1 100); do
    bound=$(grep -ao 'bound=[0-9.:]*' "$logdir/server.log" | head -1 | cut -d= -f2 || true)
    [ -n "$bound" ] && break
    sleep 0.1
done
if [ -z "$bound" ]; then
    echo "bench/viewer/run.sh: the server did not start:" >&2
    cat "$logdir/server.log" >&2
    exit 1
fi
echo "== server pid $pid at http://$bound; $(nproc) cores; load average $(cut -d' ' -f1-3 /proc/loadavg)"
"$python" bench/viewer/fps.py "http://$bound" --seconds "${SECONDS_TO_ORBIT:-10}" --mode "${MODE:-shaded}"
