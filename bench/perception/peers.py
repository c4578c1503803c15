#!/usr/bin/env python3
"""The peers' side of the perception side-by-side: manifold3d and Open3D on the inputs
that `perception_side write` wrote, and the comparison table with winged's figures.

For each scene and view count (D/scenes.json, D/SCENE/NN/sights.json):

* manifold3d: each view's cones as `perception_side write` exported them (winged's own
  `cone`, cut into triangles: the same loci, bit for bit, read through Mesh64 in double
  precision) are built into Manifolds, the outer cones intersected
  (`batch_boolean(..., Intersect)`) and the holes' cones subtracted. Timed: building the
  cones' Manifolds and the booleans, forced with `num_tri()` (manifold evaluates
  lazily); best of --repeat.
* Open3D: `VoxelGrid.create_dense` at --resolution³ voxels over the bounding cube of
  manifold3d's hull (one voxel of margin), then `carve_silhouette` with each view's
  mask (as float32, the type it samples) and camera (OpenCV's R and t; the principal
  point moved by half a pixel, since Open3D samples pixel (x, y) at integer
  coordinates while winged's pixel covers [x, x + 1)). Timed: create_dense and the
  carvings; best of --o3d-repeat. Volume: voxels left × voxel size³. Carving keeps a
  voxel when any of its eight corners samples a nonzero mask value (bilinear), so its
  volume runs above the exact hull's by up to about a voxel and a pixel all round.

Prints one Markdown table per scene and writes D/peers.json.

    python bench/perception/peers.py D [--repeat 5] [--o3d-repeat 1] [--o3d-max-views 16]
"""

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

try:
    import manifold3d as m3d
except ImportError:
    m3d = None
try:
    import open3d as o3d
except (ImportError, OSError) as e:  # Open3D's wheel links libusb, which may be missing
    o3d = None
    O3D_WHY = str(e)


def cone_manifolds(sight):
    """(outer cones, hole cones) of one sight as Manifolds."""
    outer, holes = [], []
    for c in sight["cones"]:
        mesh = m3d.Mesh64(
            vert_properties=np.asarray(c["positions"], dtype=np.float64),
            tri_verts=np.asarray(c["triangles"], dtype=np.uint64),
        )
        solid = m3d.Manifold(mesh)
        if solid.status() != m3d.Error.NoError:
            raise ValueError(f"view {sight['view']} ring {c['ring']}: {solid.status()}")
        (outer if c["op"] == "intersect" else holes).append(solid)
    return outer, holes


def manifold_hull(case):
    """The visual hull of a case by manifold3d, forced."""
    outer, holes = [], []
    for s in case["sights"]:
        o, h = cone_manifolds(s)
        outer += o
        holes += h
    hull = m3d.Manifold.batch_boolean(outer, m3d.OpType.Intersect)
    if holes:
        hull = hull - m3d.Manifold.batch_boolean(holes, m3d.OpType.Add)
    hull.num_tri()
    return hull


def open3d_inputs(folder, case):
    """Each view's (mask as float32 Image, PinholeCameraParameters)."""
    out = []
    for s in case["sights"]:
        mask = np.asarray(o3d.io.read_image(str(folder / s["mask"])))
        image = o3d.geometry.Image((mask > 0).astype(np.float32))
        params = o3d.camera.PinholeCameraParameters()
        params.intrinsic = o3d.camera.PinholeCameraIntrinsic(
            s["width"], s["height"], s["fx"], s["fy"], s["cx"] - 0.5, s["cy"] - 0.5
        )
        extrinsic = np.eye(4)
        extrinsic[:3, :3] = np.asarray(s["r_cv"])
        extrinsic[:3, 3] = np.asarray(s["t_cv"])
        params.extrinsic = extrinsic
        out.append((image, params))
    return out


def open3d_hull(views, lo, side, resolution):
    """Open3D's carved voxel grid over the cube of corner `lo` and size `side`."""
    voxel = side / resolution
    grid = o3d.geometry.VoxelGrid.create_dense(lo, np.array([1.0, 1.0, 1.0]), voxel, side, side, side)
    for image, params in views:
        grid.carve_silhouette(image, params)
    return grid, voxel


def best_of(n, f):
    """(best seconds, all seconds, last result) of n runs of f."""
    runs, result = [], None
    for _ in range(max(1, n)):
        start = time.perf_counter()
        result = f()
        runs.append(time.perf_counter() - start)
    return min(runs), runs, result


def fmt(x, spec):
    return "—" if x is None else format(x, spec)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dir", type=Path)
    parser.add_argument("--repeat", type=int, default=5, help="manifold3d runs per case (best kept)")
    parser.add_argument("--o3d-repeat", type=int, default=1, help="Open3D runs per case (best kept)")
    parser.add_argument("--o3d-max-views", type=int, default=16,
                        help="Open3D only on cases of at most this many views (each view costs seconds)")
    parser.add_argument("--resolution", type=int, default=256, help="Open3D's voxels per side")
    parser.add_argument("--only", help="only this scene")
    args = parser.parse_args()
    if m3d is None:
        sys.exit("manifold3d is not installed (pip install manifold3d)")
    if o3d is None:
        print(f"Open3D does not load ({O3D_WHY}); its columns stay empty "
              "(its wheel needs libusb-1.0: apt-get install libusb-1.0-0)", file=sys.stderr)
    try:
        index = json.loads((args.dir / "scenes.json").read_text())
    except (OSError, ValueError) as e:
        sys.exit(f"{args.dir / 'scenes.json'}: {e} (run perception_side write first)")
    try:
        winged = json.loads((args.dir / "winged.json").read_text())
    except (OSError, ValueError):
        winged = {}
    report, rows = {}, {}
    for item in index:
        scene, views = item["scene"], item["views"]
        if args.only and args.only != scene:
            continue
        path = args.dir / item["path"]
        case = json.loads(path.read_text())
        entry = {"views": views, "true_volume": case["true_volume"]}
        best, runs, hull = best_of(args.repeat, lambda: manifold_hull(case))
        entry.update(manifold_best_s=best, manifold_runs_s=runs, manifold_volume=hull.volume(),
                     manifold_triangles=hull.num_tri())
        lo_hi = hull.bounding_box()
        lo, hi = np.array(lo_hi[:3]), np.array(lo_hi[3:])
        if o3d is not None and views <= args.o3d_max_views:
            side = (hi - lo).max() * (1 + 2 / args.resolution)
            corner = (lo + hi) / 2 - side / 2
            inputs = open3d_inputs(path.parent, case)
            best, runs, (grid, voxel) = best_of(
                args.o3d_repeat, lambda: open3d_hull(inputs, corner, side, args.resolution))
            entry.update(open3d_best_s=best, open3d_runs_s=runs,
                         open3d_volume=len(grid.get_voxels()) * voxel**3, open3d_voxel=voxel)
        key = f"{scene}/{views}"
        report[key] = entry
        w = winged.get(key, {})
        rows.setdefault(scene, []).append((views, entry, w))
        print(f"{key}: manifold3d {entry['manifold_best_s'] * 1e3:.1f} ms"
              + (f", Open3D {entry['open3d_best_s'] * 1e3:.0f} ms" if "open3d_best_s" in entry else ""),
              file=sys.stderr, flush=True)
    for scene, items in rows.items():
        true_volume = items[0][1]["true_volume"]
        print(f"\n{scene}: true volume {true_volume:.6e} m³\n")
        print("| views | winged ms | manifold3d ms | Open3D ms | winged volume / true | manifold3d volume / true "
              "| (winged − manifold3d) / manifold3d | Open3D volume / true | Open3D voxel (mm) |")
        print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        for views, e, w in items:
            wv = w.get("volume") if w.get("status") == "ok" else None
            mv = e["manifold_volume"]
            rel = (wv - mv) / mv if wv is not None else None
            ov = e.get("open3d_volume")
            print(f"| {views} | {fmt(w.get('best_s') and w['best_s'] * 1e3, '.2f')} "
                  f"| {e['manifold_best_s'] * 1e3:.2f} | {fmt(e.get('open3d_best_s') and e['open3d_best_s'] * 1e3, '.0f')} "
                  f"| {fmt(wv and wv / true_volume, '.5f')} | {mv / true_volume:.5f} | {fmt(rel, '.1e')} "
                  f"| {fmt(ov and ov / true_volume, '.4f')} | {fmt(e.get('open3d_voxel') and e['open3d_voxel'] * 1e3, '.3f')} |")
            e["winged_volume"] = wv
            e["relative_difference"] = rel
    (args.dir / "peers.json").write_text(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
