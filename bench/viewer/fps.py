"""Frames per second of the browser viewer: opens the viewer of a running server in
headless Chromium with an 800 × 600 picture, orbits the camera a little every animation
frame for a while, and reports the pictures received and painted per second with the
request-to-paint latency percentiles.

    python bench/viewer/fps.py http://127.0.0.1:7878 [--seconds 10] [--mode shaded]

The browser paints at most one picture per animation frame (60 per second headless),
so the orbit is then run again with the camera moved as often as timers run, which
keeps a picture request always in flight: that rate is what the viewer and the server
can reach together. Last, the same picture is fetched one request after another
straight over HTTP (no browser), to show how much of a frame is the server's drawing.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import sys
import tempfile
import time

import httpx
from selenium import webdriver
from selenium.webdriver.chrome.service import Service

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"


def driver_for(width: int, height: int) -> tuple[webdriver.Chrome, str]:
    """A headless Chromium window of the given size and its throw-away profile."""
    profile = tempfile.mkdtemp(prefix="winged-fps-chromium-")
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--disable-dev-shm-usage",
        f"--user-data-dir={profile}",
        f"--window-size={width},{height}",
    ):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service(executable_path=CHROMEDRIVER), options=options)
    return driver, profile


def direct(base: str, camera: dict, mode: str, n: int) -> tuple[float, float]:
    """p50 and p95 of `n` sequential POST /v1/appearance requests for `camera`, ms."""
    times = []
    with httpx.Client(base_url=base, timeout=30) as client:
        for _ in range(n):
            t = time.perf_counter()
            r = client.post("/v1/appearance", json={"camera": camera, "mode": mode})
            r.raise_for_status()
            times.append((time.perf_counter() - t) * 1e3)
    times.sort()
    return statistics.median(times), times[min(len(times) - 1, int(0.95 * len(times)))]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("base", help="the server, e.g. http://127.0.0.1:7878")
    parser.add_argument("--seconds", type=float, default=10.0, help="how long to orbit (default 10)")
    parser.add_argument("--size", default="800x600", help="picture size WxH (default 800x600)")
    parser.add_argument("--mode", default="shaded", help="drawing mode (default shaded)")
    parser.add_argument("--step", type=float, default=1.0, help="degrees turned per animation frame (default 1)")
    parser.add_argument("--json", help="also write the figures to this file")
    args = parser.parse_args()

    w, h = (int(x) for x in args.size.split("x"))
    driver, profile = driver_for(w + 420, h + 200)
    try:
        driver.set_script_timeout(args.seconds + 60)
        driver.get(f"{args.base}/?size={args.size}")
        deadline = time.monotonic() + 30
        while not driver.execute_script(
            "return !!(window.wingedViewer && wingedViewer.ready && wingedViewer.frames > 0)"
        ):
            if time.monotonic() > deadline:
                print("the viewer drew no picture within 30 s", file=sys.stderr)
                return 1
            time.sleep(0.05)
        driver.execute_script(
            "const s = document.getElementById('mode'); s.value = arguments[0]; s.dispatchEvent(new Event('change'));",
            args.mode,
        )
        # Warm up (scene built, connections open), then measure.
        driver.execute_async_script(
            "wingedViewer.spin(1000, arguments[0]).then(arguments[arguments.length - 1])", args.step
        )
        load_before = os.getloadavg()
        started = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
        result = driver.execute_async_script(
            "wingedViewer.spin(arguments[0], arguments[1]).then(arguments[arguments.length - 1])",
            args.seconds * 1000,
            args.step,
        )
        load_after = os.getloadavg()
        # The same orbit with the camera moved as often as timers run: pictures are then
        # asked for back to back, and the rate is what the viewer and server can reach.
        flood = driver.execute_async_script(
            "wingedViewer.spin(arguments[0], arguments[1], true).then(arguments[arguments.length - 1])",
            args.seconds * 1000,
            args.step / 4,
        )
        camera = driver.execute_script("return wingedViewer.camera()")
        errors = driver.execute_script("return wingedViewer.errors")
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)

    d50, d95 = direct(args.base, camera, args.mode, 50)
    figures = {
        "measured_at": started,
        "cores": os.cpu_count(),
        "load_average_before": load_before,
        "load_average_after": load_after,
        "picture": f"{result['width']}x{result['height']}",
        "mode": args.mode,
        "seconds": round(result["seconds"], 2),
        "animation_frames": result["ticks"],
        "frames_painted": result["frames"],
        "fps": round(result["fps"], 1),
        "latency_p50_ms": round(result["p50"], 1),
        "latency_p95_ms": round(result["p95"], 1),
        "back_to_back_fps": round(flood["fps"], 1),
        "back_to_back_latency_p50_ms": round(flood["p50"], 1),
        "back_to_back_latency_p95_ms": round(flood["p95"], 1),
        "direct_http_p50_ms": round(d50, 1),
        "direct_http_p95_ms": round(d95, 1),
        "viewer_errors": errors,
        "failed_pictures": result["failures"] + flood["failures"],
    }
    print(
        f"viewer {figures['picture']} {args.mode}: {figures['fps']} frames/s "
        f"({result['frames']} pictures painted in {figures['seconds']} s of orbiting, "
        f"{result['ticks']} animation frames); request-to-paint p50 {figures['latency_p50_ms']} ms, "
        f"p95 {figures['latency_p95_ms']} ms"
    )
    print(
        f"camera moved as fast as timers run: {figures['back_to_back_fps']} frames/s, request-to-paint "
        f"p50 {figures['back_to_back_latency_p50_ms']} ms, p95 {figures['back_to_back_latency_p95_ms']} ms; "
        f"the same picture straight over HTTP (no browser) p50 {figures['direct_http_p50_ms']} ms, "
        f"p95 {figures['direct_http_p95_ms']} ms"
    )
    print(
        f"measured at {started} on {figures['cores']} cores; load average "
        f"{' '.join(f'{x:.2f}' for x in load_before)} before, {' '.join(f'{x:.2f}' for x in load_after)} after"
    )
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(figures, f, indent=2)
    return 0 if errors == 0 and figures["failed_pictures"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
