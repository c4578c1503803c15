"""Camera-solution benchmark data on the EPnP paper's protocol, written once for both sides.

    python data.py DIR [--seed 2020] [--trials 300]

Every problem: f = 800 px, a 640 x 480 image with the principal point at its centre
(cx = 320, cy = 240), n points uniform in [-2,2] x [-2,2] x [4,8] in the camera frame, the
world frame a uniformly random rotation about an origin uniform in that same box (so
x_cam = R x_world + t with |t| about 6), pixels u = f x/z + cx, v = f y/z + cy plus
Gaussian noise of sigma px on each axis. In the robustness sets a random choice of
round(fraction * n) pixels is replaced by pixels uniform over the image.

Writes DIR/index.json (the intrinsics and, per set, its name, n, sigma, outlier fraction,
trial count and offset) and DIR/data.f64: little-endian float64, per problem
R (9, row by row), t (3), world points (3 n), pixels (2 n), outlier flags (n: 1 or 0).
Both bench/solve/peer.py (OpenCV) and examples/solve_bench.rs (winged) read these files.
"""

import argparse
import json
from pathlib import Path

import numpy as np

F = 800.0
WIDTH, HEIGHT = 640, 480
CX, CY = WIDTH / 2, HEIGHT / 2
SIZES = [4, 6, 10, 50, 200, 1000]
SIGMAS = [0.5, 2.0]
ROBUST_N = 200
ROBUST_SIGMA = 2.0
FRACTIONS = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]


def rotation(rng):
    """A rotation uniform over SO(3): a normalised Gaussian quaternion."""
    while True:
        q = rng.normal(size=4)
        norm = np.linalg.norm(q)
        if norm > 1e-3:
            break
    w, x, y, z = q / norm
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def box(rng, count):
    lo = np.array([-2.0, -2.0, 4.0])
    hi = np.array([2.0, 2.0, 8.0])
    return lo + (hi - lo) * rng.random((count, 3))


def problem(rng, n, sigma, fraction):
    cam = box(rng, n)
    r = rotation(rng)
    t = box(rng, 1)[0]
    world = (cam - t) @ r  # rows: R^T (x_cam - t)
    pixels = F * cam[:, :2] / cam[:, 2:] + np.array([CX, CY])
    pixels += rng.normal(scale=sigma, size=(n, 2))
    outlier = np.zeros(n)
    wrong = int(round(fraction * n))
    if wrong:
        chosen = rng.choice(n, size=wrong, replace=False)
        outlier[chosen] = 1.0
        pixels[chosen] = rng.random((wrong, 2)) * np.array([WIDTH, HEIGHT])
    return np.concatenate([r.ravel(), t, world.ravel(), pixels.ravel(), outlier])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("dir", type=Path)
    parser.add_argument("--seed", type=int, default=2020)
    parser.add_argument("--trials", type=int, default=300)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    specs = [(n, s, 0.0) for s in SIGMAS for n in SIZES]
    specs += [(ROBUST_N, ROBUST_SIGMA, f) for f in FRACTIONS]
    sets, chunks, offset = [], [], 0
    for n, sigma, fraction in specs:
        name = f"n{n}_s{sigma:g}" + (f"_out{round(fraction * 100)}" if fraction else "")
        sets.append(
            {
                "name": name,
                "n": n,
                "sigma": sigma,
                "outliers": fraction,
                "trials": args.trials,
                "offset": offset,
            }
        )
        for _ in range(args.trials):
            chunk = problem(rng, n, sigma, fraction)
            chunks.append(chunk)
            offset += chunk.size
    args.dir.mkdir(parents=True, exist_ok=True)
    np.concatenate(chunks).astype("<f8").tofile(args.dir / "data.f64")
    index = {
        "seed": args.seed,
        "fx": F,
        "fy": F,
        "cx": CX,
        "cy": CY,
        "width": WIDTH,
        "height": HEIGHT,
        "sets": sets,
    }
    (args.dir / "index.json").write_text(json.dumps(index, indent=1))
    print(f"{len(sets)} sets, {offset * 8 / 1e6:.1f} MB in {args.dir}")


if __name__ == "__main__":
    main()
