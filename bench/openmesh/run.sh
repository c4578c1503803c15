#!/usr/bin/env bash
# Runs the OpenMesh peer program and winged's equivalent (examples/kernel_peer.rs) in one
# go and prints the two side by side with their ratio.
#
#   bash bench/openmesh/run.sh            # every measure (about 30 s of running)
#   bash bench/openmesh/run.sh esplit     # measures whose name contains "esplit"
#   RUNS=1 bash bench/openmesh/run.sh     # one run of each program instead of two
#
# The two programs run alternately RUNS times (default 2) and each figure is the lowest
# seen, so that a burst of load from elsewhere on a shared machine hits both sides alike.
#
# Needs Debian's libopenmesh-dev (installed here when missing, as root) and g++.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
out="$repo/target/openmesh"
filter="${1:-}"
runs="${RUNS:-2}"

if ! dpkg -s libopenmesh-dev >/dev/null 2>&1; then
    echo "installing libopenmesh-dev ..." >&2
    if [ "$(id -u)" -eq 0 ]; then
        apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libopenmesh-dev >&2
    else
        sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libopenmesh-dev >&2
    fi
fi

mkdir -p "$out"
echo "compiling split_collapse.cpp ..." >&2
g++ -O2 -DNDEBUG -std=c++17 -o "$out/split_collapse" "$here/split_collapse.cpp" -lOpenMeshCore
echo "building examples/kernel_peer.rs ..." >&2
(cd "$repo" && cargo build --release --quiet --example kernel_peer)

: >"$out/openmesh.all"
: >"$out/winged.all"
for i in $(seq "$runs"); do
    echo "run $i/$runs: OpenMesh ..." >&2
    "$out/split_collapse" $filter >>"$out/openmesh.all"
    echo "run $i/$runs: winged ..." >&2
    "$repo/target/release/examples/kernel_peer" $filter >>"$out/winged.all"
done
# The lowest figure of each measure, in first-seen order.
lowest() {
    awk -F'\t' '{ if (!($1 in v)) { o[++n] = $1; v[$1] = $2; u[$1] = $3 } else if ($2 + 0 < v[$1] + 0) v[$1] = $2 }
        END { for (i = 1; i <= n; i++) printf "%s\t%s\t%s\n", o[i], v[o[i]], u[o[i]] }' "$1"
}
lowest "$out/openmesh.all" >"$out/openmesh.tsv"
lowest "$out/winged.all" >"$out/winged.tsv"

echo "# $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) cores;" \
    "OpenMesh $(dpkg-query -W -f '${Version}' libopenmesh-dev); $(rustc --version)"
echo "# lowest of $runs runs x 3 repetitions each (10 for the perimeter walks); every figure is a cost, so ratio < 1 means winged is cheaper"
# Rows only the OpenMesh program has (e.g. *_checked) compare with winged's row of the
# same name without the suffix: winged's operators always check their preconditions.
awk -F'\t' '
    NR == FNR { w[$1] = $2; next }
    {
        name = $1; base = name; sub(/_checked$/, "", base)
        om[name] = $2; unit[name] = $3; order[++n] = name; wv[name] = (base in w) ? w[base] : ""
    }
    END {
        printf "%-28s %12s %12s  %-8s %8s\n", "measure", "winged", "OpenMesh", "unit", "ratio"
        for (i = 1; i <= n; i++) {
            k = order[i]
            r = (wv[k] != "" && om[k] > 0) ? sprintf("%.2f", wv[k] / om[k]) : "-"
            printf "%-28s %12s %12s  %-8s %8s\n", k, (wv[k] != "" ? wv[k] : "-"), om[k], unit[k], r
        }
    }' "$out/winged.tsv" "$out/openmesh.tsv"
