"""Puts winged's and OpenCV's camera-solution figures side by side and checks the goals.

    python report.py WINGED.json OPENCV.json

Reads the outputs of examples/solve_bench.rs and bench/solve/peer.py (same sets, same
layout) and prints a Markdown table per kind of set, then the issue's checks:

* accuracy: on every outlier-free set, winged's SQPnP median rotation and translation
  errors within 5 % of OpenCV's SQPnP (cv.SQPNP) on the same problems;
* no failure (rotation error over 5 degrees, or no answer) for n >= 6, for winged's
  sqpnp and solve_pnp;
* robustness: no failure of solve_pnp up to 80 % outliers;
* speed: sqpnp <= 15 us per solve for n <= 200; solve_pnp <= 3 ms at 70 % outliers.

OpenCV's times include Python's call overhead (`call_overhead_us`, printed); the
table gives them as measured. Exits with status 1 when a check fails, so a run shows it.
"""

import json
import sys
from pathlib import Path

WITHIN = 1.05


def load(path):
    data = json.loads(Path(path).read_text())
    return data, {(r["set"], r["solver"]): r for r in data["rows"]}


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    ours_meta, ours = load(sys.argv[1])
    peer_meta, peer = load(sys.argv[2])
    sets = list(dict.fromkeys(s for s, _ in list(ours) + list(peer)))
    if ours_meta["threshold_px"] != peer_meta.get("threshold_px"):
        sys.exit("the two runs used different inlier thresholds")
    print(f"winged: {ours_meta['library']}, inlier threshold {ours_meta['threshold_px']} px")
    print(
        f"peer: {peer_meta['library']}, the same threshold; Python call overhead "
        f"{peer_meta['call_overhead_us']:.2f} us per call (included in its times)"
    )
    print()
    print("| set | solver | median time | p90 time | median rotation error "
          "| median translation error | failures |")
    print("|---|---|---|---|---|---|---|")
    rows = {**ours, **peer}
    for s in sets:
        for solver in ["sqpnp", "cv.SQPNP", "cv.EPNP", "solve_pnp", "cv.ransac", "cv.magsac"]:
            # (winged's focal-length rows have a table of their own below)
            r = rows.get((s, solver))
            if r is None:
                continue
            print(
                f"| {s} | {solver} | {fmt_time(r['median_us'])} | {fmt_time(r['p90_us'])} "
                f"| {r['rot_deg']:.4f}° | {r['trans_pct']:.3f} % "
                f"| {r['failures']} / {r['trials']} |"
            )
    focal = [(s, r) for (s, solver), r in ours.items() if solver == "focal"]
    if focal:
        print()
        print("winged's `solve_pnp_focal` (focal length unknown; its error relative to 800 px):")
        print()
        print("| set | median time | median rotation error | median focal error "
              "| failures or refusals |")
        print("|---|---|---|---|---|")
        for s, r in focal:
            print(
                f"| {s} | {fmt_time(r['median_us'])} | {r['rot_deg']:.4f}° "
                f"| {r.get('focal_pct', float('nan')):.3f} % | {r['failures']} / {r['trials']} |"
            )
    print()
    failed = []

    def check(ok, text):
        print(f"- [{'x' if ok else ' '}] {text}")
        if not ok:
            failed.append(text)

    for s in sets:
        ours_r, cv_r = ours.get((s, "sqpnp")), peer.get((s, "cv.SQPNP"))
        if ours_r and cv_r:
            rot = ours_r["rot_deg"] / cv_r["rot_deg"]
            trans = ours_r["trans_pct"] / cv_r["trans_pct"]
            check(
                rot <= WITHIN and trans <= WITHIN,
                f"{s}: sqpnp / cv.SQPNP median errors {rot:.3f} (rotation), "
                f"{trans:.3f} (translation), within {WITHIN}",
            )
    for (s, solver), r in sorted(ours.items(), key=lambda item: sets.index(item[0][0])):
        if solver == "focal":
            continue
        n = int(s.split("_")[0][1:])
        outliers = int(s.split("_out")[1]) if "_out" in s else 0
        if n >= 6 and outliers <= 80:
            check(r["failures"] == 0, f"{s}: {solver} {r['failures']} failures")
        if solver == "sqpnp" and n <= 200:
            check(r["median_us"] <= 15.0, f"{s}: sqpnp {r['median_us']:.1f} us <= 15 us")
        if solver == "solve_pnp" and outliers == 70:
            check(
                r["median_us"] <= 3000.0,
                f"{s}: solve_pnp {r['median_us']:.0f} us <= 3 ms",
            )
    print()
    print(f"{len(failed)} checks failed" if failed else "all checks passed")
    sys.exit(1 if failed else 0)


def fmt_time(us):
    return f"{us / 1000:.2f} ms" if us >= 1000 else f"{us:.1f} µs"


if __name__ == "__main__":
    main()
