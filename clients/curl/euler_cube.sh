#!/usr/bin/env bash
# A cube built with the Euler operators, step by step, as Baumgart's GEOMED chapter
# builds it: MKBFV, three MKEVs to a wire, an MKFE closing it to a lamina, four MKEV
# spurs up from the lamina's corners, and four MKFEs tying the spurs' tips. Then it reads
# the cube's topology back (F=6, E=12, V=8), moves it, and deletes it.
#
#   WINGED=http://127.0.0.1:7878 bash clients/curl/euler_cube.sh
set -euo pipefail
. "$(dirname "$0")/lib.sh"

echo "# MKBFV: a body with one face and one vertex at (1, 1, -1)"
r=$(call POST /v1/bodies '{"shape": {"type": "seminal", "position": [1, 1, -1]}}')
IFS=$'\t' read -r body f v1 <<<"$(field "$r" id face vertex)"

echo "# MKEV x3: a wire of four vertices along the bottom square"
r=$(call POST "/v1/bodies/$body/euler" "{\"op\": \"mkev\", \"face\": $f, \"vertex\": $v1, \"position\": [-1, 1, -1]}")
v2=$(field "$r" vertex)
r=$(call POST "/v1/bodies/$body/euler" "{\"op\": \"mkev\", \"face\": $f, \"vertex\": $v2, \"position\": [-1, -1, -1]}")
v3=$(field "$r" vertex)
r=$(call POST "/v1/bodies/$body/euler" "{\"op\": \"mkev\", \"face\": $f, \"vertex\": $v3, \"position\": [1, -1, -1]}")
v4=$(field "$r" vertex)

echo "# MKFE: close the wire from v1 to v4, a lamina; the answer's face is the new one"
r=$(call POST "/v1/bodies/$body/euler" "{\"op\": \"mkfe\", \"v1\": $v1, \"face\": $f, \"v2\": $v4}")
top=$(field "$r" face)

echo "# MKEV x4: a spur from each corner up to z = +1, all into the new face"
corners=("$v1" "$v2" "$v3" "$v4")
above=("[1, 1, 1]" "[-1, 1, 1]" "[-1, -1, 1]" "[1, -1, 1]")
tips=()
for i in 0 1 2 3; do
    r=$(call POST "/v1/bodies/$body/euler" "{\"op\": \"mkev\", \"face\": $top, \"vertex\": ${corners[$i]}, \"position\": ${above[$i]}}")
    tips+=("$(field "$r" vertex)")
done

echo "# MKFE x4: tie the tips in order, making the four sides"
for i in 0 1 2 3; do
    a="${tips[$i]}"
    b="${tips[$(((i + 1) % 4))]}"
    r=$(call POST "/v1/bodies/$body/euler" "{\"op\": \"mkfe\", \"v1\": $a, \"face\": $top, \"v2\": $b}")
done
IFS=$'\t' read -r nf ne nv <<<"$(field "$r" faces edges vertices)"
echo "counts after the last MKFE: F=$nf E=$ne V=$nv"

echo "# The topology: Baumgart's winged edges, faces and vertices"
t=$(BRIEF=1 call GET "/v1/bodies/$body/topology")
IFS=$'\t' read -r nf ne nv <<<"$(field "$t" faces.length edges.length vertices.length)"
expect "F" "$nf" 6
expect "E" "$ne" 12
expect "V" "$nv" 8
echo "topology: F=$nf E=$ne V=$nv; every face has four corners:"
rows "$t" faces id vertices plane | while IFS=$'\t' read -r id vs plane; do
    echo "  face $id: vertices $vs, plane $plane"
done
expect "faces with four corners" "$(rows "$t" faces vertices.length | grep -c '^4$')" 6

r=$(call GET "/v1/bodies/$body")
IFS=$'\t' read -r euler volume <<<"$(field "$r" euler volume)"
expect_num "volume" "$volume" 8
echo "body $body: euler $euler, volume $volume"

echo "# Move it 3 m along +x, in the world frame: its pose changes, its loci do not"
call POST "/v1/bodies/$body/transform" '{"op": "translate", "vector": [3, 0, 0], "frame": "world"}' >/dev/null
r=$(call GET "/v1/bodies/$body")
IFS=$'\t' read -r x y z <<<"$(field "$r" world_pose.position.0 world_pose.position.1 world_pose.position.2)"
expect_num "world x" "$x" 3
expect_num "world y" "$y" 0
expect_num "world z" "$z" 0
echo "moved: world position ($x, $y, $z)"

echo "# Delete it (KLBFEV)"
r=$(call DELETE "/v1/bodies/$body")
IFS=$'\t' read -r killed revision <<<"$(field "$r" killed revision)"
expect "killed" "$killed" "[$body]"

echo "euler_cube: ok (body $body: F=6 E=12 V=8, volume 8, moved, deleted at revision $revision)"
