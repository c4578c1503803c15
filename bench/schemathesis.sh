#!/usr/bin/env bash
# Schemathesis against the real server: every operation of proto/openapi.yaml (as the
# server serves it at /openapi.json), with every check, on a live `winged serve --memory
# --demo` guarded by tokens. Fails on any failure.
#
# Usage: bench/schemathesis.sh [EXAMPLES]   (test cases per operation and phase; default 10)
#
# Needs only the Rust toolchain and python3 with venv and pip: Schemathesis is installed,
# at the version pinned below, into target/schemathesis-venv the first time.
# Extra arguments for `schemathesis run` may be given in SCHEMATHESIS_ARGS.
set -euo pipefail
cd "$(dirname "$0")/.."

examples=${1:-10}
[[ $examples =~ ^[1-9][0-9]*$ ]] || { echo "usage: $0 [EXAMPLES]" >&2; exit 2; }

version=4.32.5
target=${CARGO_TARGET_DIR:-target}
venv=$target/schemathesis-venv
st=$venv/bin/schemathesis
if ! "$st" --version 2>/dev/null | grep -qF "$version"; then
    echo "schemathesis: installing $version into $venv"
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check "schemathesis==$version"
fi

# The debug binary `cargo test` builds already; this only builds it if it is missing
# or stale.
cargo build --locked --quiet --bin winged
bin=$target/debug/winged

work=$(mktemp -d)
server=
cleanup() {
    if [[ -n $server ]]; then
        kill "$server" 2>/dev/null || true
        wait "$server" 2>/dev/null || true
    fi
    rm -rf "$work"
}
trap cleanup EXIT

# A token per role: the run authenticates as admin; schemathesis's ignored_auth check
# also tries every guarded operation without it (and must be answered 401).
token() { python3 -c 'import secrets; print(secrets.token_hex(16))'; }
admin=$(token)
export WINGED_TOKENS="admin:$admin,read:$(token),write:$(token)"

# Port 0: the kernel picks a free port; the server logs the address it bound.
# Renders are capped at 1 megapixel so that the run's time goes to breadth, not to
# drawing large pictures with a debug build (larger ones answer 422 render-too-large).
RUST_LOG=info "$bin" serve --memory --demo --addr 127.0.0.1:0 \
    --max-render-pixels 1048576 >"$work/server.log" 2>&1 &
server=$!
base=
for _ in $(seq 1 100); do
    base=$(grep -o 'http://127\.0\.0\.1:[0-9]*' "$work/server.log" | head -n 1 || true)
    [[ -n $base ]] && break
    kill -0 "$server" 2>/dev/null || { cat "$work/server.log" >&2; exit 1; }
    sleep 0.1
done
[[ -n $base ]] || { echo "the server did not start:" >&2; cat "$work/server.log" >&2; exit 1; }
echo "schemathesis: $("$st" --version) against $base, $examples examples per operation"

status=0
# One worker: with two, CPython 3.11's AST module (which Hypothesis uses to describe its
# strategies) can raise "AST constructor recursion depth mismatch" when two threads
# parse at once, a failure of the tool rather than of the server.
# shellcheck disable=SC2086 # SCHEMATHESIS_ARGS is split on purpose
"$st" --config-file bench/schemathesis.toml run "$base/openapi.json" \
    --checks all \
    --max-examples "$examples" \
    --header "Authorization: Bearer $admin" \
    --workers 1 \
    --seed 1 \
    --generation-database none \
    --request-timeout 60 \
    --no-color \
    ${SCHEMATHESIS_ARGS:-} || status=$?
if [[ $status -ne 0 ]]; then
    echo "schemathesis: failed (exit $status); the server's log is in the output above" >&2
    tail -n 50 "$work/server.log" >&2
fi
exit "$status"
