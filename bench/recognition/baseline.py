"""What the baselines of the recognition benchmark share: which bodies are judged, the
tally of "there" against the truth, and the F1 table."""

import numpy as np


def judged(scene, truth, names):
    """The bodies of `names` that are judged, with whether each is truly there: the removed
    ones (not there) and those the truth makes at least 30 % visible (there)."""
    for fate in scene["fates"]:
        name = fate["name"]
        if name not in names:
            continue
        if fate["fate"] == "removed":
            yield name, False
            continue
        whole = truth["whole_px"].get(name, 0)
        if whole and truth["visible_px"].get(name, 0) / whole >= 0.3:
            yield name, True


def tally(counts, said_by, truly):
    """Counts each method's answer (`said_by`: pairs of method and "there") into its true
    positives, false positives and false negatives."""
    for method, said in said_by:
        c = counts.setdefault(method, [0, 0, 0])
        if said and truly:
            c[0] += 1
        elif said:
            c[1] += 1
        elif truly:
            c[2] += 1


def f1(tp, fp, fn):
    return 2 * tp / (2 * tp + fp + fn) if tp else 0.0


def print_table(counts, times_of):
    """The F1 table; `times_of(method)` is the method's times per picture, ms, or None."""
    print("| method | F1 of \"there\" | tp / fp / fn | median ms per picture |")
    print("|---|---:|---:|---:|")
    for method, (tp, fp, fn) in counts.items():
        times = times_of(method)
        ms = f"{np.median(times):.0f}" if times else "see the table above"
        print(f"| {method} | {f1(tp, fp, fn):.3f} | {tp} / {fp} / {fn} | {ms} |")


def winged_there(answer):
    """Whether winged's `image` run said each body is there (seen or moved)."""
    run = next(r for r in answer["runs"] if r["run"] == "image")
    return {b["name"]: b["status"] in ("seen", "moved") for b in run["bodies"]}
