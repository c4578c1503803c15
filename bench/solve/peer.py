"""OpenCV's PnP solvers on the data of bench/solve/data.py: time per solve and accuracy.

    python peer.py DIR OUT.json [--threshold PX]

For every set of DIR/index.json, each solver is called once per problem (after one
warm-up call), timed around the call with perf_counter_ns (so the figures include
Python's call overhead, estimated separately and written as `call_overhead_us`):

* `cv.SQPNP`, `cv.EPNP`: cv2.solvePnP with SOLVEPNP_SQPNP / SOLVEPNP_EPNP, sets without
  outliers;
* `cv.ransac`: cv2.solvePnPRansac with its default flags (SOLVEPNP_ITERATIVE: EPnP on
  minimal samples, Levenberg-Marquardt on the inliers), and `cv.magsac`: the same call
  with flags=USAC_MAGSAC; both with the threshold given (winged's default), confidence
  0.999 and at most 10,000 iterations, as winged's solve_pnp; sets with n >= 6.

OpenCV runs on one thread (cv2.setNumThreads(1)), as winged does. The same K and the
same pixels as winged: x = (u - cx)/fx. Writes per set and solver the median and p90 time
(us), the median rotation error (degrees, the angle of R_est R_true^T), the median
relative translation error |t - t_true|/|t_true| (%) and the failures (no answer, or a
rotation error over 5 degrees). A solver that takes long (solvePnPRansac at high outlier
fractions: up to a second a solve) is stopped after --budget seconds on a set, and the
number of problems it solved is written with its figures.
"""

import argparse
import json
import time
from pathlib import Path

import cv2
import numpy as np

FAIL_DEGREES = 5.0


def problems(directory):
    index = json.loads((directory / "index.json").read_text())
    data = np.fromfile(directory / "data.f64", dtype="<f8")
    for s in index["sets"]:
        n, at, out = s["n"], s["offset"], []
        for _ in range(s["trials"]):
            r = data[at : at + 9].reshape(3, 3)
            t = data[at + 9 : at + 12]
            at += 12
            world = np.ascontiguousarray(data[at : at + 3 * n].reshape(n, 3))
            at += 3 * n
            pixels = np.ascontiguousarray(data[at : at + 2 * n].reshape(n, 2))
            at += 3 * n  # pixels and the outlier flags
            out.append((r, t, world, pixels))
        yield index, s, out


def errors(rvec, tvec, r_true, t_true):
    r, _ = cv2.Rodrigues(rvec)
    d, _ = cv2.Rodrigues(r @ r_true.T)
    degrees = float(np.degrees(np.linalg.norm(d)))
    shift = 100.0 * float(np.linalg.norm(tvec.ravel() - t_true) / np.linalg.norm(t_true))
    return degrees, shift


def run(solver, batch, budget):
    """Times `solver(world, pixels)` -> (ok, rvec, tvec) on the problems in turn, until
    all are done or `budget` seconds have gone by (the problems are independent draws, so
    the first ones are a fair sample)."""
    solver(batch[0][2], batch[0][3])
    times, rot, trans, failures = [], [], [], 0
    deadline = time.perf_counter() + budget
    for r_true, t_true, world, pixels in batch:
        if time.perf_counter() > deadline:
            break
        start = time.perf_counter_ns()
        ok, rvec, tvec = solver(world, pixels)
        times.append((time.perf_counter_ns() - start) / 1e3)
        if not ok or rvec is None or not np.all(np.isfinite(rvec)):
            failures += 1
            continue
        degrees, shift = errors(rvec, tvec, r_true, t_true)
        failures += degrees > FAIL_DEGREES
        rot.append(degrees)
        trans.append(shift)
    median = lambda v: float(np.median(v)) if v else float("nan")  # noqa: E731
    return {
        "median_us": float(np.median(times)),
        "p90_us": float(np.percentile(times, 90)),
        "rot_deg": median(rot),
        "trans_pct": median(trans),
        "failures": int(failures),
        "trials": len(times),
    }


def call_overhead_us():
    """The median time of a call that does next to nothing (Rodrigues of a 3-vector)."""
    v = np.zeros(3)
    times = []
    for _ in range(2000):
        start = time.perf_counter_ns()
        cv2.Rodrigues(v)
        times.append((time.perf_counter_ns() - start) / 1e3)
    return float(np.median(times))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("dir", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--threshold", type=float, default=8.0)
    parser.add_argument(
        "--budget",
        type=float,
        default=30.0,
        help="seconds per solver and set, after which the remaining problems are skipped",
    )
    args = parser.parse_args()
    cv2.setNumThreads(1)
    rows = []
    for index, s, batch in problems(args.dir):
        k = np.array(
            [[index["fx"], 0, index["cx"]], [0, index["fy"], index["cy"]], [0, 0, 1]],
            dtype=np.float64,
        )
        dist = np.zeros(0)

        def plain(flag):
            def solve(world, pixels):
                return cv2.solvePnP(world, pixels, k, dist, flags=flag)

            return solve

        def ransac(flag):
            def solve(world, pixels):
                ok, rvec, tvec, _ = cv2.solvePnPRansac(
                    world,
                    pixels,
                    k,
                    dist,
                    iterationsCount=10_000,
                    reprojectionError=args.threshold,
                    confidence=0.999,
                    flags=flag,
                )
                return ok, rvec, tvec

            return solve

        solvers = []
        if s["outliers"] == 0:
            solvers += [
                ("cv.SQPNP", plain(cv2.SOLVEPNP_SQPNP)),
                ("cv.EPNP", plain(cv2.SOLVEPNP_EPNP)),
            ]
        if s["n"] >= 6:
            solvers += [
                ("cv.ransac", ransac(cv2.SOLVEPNP_ITERATIVE)),
                ("cv.magsac", ransac(cv2.USAC_MAGSAC)),
            ]
        for name, solver in solvers:
            row = {"set": s["name"], "solver": name, **run(solver, batch, args.budget)}
            rows.append(row)
            print(
                f"{row['set']:>16} {name:>10}: {row['median_us']:9.1f} us "
                f"(p90 {row['p90_us']:9.1f}), {row['rot_deg']:.4f} deg, "
                f"{row['trans_pct']:.3f} %, {row['failures']} failures"
                f" in {row['trials']}",
                flush=True,
            )
    out = {
        "library": f"OpenCV {cv2.__version__} (opencv-python-headless), 1 thread",
        "call_overhead_us": call_overhead_us(),
        "threshold_px": args.threshold,
        "rows": rows,
    }
    args.out.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
