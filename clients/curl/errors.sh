#!/usr/bin/env bash
# The error format: every refusal is an RFC 9457 problem (application/problem+json with
# type, title, status and detail), and a refused request changes nothing. Shown here: a
# 404 for an id that names nothing, a 422 for an Euler operator the body refuses (KLEV
# of a cube's corner, which has three edges), and a 400 for malformed JSON.
#
#   WINGED=http://127.0.0.1:7878 bash clients/curl/errors.sh
set -euo pipefail
. "$(dirname "$0")/lib.sh"

# refused STATUS METHOD PATH [JSON]: sends a request that must be refused with STATUS
# and a problem+json body; prints the answer. Stops the script otherwise.
refused() {
    local want="$1" method="$2" path="$3" data="${4:-}"
    local args=(-sS -X "$method" -D - -o "$tmp/body")
    if [ -n "$data" ]; then
        args+=(-H 'Content-Type: application/json' --data-binary "$data")
        echo "\$ curl -i -X $method \$WINGED$path -H 'Content-Type: application/json' -d '$data'"
    elif [ "$method" = GET ]; then
        echo "\$ curl -i \$WINGED$path"
    else
        echo "\$ curl -i -X $method \$WINGED$path"
    fi
    local head status ctype
    if ! head=$(curl "${args[@]}" "$WINGED$path"); then
        echo "winged clients: no answer from $WINGED (is 'winged serve' running there?)" >&2
        exit 1
    fi
    status=$(printf '%s' "$head" | sed -n '1s/^HTTP\/[0-9.]* \([0-9]*\).*/\1/p')
    ctype=$(printf '%s' "$head" | tr -d '\r' | sed -n 's/^[Cc]ontent-[Tt]ype: *//p')
    echo "HTTP $status, Content-Type: $ctype"
    cat "$tmp/body"
    echo
    expect "$method $path: status" "$status" "$want"
    expect "$method $path: content type" "$ctype" "application/problem+json"
    local type title pstatus detail
    IFS=$'\t' read -r type title pstatus detail <<<"$(field "$(cat "$tmp/body")" type title status detail)"
    expect "$method $path: problem status" "$pstatus" "$want"
    case "$type" in
        urn:winged:problem:*) ;;
        *) expect "$method $path: problem type" "$type" "urn:winged:problem:..." ;;
    esac
    [ -n "$title" ] && [ -n "$detail" ] || expect "$method $path: title and detail" "" "present"
}

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

echo "# 404: no body has this id (ids are never reused, so a stale id is always a 404)"
refused 404 GET /v1/bodies/999999999

echo "# A box to refuse things on"
r=$(call POST /v1/bodies '{"shape": {"type": "box", "size": [2, 2, 2]}}')
box=$(field "$r" id)
t=$(QUIET=1 call GET "/v1/bodies/$box/topology")
corner=$(field "$t" vertices.0.id)
before=$(field "$(QUIET=1 call GET /v1/world)" revision)

echo "# 422: KLEV kills a vertex with one or two edges; a cube's corner has three"
refused 422 POST "/v1/bodies/$box/euler" "{\"op\": \"klev\", \"vertex\": $corner}"
after=$(field "$(QUIET=1 call GET /v1/world)" revision)
expect "revision after a refusal" "$after" "$before"
echo "the world is unchanged: still at revision $after"

echo "# 400: the body is not JSON"
refused 400 POST /v1/bodies '{"shape": {"type": "box", "size": [2, 2, 2]'

echo "# 404 also for an id that names something of another kind (a vertex is not a body)"
refused 404 GET "/v1/bodies/$corner"

call DELETE "/v1/bodies/$box" >/dev/null
echo "errors: ok (404, 422 and 400 answered as application/problem+json; the refusal changed nothing)"
