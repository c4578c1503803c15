#!/usr/bin/env bash
# A tour of the demo scene (start the server with `winged serve --demo`): the world's
# counts, the bodies on the hand-eye table, one body, a block's winged-edge topology, the
# cameras and the light, and what the camera sees. It only reads, so it can run any
# number of times.
#
#   WINGED=http://127.0.0.1:7878 bash clients/curl/demo_tour.sh
set -euo pipefail
. "$(dirname "$0")/lib.sh"

echo "# The world: revision and counts"
r=$(call GET /v1/world)
IFS=$'\t' read -r rev nb nf ne nv <<<"$(field "$r" revision bodies faces edges vertices)"
echo "world: revision $rev, $nb bodies, $nf faces, $ne edges, $nv vertices"

echo "# The table, found by name"
r=$(BRIEF=1 call GET "/v1/bodies?name=table")
if [ "$(field "$r" bodies.length)" = 0 ]; then
    echo "winged clients: no body is named \"table\"; start the server with 'winged serve --demo'" >&2
    exit 1
fi
IFS=$'\t' read -r table position parts <<<"$(field "$r" bodies.0.id bodies.0.world_pose.position bodies.0.parts)"
echo "table: body $table, world position $position, parts $parts"

echo "# Every body, with its parent (the table's parts name it)"
r=$(BRIEF=1 call GET /v1/bodies)
n=$(field "$r" bodies.length)
rows "$r" bodies id name parent euler.F euler.E euler.V volume |
    while IFS=$'\t' read -r id name parent f e v volume; do
        printf '  body %-4s %-8s parent %-3s F=%-3s E=%-3s V=%-3s volume %.6f m3\n' \
            "$id" "$name" "$parent" "$f" "$e" "$v" "$volume"
    done

echo "# One block, and its winged edges"
r=$(call GET "/v1/bodies?name=cube")
cube=$(field "$r" bodies.0.id)
call GET "/v1/bodies/$cube" >/dev/null
t=$(BRIEF=1 call GET "/v1/bodies/$cube/topology")
IFS=$'\t' read -r nf ne nv edge face <<<"$(field "$t" faces.length edges.length vertices.length edges.0 faces.0)"
expect "cube faces" "$nf" 6
echo "cube: body $cube, F=$nf E=$ne V=$nv"
echo "  an edge with its eight links: $edge"
echo "  a face with its plane and corners: $face"

echo "# The cameras and the light"
r=$(BRIEF=1 call GET /v1/cameras)
echo "cameras: $(field "$r" cameras.length)"
r=$(call GET /v1/cameras/eye)
IFS=$'\t' read -r at along w h <<<"$(field "$r" pose.position view_direction intrinsics.width intrinsics.height)"
echo "eye: at $at, looking along $along, ${w}x$h px"
r=$(call GET /v1/lights)
echo "lights: $(field "$r" lights.length)"
r=$(call GET /v1/lights/sun)
IFS=$'\t' read -r along intensity <<<"$(field "$r" direction intensity)"
echo "sun: light travelling along $along, intensity $intensity"

echo "# What the camera eye sees (set OUT=DIR to keep the images)"
out="${OUT:-$(mktemp -d)}"
mkdir -p "$out"
for mode in shaded hidden depth ids; do
    [ "${QUIET:-0}" = 1 ] || echo "\$ curl -o $mode.png \$WINGED/v1/cameras/eye/image?mode=$mode" >&3
    curl -sf -o "$out/$mode.png" "$WINGED/v1/cameras/eye/image?mode=$mode"
    magic=$(head -c 4 "$out/$mode.png" | tail -c 3)
    expect "$mode is a PNG" "$magic" PNG
    echo "  $mode: $(wc -c <"$out/$mode.png") bytes"
done
r=$(BRIEF=1 call GET "/v1/cameras/eye/image?mode=hidden&format=json")
echo "hidden lines: $(field "$r" segments.length) visible segments"
r=$(BRIEF=1 call GET "/v1/cameras/eye/image?mode=ids&format=json")
echo "bodies in view: $(field "$r" bodies.length)"

echo "demo_tour: ok ($n bodies, camera eye, light sun)"
