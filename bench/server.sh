# Starting `winged serve` from a benchmark script; sourced, not run.
#
#   source bench/server.sh
#   start_winged LOG env RUST_LOG=warn target/release/winged serve --memory --addr 127.0.0.1:0
#
# start_winged LOG COMMAND...: runs COMMAND (a `winged serve` on port 0) in the
# background with its output in LOG, waits for the address it prints (`bound=IP:PORT`;
# up to WAIT_TRIES tenths of a second, 100 by default) and sets `pid` and `url`. If the
# server prints none, or exits first, it shows LOG and fails.
start_winged() {
    local log=$1 bound="" tries=${WAIT_TRIES:-100}
    shift
    # Removed first: the redirection happens in the background job, so an old file
    # could still show the previous server's address to the loop below.
    rm -f "$log"
    "$@" >"$log" 2>&1 &
    pid=$!
    for _ in $(seq 1 "$tries"); do
        bound=$(grep -ao 'bound=[0-9.:]*' "$log" 2>/dev/null | head -1 | cut -d= -f2 || true)
        [ -n "$bound" ] && break
        kill -0 "$pid" 2>/dev/null || break
        sleep 0.1
    done
    if [ -z "$bound" ]; then
        echo "the server did not start ($*):" >&2
        cat "$log" >&2
        return 1
    fi
    url="http://$bound"
}
