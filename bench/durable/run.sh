#!/usr/bin/env bash
# Durable writes per second, end to end: the release server on a fresh data directory
# (SQLite journal, --durability full unless DURABILITY=normal), and wrk sending small
# writes (PATCH a body's pose) over 1, 8 and 64 connections. Every 2xx answer is a write
# on disk. Then recovery: the server is stopped with SIGKILL and restarted on the same
# directory, and its recovery line is printed. Figures: BENCHMARKS.md, "Durability".
#
#   bash bench/durable/run.sh
#   SECONDS_PER_RUN=5 DURABILITY=normal bash bench/durable/run.sh
#
# Needs wrk (Debian: apt-get install -y wrk).
set -euo pipefail
cd "$(dirname "$0")/../.."
source bench/server.sh

SECS="${SECONDS_PER_RUN:-10}"
DURABILITY="${DURABILITY:-full}"

if ! command -v wrk >/dev/null 2>&1; then
    echo "bench/durable/run.sh: wrk is not installed (Debian: apt-get install -y wrk)" >&2
    exit 1
fi
cargo build --release --bin winged

work=$(mktemp -d)
pid=""
cleanup() {
    if [ -n "$pid" ]; then
        kill -9 "$pid" 2>/dev/null || true
        wait "$pid" 2>/dev/null || true
    fi
    rm -rf "$work"
}
trap cleanup EXIT

# start_server NAME: starts the server on the data directory, logging to NAME.log.
start_server() {
    log="$work/$1.log"
    WAIT_TRIES=600 start_winged "$log" env RUST_LOG=warn,winged=info \
        target/release/winged serve --addr 127.0.0.1:0 \
        --data "$work/data" --durability "$DURABILITY"
}

start_server first
id=$(curl -sf -X POST "$url/v1/bodies" -H 'Content-Type: application/json' \
    -d '{"name":"target","shape":{"type":"box","size":[1,1,1]}}' | sed -E 's/.*"id":([0-9]+).*/\1/')
echo "== durable writes, durability $DURABILITY, ${SECS} s per run, body $id"
for conns in 1 8 64; do
    threads=$(( conns < 2 ? 1 : 2 ))
    out=$(wrk -t"$threads" -c"$conns" -d"${SECS}s" --latency -s bench/durable/patch_pose.lua "$url/v1/bodies/$id")
    rps=$(echo "$out" | awk '/^Requests\/sec/ {print $2}')
    p50=$(echo "$out" | awk '$1 == "50%" {print $2}')
    p99=$(echo "$out" | awk '$1 == "99%" {print $2}')
    errors=$(echo "$out" | awk '/Non-2xx/ {print $NF}')
    printf '%3s connections  %10s writes/s  p50 %8s  p99 %8s  non-2xx %s\n' \
        "$conns" "$rps" "$p50" "$p99" "${errors:-0}"
done
curl -sf "$url/metrics" | grep -E '^winged_journal_(commit_duration_seconds|batch_entries)_(sum|count)'
revision=$(curl -sf "$url/v1/world" | sed -E 's/.*"revision":([0-9]+).*/\1/')
echo "== SIGKILL at revision $revision, then restart"
kill -9 "$pid"; wait "$pid" 2>/dev/null || true; pid=""
start_server restart
grep -a 'recovered' "$log" | tail -1
after=$(curl -sf "$url/v1/world" | sed -E 's/.*"revision":([0-9]+).*/\1/')
echo "revision after restart: $after (acknowledged before the kill: $revision)"
