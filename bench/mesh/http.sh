#!/usr/bin/env bash
# The mesh import end to end over HTTP: a release `winged serve`, the file sent with
# `curl --data-binary` to POST /v1/bodies/import, timed by curl from the first byte sent
# to the last byte of the answer. Each run uses a fresh server, once with the world in
# memory and once with the default SQLite journal (durability full) in a new directory.
#
#   bash bench/mesh/http.sh [DIR]   # DIR holds the STLs of bench/mesh/run.sh (written
#                                   # when missing; default /tmp/mesh-side); REPEAT (3)
set -euo pipefail
cd "$(dirname "$0")/../.."
source bench/server.sh
DIR=${1:-/tmp/mesh-side}
REPEAT=${REPEAT:-3}
target=${CARGO_TARGET_DIR:-target}
cargo build --locked --release --bin winged --example mesh_side
if [ ! -f "$DIR/sphere-1m.stl" ] || [ ! -f "$DIR/grid-box-1m.stl" ]; then
    "$target/release/examples/mesh_side" write --dir "$DIR"
fi

work=$(mktemp -d)
pid=""
cleanup() {
    if [ -n "$pid" ]; then
        kill "$pid" 2>/dev/null || true
        wait "$pid" 2>/dev/null || true
    fi
    rm -rf "$work"
}
trap cleanup EXIT

# start MODE: a server on 127.0.0.1:0, in memory (MODE=memory) or journaling into a
# new directory (MODE=journal); sets pid, url and log.
start() {
    local storage
    log="$work/server.log"
    if [ "$1" = memory ]; then storage=(--memory); else
        rm -rf "$work/data"
        storage=(--data "$work/data")
    fi
    start_winged "$log" env RUST_LOG=warn,winged=info "$target/release/winged" serve \
        "${storage[@]}" --addr 127.0.0.1:0
}

stop() {
    kill "$pid"
    wait "$pid" 2>/dev/null || true
    pid=""
}

printf '%-8s %-16s %s\n' mode file "seconds (curl time_total), then the answer's status"
for mode in memory journal; do
    for file in sphere-1m grid-box-1m; do
        for _ in $(seq 1 "$REPEAT"); do
            start "$mode"
            if ! out=$(curl -sS -o "$work/answer.json" -w '%{time_total} %{http_code}' \
                --data-binary "@$DIR/$file.stl" \
                "$url/v1/bodies/import?format=stl&name=$file"); then
                echo "bench/mesh/http.sh: the request failed; the server's log:" >&2
                cat "$log" >&2
                exit 1
            fi
            stop
            printf '%-8s %-16s %s\n' "$mode" "$file" "$out"
        done
    done
done
