"""Screenshots of the viewer as a person sees it: the slicer view (A), the path-traced reference of the
same view after ``--seconds`` of rendering (B) and their difference, with the metrics line.

    .venv/bin/python validation/viewer_screenshots.py [--demo supercell] [--seconds 90] [-o out/viewer]

``weather-mi view`` runs in a subprocess, headless Chromium (Playwright, Debian's chromium) clicks
"Path-trace this view", waits, and takes one screenshot per toggle: a.png, b.png, difference.png.
"""
from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from weather_mi.viewer.browser import ViewerProcess, browser_page, wait_frames, wait_idle  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--demo", default="supercell", choices=("supercell", "cumulus"))
    ap.add_argument("--seconds", type=float, default=90.0, help="reference rendering time before the B shot")
    ap.add_argument("--size", default="320x240")
    ap.add_argument("-o", "--output", default="out/viewer")
    args = ap.parse_args()
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    with ViewerProcess("--demo", args.demo, "--size", args.size) as viewer, browser_page((1300, 900)) as page:
        page.goto(viewer.url)
        wait_frames(page, 1, 120)
        wait_idle(page, 1.0)
        page.screenshot(path=str(out / "a.png"))
        page.get_by_role("button", name="Path-trace this view").click()
        t0 = time.time()
        while time.time() - t0 < args.seconds:
            time.sleep(2)
        progress = page.get_by_text(re.compile(r"Reference: \d+ passes")).first
        progress.wait_for(timeout=120000)
        page.get_by_text(re.compile(r"CIEDE2000 \d")).first.wait_for(timeout=60000)
        page.get_by_role("button", name="B: reference").click()
        time.sleep(1.5)
        page.screenshot(path=str(out / "b.png"))
        page.get_by_role("button", name="difference").click()
        time.sleep(1.5)
        page.screenshot(path=str(out / "difference.png"))
        metrics = page.get_by_text(re.compile(r"CIEDE2000")).first.inner_text()
        print(progress.inner_text())
        print(metrics)
    print(f"wrote {out / 'a.png'}, {out / 'b.png'}, {out / 'difference.png'}")


if __name__ == "__main__":
    main()
