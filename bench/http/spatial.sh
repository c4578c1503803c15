#!/usr/bin/env bash
# Spatial queries over HTTP, end to end: builds the release binary, starts
# `winged serve --memory` on loopback (an ephemeral port), fills it with a city of
# boxes by parallel POSTs, then runs wrk against `GET /v1/spatial/sphere` with a
# different centre on every request (bench/http/spatial.lua) and reports latency
# percentiles. Figures and discussion: BENCHMARKS.md.
#
#   bash bench/http/spatial.sh                       # 100 × 100 = 10,000 boxes, 10 s per run
#   CITY_SIDE=50 SECONDS_PER_RUN=5 bash bench/http/spatial.sh   # 2,500 boxes, shorter
#   WINGED_BIN=/path/to/winged bash bench/http/spatial.sh       # another build, as is
#
# After the sphere runs, one more wrk run reads `GET /v1/world` (the world's counts) in
# the same city.
# Needs wrk (Debian: apt-get install -y wrk) and curl ≥ 7.66 (for --parallel).
# Everything runs on this machine: wrk, curl and the server share its cores.
set -euo pipefail
cd "$(dirname "$0")/../.."
source bench/server.sh

SECS="${SECONDS_PER_RUN:-10}"
THREADS="${WRK_THREADS:-2}"
CONNS="${WRK_CONNECTIONS:-8}"
SIDE="${CITY_SIDE:-100}"        # boxes per side of the square city
PITCH=20                        # meters between neighbouring boxes' centres
POSTS_AT_ONCE="${POSTS_AT_ONCE:-16}"

if ! command -v wrk >/dev/null 2>&1; then
    echo "bench/http/spatial.sh: wrk is not installed (Debian: apt-get install -y wrk)" >&2
    exit 1
fi

bin="${WINGED_BIN:-}"
if [ -z "$bin" ]; then
    cargo build --release --bin winged
    bin=target/release/winged
fi

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

log="$logdir/server.log"
# winged's own lines (the index build among them, and each sync of the index), not one
# line per request.
start_winged "$log" env RUST_LOG="warn,winged=info,winged::server::api::spatial=debug" \
    "$bin" serve --memory --addr 127.0.0.1:0
echo "== $(nproc) cores; load average: $(cut -d' ' -f1-3 /proc/loadavg); server pid $pid at $url"

# The city: SIDE × SIDE boxes on a PITCH grid, footprints 8–16 m, heights 6–60 m
# (fixed pseudo-random sizes), standing on z = 0. One curl process sends them all,
# POSTS_AT_ONCE at a time.
n=$((SIDE * SIDE))
awk -v side="$SIDE" -v pitch="$PITCH" -v url="$url/v1/bodies" 'BEGIN {
    srand(7);
    for (i = 0; i < side; i++) for (j = 0; j < side; j++) {
        w = 8 + 8 * rand(); d = 8 + 8 * rand(); h = 6 + 54 * rand();
        if (i + j > 0) print "next";
        printf "url = \"%s\"\n", url;
        print "header = \"Content-Type: application/json\"";
        printf "data = \"{\\\"pose\\\": {\\\"position\\\": [%.2f, %.2f, %.2f]}, \\\"shape\\\": {\\\"type\\\": \\\"box\\\", \\\"size\\\": [%.2f, %.2f, %.2f]}}\"\n", \
            (i + 0.5) * pitch, (j + 0.5) * pitch, h / 2, w, d, h;
        print "output = \"/dev/null\"";
        print "write-out = \"%{http_code}\\n\"";
    }
}' >"$logdir/city.curl"
started=$(date +%s.%N)
curl -sS --no-progress-meter --parallel --parallel-max "$POSTS_AT_ONCE" -K "$logdir/city.curl" >"$logdir/codes"
elapsed=$(echo "$(date +%s.%N) - $started" | bc)
made=$(grep -c '^201$' "$logdir/codes" || true)
echo "== city: $made of $n boxes made in ${elapsed} s ($POSTS_AT_ONCE POSTs at a time); $(curl -sS "$url/v1/world")"
if [ "$made" != "$n" ]; then
    echo "bench/http/spatial.sh: some POSTs failed:" >&2
    sort "$logdir/codes" | uniq -c >&2
    exit 1
fi

extent=$((SIDE * PITCH))
# The first query builds the index; later ones answer from it.
first=$(curl -sS -o /dev/null -w '%{time_total}' "$url/v1/spatial/sphere?x=10&y=10&z=5&r=15")
echo "== first query (builds the index): ${first} s; $(grep -a 'spatial index built' "$log" | sed 's/.*INFO //')"
sample=$(curl -sS "$url/v1/spatial/sphere?x=$((extent / 2))&y=$((extent / 2))&z=20&r=15&detail=bodies")
echo "== a sample answer (detail=bodies): $sample"

summary=()
# load NAME DETAIL RADIUS: one wrk run of GET /v1/spatial/sphere.
load() {
    local name="$1" detail="$2" radius="$3" out
    out=$(SPATIAL_EXTENT="$extent" SPATIAL_DETAIL="$detail" SPATIAL_RADIUS="$radius" \
        wrk -t"$THREADS" -c"$CONNS" -d"${SECS}s" --latency -s bench/http/spatial.lua "$url")
    echo "-- $name: wrk -t$THREADS -c$CONNS -d${SECS}s --latency -s bench/http/spatial.lua" \
        "(SPATIAL_EXTENT=$extent SPATIAL_DETAIL=$detail SPATIAL_RADIUS=$radius)"
    echo "$out"
    local rps p50 p75 p90 p99 errors
    rps=$(echo "$out" | awk '/^Requests\/sec/ {print $2}')
    p50=$(echo "$out" | awk '$1 == "50%" {print $2}')
    p75=$(echo "$out" | awk '$1 == "75%" {print $2}')
    p90=$(echo "$out" | awk '$1 == "90%" {print $2}')
    p99=$(echo "$out" | awk '$1 == "99%" {print $2}')
    errors=$(echo "$out" | awk '/Non-2xx/ {print $NF}')
    summary+=("$(printf '%-34s %10s req/s  p50 %8s  p75 %8s  p90 %8s  p99 %8s  non-2xx %s' \
        "$name" "$rps" "$p50" "$p75" "$p90" "$p99" "${errors:-0}")")
}

load "sphere r=15 m, features" features 15
load "sphere r=15 m, bodies" bodies 15
load "sphere r=50 m, features" features 50
load "sphere r=15 m, portions" portions 15

# The same queries while the world changes: one client moves a random box to a random
# place MOVES_PER_SECOND times a second (curl, one process per move), so most queries
# find the index behind the world and bring it up first (a snapshot of the world, then
# a sync with the bodies the change feed names).
MOVES_PER_SECOND="${MOVES_PER_SECOND:-20}"
curl -sS "$url/v1/bodies" | grep -o '"id":[0-9]*' | cut -d: -f2 >"$logdir/ids"
mapfile -t ids <"$logdir/ids"
before=$(curl -sS "$url/v1/world" | sed -E 's/.*"revision":([0-9]+).*/\1/')
(
    while :; do
        n_ids=${#ids[@]}; k=$(( (RANDOM * 32768 + RANDOM) % n_ids )); id=${ids[$k]}
        x=$((RANDOM % extent)); y=$((RANDOM % extent))
        curl -sS -o /dev/null -X PATCH "$url/v1/bodies/$id" -H 'Content-Type: application/json' \
            -d "{\"pose\": {\"position\": [$x, $y, 20]}}" || true
        sleep "$(echo "scale=3; 1 / $MOVES_PER_SECOND" | bc)"
    done
) &
mover=$!
load "sphere r=15 m, features, moving" features 15
kill "$mover" 2>/dev/null || true
wait "$mover" 2>/dev/null || true
after=$(curl -sS "$url/v1/world" | sed -E 's/.*"revision":([0-9]+).*/\1/')
echo "== $((after - before)) moves during the last run (${MOVES_PER_SECOND}/s asked)"
in_place=$(( $(grep -ac 'spatial index rebuilt in place' "$log" || true) + $(grep -ac 'rebuilt=true' "$log" || true) ))
echo "== the index was rebuilt $(grep -ac 'spatial index rebuilt off the lock' "$log" || true) times" \
    "off the lock (the last: $(grep -a 'spatial index rebuilt off the lock' "$log" | tail -1 | sed 's/.*INFO //'))" \
    "and $in_place times in place (by a sync, queries waiting)"
echo "== the index was synced $(grep -ac 'spatial index synced' "$log" || true) times; the slowest and the last:"
grep -a 'spatial index synced' "$log" | awk -F'elapsed_ms=' '{print $2 + 0, $0}' | sort -g | tail -1 |
    cut -d' ' -f2- | sed 's/.*DEBUG //' || true
grep -a 'spatial index synced' "$log" | tail -1 | sed 's/.*DEBUG //' || true

# The world's counts (bodies, faces, edges, vertices) in the same city.
out=$(wrk -t"$THREADS" -c"$CONNS" -d"${SECS}s" --latency "$url/v1/world")
echo "-- GET /v1/world: wrk -t$THREADS -c$CONNS -d${SECS}s --latency $url/v1/world"
echo "$out"
summary+=("$(printf '%-34s %10s req/s  p50 %8s  p75 %8s  p90 %8s  p99 %8s' "GET /v1/world" \
    "$(echo "$out" | awk '/^Requests\/sec/ {print $2}')" "$(echo "$out" | awk '$1 == "50%" {print $2}')" \
    "$(echo "$out" | awk '$1 == "75%" {print $2}')" "$(echo "$out" | awk '$1 == "90%" {print $2}')" \
    "$(echo "$out" | awk '$1 == "99%" {print $2}')")")

echo "== summary ($n boxes, wrk -t$THREADS -c$CONNS, ${SECS} s per run; load average now: $(cut -d' ' -f1-3 /proc/loadavg))"
printf '%s\n' "${summary[@]}"
