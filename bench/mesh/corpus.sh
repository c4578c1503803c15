#!/usr/bin/env bash
# Real mesh files from elsewhere, over real HTTP: every glTF, GLB, OBJ, STL, PLY and 3MF
# of Debian's assimp-testmodels (its deliberately broken files too) and every OFF of
# libcgal-demo's data, demo and example archives, each POSTed to
# /v1/bodies/import?format=EXT on a live `winged serve --memory`. Each must import
# (201) or be refused with a 4xx problem+json; a 5xx, a hang (60 s) or a server that
# stops answering fails the run. Prints one line per file and the counts per format.
#
# Usage: bench/mesh/corpus.sh [release]   (installs the two Debian packages if missing;
#        "release" serves a release build, else the debug one cargo test builds)
set -euo pipefail
cd "$(dirname "$0")/../.."

assimp=/usr/share/assimp/models
cgal_archives=/usr/share/doc/libcgal-dev
if [[ ! -d $assimp || ! -f $cgal_archives/data.tar.gz ]]; then
    echo "corpus: installing assimp-testmodels and libcgal-demo"
    sudo=""; [[ $(id -u) -ne 0 ]] && sudo=sudo
    $sudo apt-get install -y --no-install-recommends assimp-testmodels libcgal-demo >/dev/null
fi

target=${CARGO_TARGET_DIR:-target}
if [[ ${1:-} == release ]]; then
    cargo build --locked --quiet --release --bin winged
    bin=$target/release/winged
else
    cargo build --locked --quiet --bin winged
    bin=$target/debug/winged
fi

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

for a in data demo examples; do
    tar xzf "$cgal_archives/$a.tar.gz" -C "$work" 2>/dev/null || true
done

RUST_LOG=info "$bin" serve --memory --addr 127.0.0.1:0 >"$work/server.log" 2>&1 &
server=$!
base=
for _ in $(seq 1 100); do
    base=$(grep -o 'http://127\.0\.0\.1:[0-9]*' "$work/server.log" | head -n 1 || true)
    [[ -n $base ]] && break
    sleep 0.1
done
[[ -n $base ]] || { echo "the server did not start" >&2; cat "$work/server.log" >&2; exit 1; }

files=$(
    find "$assimp" -type f \( -iname '*.gltf' -o -iname '*.glb' -o -iname '*.obj' \
        -o -iname '*.stl' -o -iname '*.ply' -o -iname '*.3mf' \)
    find "$work" -type f -iname '*.off'
)
failures=0
declare -A total made refused
while IFS= read -r file; do
    [[ -n $file ]] || continue
    ext=${file##*.}; ext=${ext,,}
    code=$(curl -s -o "$work/answer" -w '%{http_code}' --max-time 60 \
        --data-binary "@$file" -H 'Content-Type: application/octet-stream' \
        "$base/v1/bodies/import?format=$ext" || echo 000)
    total[$ext]=$(( ${total[$ext]:-0} + 1 ))
    what=$(python3 -c 'import json,sys
try:
    a = json.load(open(sys.argv[1]))
except Exception:
    print("(not JSON)"); sys.exit()
if "bodies" in a:
    print(len(a["bodies"]), "bodies,", sum(b["faces"] for b in a["bodies"]), "faces")
else:
    print(a.get("type", "?").rsplit(":", 1)[-1] + ": " + a.get("detail", "")[:150])' "$work/answer")
    case $code in
        201)
            made[$ext]=$(( ${made[$ext]:-0} + 1 ))
            # Clear the world for the next file (names in files repeat).
            python3 -c 'import json,sys; [print(b["id"]) for b in json.load(open(sys.argv[1]))["bodies"] if b["parent"] == 1]' "$work/answer" |
                while read -r id; do curl -s -o /dev/null -X DELETE "$base/v1/bodies/$id"; done
            ;;
        4??) refused[$ext]=$(( ${refused[$ext]:-0} + 1 )) ;;
        *) failures=$((failures + 1)) ;;
    esac
    printf '%s %s: %s\n' "$code" "${file#"$work"/}" "$what"
    if ! curl -s -o /dev/null --max-time 10 "$base/healthz"; then
        echo "the server stopped answering after $file" >&2
        exit 1
    fi
done <<<"$files"

echo
echo "format  files  imported  refused (4xx)  other"
for ext in $(printf '%s\n' "${!total[@]}" | sort); do
    t=${total[$ext]}; m=${made[$ext]:-0}; r=${refused[$ext]:-0}
    printf '%-6s  %5d  %8d  %13d  %5d\n' "$ext" "$t" "$m" "$r" $((t - m - r))
done
if [[ $failures -ne 0 ]]; then
    echo "corpus: $failures files got a 5xx or no answer" >&2
    exit 1
fi
echo "corpus: no 5xx, no hang, the server answered throughout"
