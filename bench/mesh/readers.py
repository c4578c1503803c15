"""trimesh's view of the meshes winged exported: watertight, and the volume winged
reported (see readers.sh)."""

import math
import pathlib
import sys

import trimesh
import trimesh.exchange.off

F32 = {"stl", "glb", "3mf"}

# trimesh's OFF loader hands each face to triangulate_quads as a list of strings, which
# fails for faces of more than four corners (numpy will not multiply a string); the shim
# gives it the same indices as integers. Everything else is trimesh's own loading.
_triangulate_quads = trimesh.exchange.off.triangulate_quads
trimesh.exchange.off.triangulate_quads = lambda faces, *a, **k: _triangulate_quads(
    [[int(i) for i in f] for f in faces], *a, **k
)


def main(directory: str) -> int:
    files = sorted(
        p
        for p in pathlib.Path(directory).iterdir()
        if p.suffix.lstrip(".") in {"stl", "ply", "off", "obj", "glb", "3mf"}
    )
    if not files:
        print(f"{directory}: no exported meshes", file=sys.stderr)
        return 1
    failed = 0
    for path in files:
        fmt = path.suffix.lstrip(".")
        loaded = trimesh.load(str(path), force="scene", process=True)
        meshes = list(loaded.dump()) if isinstance(loaded, trimesh.Scene) else [loaded]
        meshes = [m for m in meshes if isinstance(m, trimesh.Trimesh) and len(m.faces)]
        problems = []
        if not meshes:
            problems.append("no mesh")
        for k, m in enumerate(meshes):
            if not m.is_watertight:
                problems.append(f"mesh {k} is not watertight")
        volume = sum(m.volume for m in meshes)
        want_file = path.with_name(path.name + ".volume")
        if want_file.exists():
            want = float(want_file.read_text())
            if not math.isnan(want):
                tol = 1e-4 if fmt in F32 else 1e-6
                if abs(volume - want) > tol * abs(want):
                    problems.append(f"volume {volume!r}, winged reported {want!r}")
        status = "ok" if not problems else "FAILED: " + "; ".join(problems)
        print(f"trimesh {trimesh.__version__}: {path.name}: {len(meshes)} mesh(es), volume {volume:.9g}: {status}")
        failed += bool(problems)
    print(f"trimesh: {len(files) - failed}/{len(files)} files pass")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
