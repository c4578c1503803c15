"""The LINE-2D baseline of the recognition benchmark (OpenCV's `cv2.linemod`, from
opencv-contrib-python-headless), and its F1 beside winged's.

For every scene, one template per model body: the model drawn by winged where the model
has the body (`model_NNN.png`, grey) with the body's visible pixels as the mask
(`model_bodies_NNN.png`, written by `recognition_bench run`). LINE-2D's default detector
(quantized gradient orientations, spread, two pyramid levels) matches the templates
against the truth's picture; a body is "there" when a match of its template lies within
the search bound of where the model has it (36 px, as the chamfer baseline) with a
similarity of at least a threshold, swept from 60 to 90 on the same scenes (a favour to
the baseline: the best F1 is the one to beat). A body whose visible part gives LINE-2D
too few features for a template is "not there". F1 of "there" over the bodies the truth
makes at least 30 % visible plus the removed ones, for LINE-2D and winged's `image` run;
the time per picture is the matching's (the templates are made beforehand, as the
chamfer baseline's are).

    python linemod.py DIR
"""

import json
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from baseline import judged, print_table, tally, winged_there

REACH = 36
THRESHOLDS = (60, 70, 80, 90)
LOWEST = min(THRESHOLDS)
# Features per template: LINE-2D's default (63), and fewer, which lets the small bodies
# of these scenes have templates at all; both are swept.
FEATURES = (63, 31)


def as_colour(grey):
    """LINE-2D's gradient modality reads three channels: the grey picture in each."""
    return cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR)


def main():
    folder = Path(sys.argv[1])
    counts = {}
    times = {}
    no_template = {}
    for path in sorted(folder.glob("edges_*.json")):
        i = path.stem.split("_")[1]
        model_path = folder / f"model_{i}.png"
        if not model_path.exists():
            continue
        names = json.loads(path.read_text())["names"]
        scene = json.loads((folder / f"scene_{i}.json").read_text())
        truth = json.loads((folder / f"truth_{i}.json").read_text())
        answer = json.loads((folder / f"winged_{i}.json").read_text())
        fates = {f["name"]: f["fate"] for f in scene["fates"]}
        model = as_colour(cv2.imread(str(model_path), cv2.IMREAD_GRAYSCALE))
        bodies = cv2.imread(str(folder / f"model_bodies_{i}.png"), cv2.IMREAD_GRAYSCALE)
        picture = as_colour(cv2.imread(str(folder / f"image_{i}.png"), cv2.IMREAD_GRAYSCALE))
        best = {}
        for features in FEATURES:
            # The default detector's settings but for the number of features.
            gradients = cv2.linemod.ColorGradient_create(10.0, features, 55.0)
            detector = cv2.linemod.Detector([gradients], [4, 8])
            where = {}
            for k, name in enumerate(names):
                if name is None or name not in fates:
                    continue
                mask = np.where(bodies == k + 1, 255, 0).astype(np.uint8)
                if not mask.any():
                    continue
                template, box = detector.addTemplate([model], name, mask)
                if template < 0:
                    no_template[features] = no_template.get(features, 0) + 1
                    continue
                where[name] = box[:2]
            start = time.perf_counter()
            matches, _ = detector.match([picture], LOWEST, list(where)) if where else ([], None)
            times.setdefault(features, []).append((time.perf_counter() - start) * 1e3)
            for m in matches:
                x, y = where[m.class_id]
                if abs(m.x - x) <= REACH and abs(m.y - y) <= REACH:
                    key = (features, m.class_id)
                    best[key] = max(best.get(key, 0.0), m.similarity)
        winged = winged_there(answer)
        predicted = set(winged)
        for name, truly in judged(scene, truth, predicted):
            said_by = [("winged", winged[name])] + [
                (f"LINE-2D, {n} features, ≥ {t}", best.get((n, name), 0.0) >= t)
                for n in FEATURES
                for t in THRESHOLDS
            ]
            tally(counts, said_by, truly)
    for n in FEATURES:
        print(f"LINE-2D, {n} features: {no_template.get(n, 0)} bodies gave too few for a template")
    print_table(
        counts,
        lambda m: next((times[n] for n in FEATURES if m.startswith(f"LINE-2D, {n} ")), None),
    )


if __name__ == "__main__":
    main()
