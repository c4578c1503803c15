# Shared helpers for the curl clients: source it, do not run it.
#
#   WINGED   the server's base URL (default http://127.0.0.1:7878)
#   QUIET=1  do not print the transcript (each request as a curl command line, and its
#            answer); the scripts' own summary lines are still printed
#   BRIEF=1  cut long answers short in the transcript (the scripts set it for big reads)
#
# Every request goes through `call`, which prints the transcript on the script's standard
# output (file descriptor 3, so that it shows even when the answer is captured with
# $(...)), and stops the script (exit 1) on any answer that is not 2xx, showing the
# server's problem+json body on standard error. JSON fields are read with `field` and
# `rows`, which use jq if it is installed and python3 otherwise.

WINGED="${WINGED:-http://127.0.0.1:7878}"
WINGED="${WINGED%/}"
exec 3>&1

if ! command -v curl >/dev/null 2>&1; then
    echo "winged clients: curl is not installed" >&2
    exit 1
fi

# call METHOD PATH [JSON]: sends one request and prints its answer on standard output
# (and the transcript on fd 3 unless QUIET=1); exits 1 on a non-2xx answer or no answer.
call() {
    local method="$1" path="$2" data="${3:-}"
    local out status
    local args=(-sS -X "$method" -w '\n%{http_code}')
    if [ -n "$data" ]; then
        args+=(-H 'Content-Type: application/json' --data-binary "$data")
    fi
    if [ "${QUIET:-0}" != 1 ]; then
        if [ -n "$data" ]; then
            echo "\$ curl -X $method \$WINGED$path -H 'Content-Type: application/json' -d '$data'" >&3
        elif [ "$method" = GET ]; then
            echo "\$ curl \$WINGED$path" >&3
        else
            echo "\$ curl -X $method \$WINGED$path" >&3
        fi
    fi
    if ! out=$(curl "${args[@]}" "$WINGED$path"); then
        echo "winged clients: no answer from $WINGED (is 'winged serve' running there?)" >&2
        exit 1
    fi
    status="${out##*$'\n'}"
    out="${out%$'\n'*}"
    case "$status" in
        2??)
            if [ "${QUIET:-0}" != 1 ]; then
                if [ "${BRIEF:-0}" = 1 ] && [ "${#out}" -gt 300 ]; then
                    printf '%s... (%d bytes)\n' "${out:0:300}" "${#out}" >&3
                else
                    printf '%s\n' "$out" >&3
                fi
            fi
            printf '%s\n' "$out"
            ;;
        *)
            echo "winged clients: $method $path answered $status:" >&2
            printf '%s\n' "$out" >&2
            exit 1
            ;;
    esac
}

# field JSON EXPR...: the values at each EXPR, tab-separated on one line. An EXPR is a
# dotted path with numeric list indices ("id", "euler.F", "bodies.0.id", "faces.length"
# for a list's length). Objects and lists come out as compact JSON, null as "null".
# Read several at once with:  IFS=$'\t' read -r a b <<<"$(field "$json" id face)"
field() {
    local json="$1"
    shift
    json_select "" "$json" "$@"
}

# rows JSON LIST EXPR...: one line per item of the list at LIST, with the values at each
# EXPR (a path within the item), tab-separated.
rows() {
    local json="$1" list="$2"
    shift 2
    json_select "$list" "$json" "$@"
}

# The JSON reader: jq if it is installed, else python3 (WINGED_JSON=jq or
# WINGED_JSON=python3 chooses). python3 is resolved once to its interpreter, so that a
# version manager's shim (pyenv) is not started again for every field.
if [ -z "${WINGED_JSON:-}" ]; then
    if command -v jq >/dev/null 2>&1; then
        WINGED_JSON=jq
    else
        WINGED_JSON=python3
    fi
fi
case "$WINGED_JSON" in
    jq) command -v jq >/dev/null 2>&1 || {
        echo "winged clients: WINGED_JSON=jq but jq is not installed" >&2
        exit 1
    } ;;
    python3)
        WINGED_PYTHON="${WINGED_PYTHON:-$(python3 -c 'import sys; print(sys.executable)' 2>/dev/null || true)}"
        if [ -z "$WINGED_PYTHON" ]; then
            echo "winged clients: need jq or python3 to read JSON" >&2
            exit 1
        fi
        export WINGED_PYTHON
        ;;
    *)
        echo "winged clients: WINGED_JSON must be jq or python3, not $WINGED_JSON" >&2
        exit 1
        ;;
esac

# json_select LIST JSON EXPR...: the engine of `field` (LIST empty) and `rows`.
json_select() {
    local list="$1" json="$2"
    shift 2
    if [ "$WINGED_JSON" = python3 ]; then
        printf '%s' "$json" | "$WINGED_PYTHON" -c '
import json, sys

def at(v, expr):
    for k in expr.split(".") if expr else []:
        if k == "length":
            v = len(v)
        elif isinstance(v, list):
            v = v[int(k)]
        else:
            v = v[k]
    return v

def text(v):
    if isinstance(v, (dict, list)):
        return json.dumps(v, separators=(",", ":"))
    if v is None:
        return "null"
    if isinstance(v, bool):
        return "true" if v else "false"
    return str(v)

doc = json.load(sys.stdin)
items = at(doc, sys.argv[1]) if sys.argv[1] else [doc]
for item in items:
    print("\t".join(text(at(item, e)) for e in sys.argv[2:]))
' "$list" "$@"
    else
        local e filter="" sep=""
        for e in "$@"; do
            filter+="$sep($(jq_path "$e"))"
            sep=", "
        done
        local each="."
        [ -z "$list" ] || each="$(jq_path "$list")[]"
        printf '%s' "$json" | jq -r "$each | [$filter]"' | map(if type == "object" or type == "array" then tojson elif . == null then "null" else tostring end) | @tsv'
    fi
}

# jq_path EXPR: a dotted path as a jq filter ("bodies.0.id" -> ".bodies[0].id").
jq_path() {
    printf '%s' "$1" | sed -E 's/\.length$/|length/; s/^length$/length/; s/\.([0-9]+)/[\1]/g; s/^([^|])/.\1/; s/^\.\[/[/; s/^$/./'
}

# expect WHAT GOT WANT: stops the script unless the text GOT equals WANT.
expect() {
    if [ "$2" != "$3" ]; then
        echo "winged clients: $1 is $2, expected $3" >&2
        exit 1
    fi
}

# expect_num WHAT GOT WANT: stops the script unless the number GOT equals WANT to 1e-9.
expect_num() {
    if ! awk -v a="$2" -v b="$3" 'BEGIN { d = a - b; exit !(a != "" && d < 1e-9 && d > -1e-9) }'; then
        echo "winged clients: $1 is $2, expected $3" >&2
        exit 1
    fi
}
