"""The chamfer-matching baseline of the recognition benchmark, and F1 beside winged's.

For every scene: Canny edges of the picture (OpenCV), their distance transform, and for
each model body its predicted visible edge points where the model has it (the template
`recognition_bench run` wrote to `edges_NNN.json`). The template is slid over image
shifts within the search bound (10 cm at the body's distance, about 30-45 pixels here),
and the body is "there" when the best mean distance (each point's capped at 10 px) is at
most a threshold, swept from 1 to 4 px on the same scenes. F1 of "there" over the bodies the truth makes at least 30 % visible plus
the removed ones (which the model still predicts in view), for the chamfer baseline and
winged's `image` run, and the time per picture.

    python chamfer.py DIR
"""

import json
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from baseline import judged, print_table, tally, winged_there

CAP = 10.0
# The baseline's threshold is swept on the same scenes (a favour to it): the best F1 is
# the one to beat.
THRESHOLDS = (1.0, 1.5, 2.0, 2.5, 3.0, 4.0)
REACH = 36
STEP = 2


def chamfer_score(distance, points):
    """The best mean capped distance of the template over the shifts."""
    if len(points) == 0:
        return np.inf
    h, w = distance.shape
    u = points[:, 0]
    v = points[:, 1]
    best = np.inf
    for dv in range(-REACH, REACH + 1, STEP):
        for du in range(-REACH, REACH + 1, STEP):
            x = np.clip((u + du).astype(int), 0, w - 1)
            y = np.clip((v + dv).astype(int), 0, h - 1)
            best = min(best, float(np.minimum(distance[y, x], CAP).mean()))
    return best


def main():
    folder = Path(sys.argv[1])
    counts = {}
    times = []
    for path in sorted(folder.glob("edges_*.json")):
        i = path.stem.split("_")[1]
        edges = json.loads(path.read_text())
        scene = json.loads((folder / f"scene_{i}.json").read_text())
        truth = json.loads((folder / f"truth_{i}.json").read_text())
        answer = json.loads((folder / f"winged_{i}.json").read_text())
        start = time.perf_counter()
        grey = cv2.imread(str(folder / f"image_{i}.png"), cv2.IMREAD_GRAYSCALE)
        canny = cv2.Canny(cv2.GaussianBlur(grey, (5, 5), 1.0), 30, 90)
        distance = cv2.distanceTransform(255 - canny, cv2.DIST_L2, 3)
        scores = {
            name: chamfer_score(distance, np.array(points).reshape(-1, 4)[:, :2])
            for name, points in zip(edges["names"], edges["points"])
        }
        times.append((time.perf_counter() - start) * 1e3)
        winged = winged_there(answer)
        for name, truly in judged(scene, truth, scores):
            said_by = [("winged", winged.get(name, False))] + [
                (f"chamfer ≤ {t} px", scores[name] <= t) for t in THRESHOLDS
            ]
            tally(counts, said_by, truly)
    print_table(counts, lambda m: times if m.startswith("chamfer") else None)


if __name__ == "__main__":
    main()
