"""The recognition benchmark's figures, from the scenes, the truth `render.py` drew and
winged's answers (`recognition_bench run`).

    python report.py DIR

Per run (`image`: the picture alone, exact camera; `depth`: with the depth picture;
`refine`: the picture alone from a camera up to 2 deg and 5 cm off, with refine_camera):

* bodies at least 30 % visible in the truth (visible pixels over whole projected pixels,
  both from the truth's renderer): precision and recall of "there" (seen or moved) against
  the truth (stays or moved); bodies 10-30 % visible: recall;
* moved bodies: the share whose answered motion puts every corner within 1 cm of a true
  corner and turns by less than 1 deg from the truth's turn or from a symmetric twin of
  it (a cylinder's sides, a prism's, a square pyramid's); a moved body not reported moved
  counts as a miss;
* removed bodies reported absent; bodies that are there reported absent;
* unexplained regions: pixel IoU with the distractors' visible pixels, over the scenes
  that have distractors (union over scenes);
* visible_fraction: the share of bodies there and reported there whose fraction is
  within 0.02 of the truth's, and the median error;
* time per picture: median and p90, ms.
"""

import json
import sys
from pathlib import Path

import numpy as np


def decode_runs(runs, size):
    bits = np.zeros(size, dtype=bool)
    at, value = 0, False
    for n in runs:
        bits[at : at + n] = value
        at += n
        value = not value
    return bits


def quat_rotate(q, v):
    x, y, z, w = q
    u = np.array([x, y, z])
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


def angle_between(q1, q2):
    d = abs(float(np.dot(q1, q2)))
    return np.degrees(2.0 * np.arccos(min(1.0, d)))


def quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ])


def symmetries(corners):
    """The turns about the vertical axis through the corners' centre that map the corner
    set onto itself (the identity first), as quaternions: a cylinder's 24 sides, a
    prism's n, a square pyramid's 4 show the same body turned by these."""
    corners = np.unique(np.round(corners, 9), axis=0)
    centre = corners.mean(axis=0)
    scale = np.linalg.norm(corners - centre, axis=1).max()
    found = [np.array([0.0, 0.0, 0.0, 1.0])]
    for n in (2, 3, 4, 5, 6, 24):
        for k in range(1, n):
            a = 2 * np.pi * k / n
            q = np.array([0.0, 0.0, np.sin(a / 2), np.cos(a / 2)])
            turned = np.array([quat_rotate(q, c - centre) + centre for c in corners])
            gaps = np.linalg.norm(turned[:, None, :] - corners[None, :, :], axis=2).min(axis=1)
            if gaps.max() < 1e-6 * scale:
                found.append(q)
    return found


def corners_of(scene, name):
    for body in scene["triangles"]:
        if body["name"] == name:
            return np.array(body["triangles"]).reshape(-1, 3)
    return None


def main():
    folder = Path(sys.argv[1])
    stats = {}
    for path in sorted(folder.glob("winged_*.json")):
        i = path.stem.split("_")[1]
        answer = json.loads(path.read_text())
        scene = json.loads((folder / f"scene_{i}.json").read_text())
        truth = json.loads((folder / f"truth_{i}.json").read_text())
        fates = {f["name"]: f for f in scene["fates"]}
        k = scene["camera"]["intrinsics"]
        size = k["width"] * k["height"]
        distractor = decode_runs(truth["distractor_runs"], size)
        for run in answer["runs"]:
            s = stats.setdefault(
                run["run"],
                {
                    "tp": 0, "fp": 0, "fn": 0, "low_there": 0, "low_found": 0,
                    "moved": 0, "moved_ok": 0, "removed": 0, "removed_absent": 0,
                    "there": 0, "there_absent": 0, "inter": 0, "union": 0,
                    "vf_errors": [], "ms": [], "errors": 0, "runs": 0, "kinds": {},
                },
            )
            s["runs"] += 1
            s["ms"].append(run["ms"])
            if "error" in run:
                s["errors"] += 1
                continue
            reported = {b["name"]: b for b in run["bodies"]}
            for name, fate in fates.items():
                whole = truth["whole_px"].get(name, 0)
                # A removed body's visibility is the model's: use the answer's fraction.
                if fate["fate"] == "removed":
                    if name in reported:
                        s["removed"] += 1
                        s["removed_absent"] += reported[name]["status"] == "absent"
                        if reported[name]["visible_fraction"] >= 0.3:
                            s["fp"] += reported[name]["status"] in ("seen", "moved")
                    continue
                visible = truth["visible_px"].get(name, 0) / whole if whole else 0.0
                r = reported.get(name)
                said_there = r is not None and r["status"] in ("seen", "moved")
                if visible >= 0.3:
                    s["tp"] += said_there
                    s["fn"] += not said_there
                elif visible >= 0.1:
                    s["low_there"] += 1
                    s["low_found"] += said_there
                if r is not None:
                    s["there"] += 1
                    s["there_absent"] += r["status"] == "absent"
                    if said_there:
                        s["vf_errors"].append(abs(r["visible_fraction"] - visible))
                if fate["fate"] == "moved" and visible >= 0.1:
                    s["moved"] += 1
                    kind = s["kinds"].setdefault(name.rstrip("0123456789"), [0, 0])
                    kind[1] += 1
                    if r is not None and r["status"] == "moved" and r["motion"]:
                        m, t = r["motion"], fate["motion"]
                        corners = corners_of(scene, name)
                        # The truth's triangles are the moved body: carry them back.
                        tq = np.array(t["rotation"])
                        tp = np.array(t["position"])
                        inv = np.array([-tq[0], -tq[1], -tq[2], tq[3]])
                        original = np.array([quat_rotate(inv, c - tp) for c in corners])
                        got = np.array(
                            [quat_rotate(np.array(m["rotation"]), c) + np.array(m["position"])
                             for c in original]
                        )
                        # Up to the body's symmetries: each answered corner's distance to
                        # the nearest true corner, and the least turn to a symmetric twin.
                        error = np.linalg.norm(
                            got[:, None, :] - corners[None, :, :], axis=2
                        ).min(axis=1).max()
                        angle = min(
                            angle_between(np.array(m["rotation"]), quat_mul(q, tq))
                            for q in symmetries(corners)
                        )
                        ok = error < 0.01 and angle < 1.0
                        s["moved_ok"] += ok
                        kind[0] += ok
            if distractor.any():
                mask = decode_runs(run["mask_runs"], size)
                s["inter"] += int((mask & distractor).sum())
                s["union"] += int((mask | distractor).sum())
    print("| run | scenes | precision (≥30 %) | recall (≥30 %) | recall (10–30 %) | moved within 1 cm, 1° | removed → absent | there → absent | unexplained IoU | visible fraction within 0.02 | median / p90 ms | refused |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, s in stats.items():
        div = lambda a, b: a / b if b else float("nan")
        vf = np.array(s["vf_errors"]) if s["vf_errors"] else np.array([np.nan])
        ms = np.array(s["ms"])
        print(
            f"| {name} | {s['runs']} | {div(s['tp'], s['tp'] + s['fp']):.3f} | "
            f"{div(s['tp'], s['tp'] + s['fn']):.3f} ({s['tp']}/{s['tp'] + s['fn']}) | "
            f"{div(s['low_found'], s['low_there']):.3f} ({s['low_found']}/{s['low_there']}) | "
            f"{div(s['moved_ok'], s['moved']):.3f} ({s['moved_ok']}/{s['moved']}) | "
            f"{div(s['removed_absent'], s['removed']):.3f} ({s['removed_absent']}/{s['removed']}) | "
            f"{div(s['there_absent'], s['there']):.4f} ({s['there_absent']}/{s['there']}) | "
            f"{div(s['inter'], s['union']):.3f} | "
            f"{float(np.mean(vf <= 0.02)):.3f} (median {float(np.median(vf)):.4f}) | "
            f"{np.median(ms):.0f} / {np.percentile(ms, 90):.0f} | {s['errors']} |"
        )

    kinds = sorted({k for s in stats.values() for k in s["kinds"]})
    print()
    print("Moved bodies within 1 cm and 1°, by kind:")
    print()
    print("| run | " + " | ".join(kinds) + " |")
    print("|---|" + "---:|" * len(kinds))
    for name, s in stats.items():
        cells = []
        for k in kinds:
            ok, n = s["kinds"].get(k, (0, 0))
            cells.append(f"{ok / n:.2f} ({ok}/{n})" if n else "–")
        print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
