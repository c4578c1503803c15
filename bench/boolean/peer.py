#!/usr/bin/env python3
"""manifold3d's side of the boolean side-by-side, and the comparison table.

Reads the scenes written by `cargo run --release --example boolean_side -- write --dir D`
(the triangle OFF files, the same faces winged reads as polygons), times manifold3d's
boolean on each (best of --repeat; manifold evaluates lazily, so the result is forced with
num_tri() inside the timer; building the input Manifolds is not timed, as winged's
from_polygons of its inputs is not), and, where `boolean_side run` left winged's result
in D/winged/, the volume of the symmetric difference (W - M) + (M - W) between the two
results relative to the inputs' total volume. Prints a Markdown table and writes
D/peer.json.

    python bench/boolean/peer.py D [--repeat 5] [--only NAME]
"""

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import manifold3d as m3d


def read_triangles(path):
    """Loci (n x 3 float64) and triangles (m x 3 uint64) of a triangle OFF file."""
    words = Path(path).read_text().split()
    if not words or words[0] != "OFF":
        raise ValueError(f"{path}: not an OFF file")
    nv, nf = int(words[1]), int(words[2])
    at = 4
    verts = np.array(words[at : at + 3 * nv], dtype=np.float64).reshape(nv, 3)
    at += 3 * nv
    faces = np.array(words[at : at + 4 * nf], dtype=np.int64).reshape(nf, 4)
    if nf and not (faces[:, 0] == 3).all():
        raise ValueError(f"{path}: a face that is not a triangle")
    tris = faces[:, 1:]
    if nf and (tris.min() < 0 or tris.max() >= nv):
        raise ValueError(f"{path}: an index past the vertex list")
    return verts, tris.astype(np.uint64)


def manifold_of(path):
    """A Manifold from a triangle OFF file, in double precision (Mesh64)."""
    verts, tris = read_triangles(path)
    mesh = m3d.Mesh64(vert_properties=np.ascontiguousarray(verts), tri_verts=np.ascontiguousarray(tris))
    solid = m3d.Manifold(mesh)
    if solid.status() != m3d.Error.NoError:
        raise ValueError(f"{path}: manifold3d refuses it: {solid.status()}")
    return solid


def evaluate(inputs, op):
    """The boolean `op` of `inputs`, forced (manifold3d evaluates lazily)."""
    if len(inputs) == 2:
        a, b = inputs
        result = {"difference": lambda: a - b, "intersection": lambda: a ^ b, "union": lambda: a + b}[op]()
    else:
        kind = {"difference": m3d.OpType.Subtract, "intersection": m3d.OpType.Intersect, "union": m3d.OpType.Add}[op]
        result = m3d.Manifold.batch_boolean(inputs, kind)
    result.num_tri()
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dir", type=Path)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--only")
    args = parser.parse_args()
    try:
        scenes = json.loads((args.dir / "scenes.json").read_text())
    except (OSError, ValueError) as e:
        sys.exit(f"{args.dir / 'scenes.json'}: {e} (run boolean_side write first)")
    try:
        winged = json.loads((args.dir / "winged.json").read_text())
    except (OSError, ValueError):
        winged = {}
    rows, report = [], {}
    for scene in scenes:
        name = scene["name"]
        if args.only and args.only != name:
            continue
        inputs = [manifold_of(args.dir / p) for p in scene["tri_inputs"]]
        volume_in = sum(s.volume() for s in inputs)
        runs = []
        for _ in range(max(1, args.repeat)):
            start = time.perf_counter()
            result = evaluate(inputs, scene["op"])
            runs.append(time.perf_counter() - start)
        best = min(runs)
        entry = {"best_s": best, "runs_s": runs, "triangles_in": sum(scene["triangles"]),
                 "triangles_out": result.num_tri(), "volume": result.volume(), "volume_in": volume_in}
        w = winged.get(name, {})
        w_best, sym = w.get("best_s"), None
        if w.get("status") == "ok":
            try:
                mine = manifold_of(args.dir / "winged" / f"{name}.tri.off")
                sym = ((mine - result) + (result - mine)).volume() / volume_in
                entry["winged_volume"] = mine.volume()
            except ValueError as e:
                entry["winged_output"] = str(e)
        entry["symmetric_difference"] = sym
        report[name] = entry
        rows.append((name, entry, w_best, w.get("status", "not run"), sym))
    print("| scene | triangles in | manifold3d best (ms) | winged best (ms) | winged / manifold3d "
          "| triangles out (manifold3d) | sym. difference / input volume | winged status |")
    print("|---|---:|---:|---:|---:|---:|---:|---|")
    for name, e, w_best, status, sym in rows:
        ratio = f"{w_best / e['best_s']:.2f}" if w_best else "—"
        wms = f"{w_best * 1e3:.3f}" if w_best else "—"
        s = f"{sym:.2e}" if sym is not None else "—"
        print(f"| {name} | {e['triangles_in']} | {e['best_s'] * 1e3:.3f} | {wms} | {ratio} "
              f"| {e['triangles_out']} | {s} | {status[:60]} |")
    (args.dir / "peer.json").write_text(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
