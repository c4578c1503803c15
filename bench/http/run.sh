#!/usr/bin/env bash
# HTTP benchmarks of `winged serve`, end to end: builds the release binary and the
# read_latency example, starts servers on loopback (ephemeral ports), runs the loads,
# stops the servers. Figures and discussion: BENCHMARKS.md, "Server".
# Spatial queries have their own run: bench/http/spatial.sh.
#
#   bash bench/http/run.sh              # 10 s per wrk run, 20 s latency phase
#   SECONDS_PER_RUN=5 bash bench/http/run.sh
#   SKIP_LATENCY=1 bash bench/http/run.sh   # wrk runs only
#
# Needs wrk (Debian: apt-get install -y wrk). Everything runs on this machine: wrk, the
# server and the latency clients share its cores.
set -euo pipefail
cd "$(dirname "$0")/../.."
source bench/server.sh

SECS="${SECONDS_PER_RUN:-10}"
LATENCY_SECS="${LATENCY_SECONDS:-20}"
THREADS="${WRK_THREADS:-2}"

if ! command -v wrk >/dev/null 2>&1; then
    echo "bench/http/run.sh: wrk is not installed (Debian: apt-get install -y wrk)" >&2
    exit 1
fi

cargo build --release --bin winged --example read_latency

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

# start_server RUST_LOG: starts `winged serve --demo` on 127.0.0.1:0, logging to a
# file; sets pid and url.
start_server() {
    start_winged "$logdir/server-${1//[^a-z]/_}.log" \
        env RUST_LOG="$1" target/release/winged serve --memory --demo --addr 127.0.0.1:0
    echo "== server pid $pid at $url, RUST_LOG=$1"
}

stop_server() {
    kill "$pid"
    wait "$pid" 2>/dev/null || true
    pid=""
}

# load NAME CONNECTIONS [wrk args...] URL: one wrk run; prints wrk's report and a summary.
load() {
    local name="$1" conns="$2"
    shift 2
    local out
    out=$(wrk -t"$THREADS" -c"$conns" -d"${SECS}s" --latency "$@")
    echo "-- $name, $conns connections, ${SECS} s"
    echo "$out"
    local rps p50 p99 errors
    rps=$(echo "$out" | awk '/^Requests\/sec/ {print $2}')
    p50=$(echo "$out" | awk '$1 == "50%" {print $2}')
    p99=$(echo "$out" | awk '$1 == "99%" {print $2}')
    errors=$(echo "$out" | awk '/Non-2xx/ {print $NF}')
    summary+=("$(printf '%-28s %4s conns  %10s req/s  p50 %8s  p99 %8s  non-2xx %s' \
        "$name" "$conns" "$rps" "$p50" "$p99" "${errors:-0}")")
}

summary=()
echo "== $(nproc) cores; load average: $(cut -d' ' -f1-3 /proc/loadavg)"

# As shipped: one INFO log line per request (to a file here).
start_server "info"
load "GET /v1/world (request log)" 8 "$url/v1/world"
load "GET /v1/world (request log)" 64 "$url/v1/world"
load "POST /v1/bodies box (request log)" 8 -s bench/http/post_box.lua "$url/v1/bodies"
load "POST /v1/bodies box (request log)" 64 -s bench/http/post_box.lua "$url/v1/bodies"
echo "== after the POST runs: $(curl -sS "$url/v1/world")"
stop_server

# Without the per-request log lines (tower_http's), keeping winged's own.
start_server "warn,winged=info"
load "GET /v1/world (no request log)" 8 "$url/v1/world"
load "GET /v1/world (no request log)" 64 "$url/v1/world"
load "POST /v1/bodies box (no request log)" 8 -s bench/http/post_box.lua "$url/v1/bodies"
load "POST /v1/bodies box (no request log)" 64 -s bench/http/post_box.lua "$url/v1/bodies"
# The same small read once the POSTs have filled the world with boxes: GET /v1/world
# sums the counts over every body.
nbodies=$(curl -sS "$url/v1/world" | sed -E 's/.*"bodies":([0-9]+).*/\1/')
load "GET /v1/world, $nbodies bodies" 8 "$url/v1/world"
stop_server

if [ "${SKIP_LATENCY:-0}" != 1 ]; then
    start_server "info"
    echo "-- read_latency: GET /v1/world while 4 clients pull a 1M-face topology"
    target/release/examples/read_latency "$url" --pullers 4 --segments 1000 --rings 1000 \
        --seconds "$LATENCY_SECS"
    stop_server
fi

echo "== summary (wrk -t$THREADS, ${SECS} s per run; load average now: $(cut -d' ' -f1-3 /proc/loadavg))"
printf '%s\n' "${summary[@]}"
