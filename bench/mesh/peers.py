"""trimesh's side of the mesh side-by-side: load (as trimesh loads by default: vertices
merged, degenerate and duplicate faces processed) and export the same files winged
reads in `mesh_side run`. Best of N runs; one line of JSON per case."""

import argparse
import io
import json
import pathlib
import time

import trimesh


def best(repeat, f):
    t_best, out = float("inf"), None
    for _ in range(repeat):
        t = time.perf_counter()
        out = f()
        t_best = min(t_best, time.perf_counter() - t)
    return t_best * 1e3, out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dir")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    for path in sorted(pathlib.Path(args.dir).glob("*.stl")):
        data = path.read_bytes()
        load_ms, mesh = best(
            args.repeat,
            lambda: trimesh.load(io.BytesIO(data), file_type="stl", process=True),
        )
        exports = {}
        for fmt in ["stl", "obj", "glb"]:
            ms, blob = best(args.repeat, lambda: mesh.export(file_type=fmt))
            exports[f"export_{fmt}_ms"] = ms
            exports[f"{fmt}_bytes"] = len(blob)
        print(
            json.dumps(
                {
                    "case": path.name,
                    "peer": f"trimesh {trimesh.__version__}",
                    "load_ms": load_ms,
                    "faces": len(mesh.faces),
                    "vertices": len(mesh.vertices),
                    "watertight": bool(mesh.is_watertight),
                    "volume": float(mesh.volume),
                    **exports,
                }
            ),
            flush=True,
        )


if __name__ == "__main__":
    main()
