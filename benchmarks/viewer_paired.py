"""The viewer's drags, this checkout against another (``--other``: a checkout of weather-mi, e.g. main's), paired:
each round runs ``weather-mi view`` from both in turn (the other's package first on PYTHONPATH), so that the two see
the same machine state (issue 38's slider stall, measured on a shared, loaded machine).

    nice -n 5 .venv/bin/python benchmarks/viewer_paired.py --other /work/main [--rounds 3] [--seconds 5]

The drags are ``benchmarks/viewer.py``'s (the sun slider, the view, the slider while the reference renders);
per drag the frames received per second, the median and p90 input-to-frame latency and the longest render.
"""
from __future__ import annotations

import argparse
import os
import re
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE / "benchmarks"))

from viewer import measure_drag  # noqa: E402
from weather_mi.viewer.browser import ViewerProcess, browser_page, wait_frames  # noqa: E402

DRAGS = ("slider", "view", "slider, reference running")


def one(env: dict, seconds: float) -> dict:
    with ViewerProcess("--demo", "supercell", env=env) as viewer, browser_page() as page:
        page.goto(viewer.url)
        wait_frames(page, 1, 120)
        slider, view = page.locator(".wm-sun-azimuth input").first, page.locator("img.wm-frame").first
        out = {"slider": measure_drag(page, slider, seconds, 120), "view": measure_drag(page, view, seconds, 200)}
        page.get_by_role("button", name="Path-trace this view").click()
        page.get_by_text(re.compile(r"Reference: \d+ passes")).first.wait_for(timeout=300000)
        out["slider, reference running"] = measure_drag(page, slider, seconds, 120)
        return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--other", required=True, help="another weather-mi checkout (its repository root)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--seconds", type=float, default=5.0)
    args = ap.parse_args()
    os.chdir(tempfile.mkdtemp())  # python -m puts the working directory first on sys.path: not this checkout
    versions = {"other": {"PYTHONPATH": str(Path(args.other).resolve())}, "this": {"PYTHONPATH": str(HERE)}}
    rows = {v: [] for v in versions}
    for r in range(args.rounds):
        for v in (list(versions) if r % 2 == 0 else list(versions)[::-1]):
            d = one(versions[v], args.seconds)
            d["load"] = os.getloadavg()[0]
            rows[v].append(d)
            print(f"round {r + 1}, {v}: " + ", ".join(f"{k} {d[k]['fps']:.1f} fps (max render {d[k]['max_render_ms']:.0f} ms)"
                                                      for k in DRAGS) + f"; load average {d['load']:.1f}", flush=True)
    print(f"\n{args.rounds} rounds, medians; this = {HERE}, other = {args.other}")
    print("| checkout | drag | fps received | median latency ms | p90 ms | longest render ms |")
    print("|---|---|---|---|---|---|")
    for v in versions:
        for k in DRAGS:
            med = lambda key: statistics.median(d[k][key] for d in rows[v])  # noqa: E731
            print(f"| {v} | {k} | {med('fps'):.1f} | {med('latency_ms'):.0f} | {med('p90_ms'):.0f} | "
                  f"{med('max_render_ms'):.0f} |")


if __name__ == "__main__":
    t0 = time.time()
    main()
    print(f"({time.time() - t0:.0f} s)")
