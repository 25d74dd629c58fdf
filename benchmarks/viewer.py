"""The viewer's speed as the page sees it (issue 13): frames per second received while a slider or the
view is dragged, latency from the input event to the new frame decoded on the page, and the time from
the command to the first frame.

    .venv/bin/python benchmarks/viewer.py [--demo supercell | --input FILE] [--seconds 5] [--rounds 2]
                                          [--atmospheres none,clear]

``--atmospheres``: each round measures the viewer with each ``--atmosphere`` in turn (paired: the same
machine state within a round; issue 38's air in the slicer against none), the baseline too.

``weather-mi view`` runs in a subprocess on a free port; headless Chromium (Playwright, Debian's
chromium) drags the sun-azimuth slider and then the view itself: one press, then 60 mouse moves a
second back and forth for ``--seconds``, as a hand does, then the release. Latency: the page stamps every input event, the server answers each frame with the
newest stamp it had seen when the frame's request was made, the page takes the difference when the
frame is decoded (``weather_mi/viewer/canvas.py``). The slider is measured a second time while the
path-traced reference of the view renders (its process at the lowest priority). Baseline, in this process: the slicer alone
(``FrameLoop.render``) at full and draft quality on the same storm and view, the camera and the sun moving
every frame; the ratio columns compare the page's rate with it. Targets: >= 10 frames/s received at 320x240 while dragging, median latency
<= 150 ms, first frame <= 10 s after the command (warm caches).
"""
from __future__ import annotations

import argparse
import os
import re
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from weather_mi.viewer.browser import ViewerProcess, browser_page, wait_frames, wait_idle  # noqa: E402


def slicer_baseline(recipe, rounds: int = 5, air: dict | None = None) -> dict:
    """Seconds per frame of the slicer alone, full and draft, for the viewer's first view dragged: the camera
    and the sun move every frame (the half-angle changes: slice planes, light and eye rays are redone), after
    a warm-up frame of each quality."""
    from weather_mi.viewer.frames import FrameLoop
    from weather_mi.viewer.serve import prepare
    storm, state = prepare(recipe, progress=lambda *a: None, air=air)
    loop = FrameLoop(storm, publish=lambda f: None)
    out = {}
    try:
        for draft in (False, True):
            loop.render(state, draft=draft)  # compiles, records
            ts = []
            for k in range(1, rounds + 1):
                s = state.updated(sun_azimuth=(state.sun_azimuth + 3 * k) % 360,
                                  camera=state.camera.dragged(6.0 * k, 0.0))
                t0 = time.perf_counter()
                loop.render(s, draft=draft)
                ts.append(time.perf_counter() - t0)
            out["draft" if draft else "full"] = statistics.median(ts)
    finally:
        loop.stop()
    return out


def measure_drag(page, target, seconds: float, dx: float) -> dict:
    """Press on ``target`` and move back and forth by ``dx`` pixels (60 moves a second) for ``seconds``
    without releasing: frames received and input-to-frame latencies while it is dragged."""
    wait_idle(page, 0.8)
    box = target.bounding_box()
    x0, y0 = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x0, y0)
    page.mouse.down()
    time.sleep(0.3)  # the press itself (a slider jumps to the pointer) is not part of the drag
    n0 = page.evaluate("window.wmStats.frames")
    l0 = page.evaluate("window.wmStats.latencies.length")
    t0 = time.perf_counter()
    k = 0
    while time.perf_counter() - t0 < seconds:
        phase = (k % 120) / 60.0            # 0..2: out and back, one second each way
        x = x0 + dx * (phase if phase <= 1 else 2 - phase) - dx / 2
        page.mouse.move(x, y0)
        k += 1
        time.sleep(max(0.0, t0 + k / 60.0 - time.perf_counter()))
    elapsed = time.perf_counter() - t0
    n1 = page.evaluate("window.wmStats.frames")
    lat = page.evaluate(f"window.wmStats.latencies.slice({l0})")
    statuses = page.evaluate(f"window.wmStats.statuses.slice({n0}, {n1})")
    page.mouse.up()
    return {"fps": (n1 - n0) / elapsed, "latency_ms": statistics.median(lat) if lat else float("nan"),
            "p90_ms": sorted(lat)[int(0.9 * (len(lat) - 1))] if lat else float("nan"), "n": len(lat),
            **frame_times(statuses)}


STATUS = re.compile(r"(?P<render>\d+) ms \(\+(?P<queued>\d+) queued\), (?P<w>\d+)x(?P<h>\d+)")


def frame_times(statuses: list[str]) -> dict:
    """Where a drag's frames spent their time, from the status lines that came with them (``session.refresh_canvas``:
    the render's ms, the ms its request waited for the render thread, its size): the medians, and the longest
    render. A frame rate far below 1000 / (render + queued) is time lost outside the render thread (the server's
    event loop, the websocket, the page)."""
    parsed = [m.groupdict() for m in map(STATUS.search, statuses) if m]
    if not parsed:
        return {"render_ms": float("nan"), "queued_ms": float("nan"), "max_render_ms": float("nan"), "width": 0}
    render = [int(p["render"]) for p in parsed]
    return {"render_ms": statistics.median(render), "queued_ms": statistics.median(int(p["queued"]) for p in parsed),
            "max_render_ms": max(render), "width": statistics.median(int(p["w"]) for p in parsed)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    src = ap.add_mutually_exclusive_group()
    src.add_argument("--demo", default=None, choices=("supercell", "cumulus"))
    src.add_argument("--input", default=None)
    ap.add_argument("--seconds", type=float, default=5.0, help="length of each drag measurement")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--atmospheres", default=None, help="comma-separated --atmosphere values measured in turn "
                    "(default: the command's default alone)")
    args = ap.parse_args()
    atmospheres = args.atmospheres.split(",") if args.atmospheres else [None]
    from weather_mi.viewer.recipe import VolumeRecipe
    demo = args.demo or (None if args.input else "supercell")
    recipe = VolumeRecipe(path=args.input, demo=demo)
    source = ["--demo", demo] if demo else [args.input]

    from weather_mi.cli.air_option import VIEW_DEFAULT
    bases = {a: slicer_baseline(recipe, air={"atmosphere": a or VIEW_DEFAULT}) for a in atmospheres}
    rows = []
    for r, atm in ((r, a) for r in range(args.rounds) for a in atmospheres):
        base = bases[atm]
        with ViewerProcess(*source, *(["--atmosphere", atm] if atm else [])) as viewer, browser_page() as page:
            t_cmd = viewer.t_start
            page.goto(viewer.url)
            wait_frames(page, 1, 120)
            first = time.perf_counter() - t_cmd
            slider = page.locator(".wm-sun-azimuth input").first
            view = page.locator("img.wm-frame").first
            s = measure_drag(page, slider, args.seconds, 120)
            v = measure_drag(page, view, args.seconds, 200)
            # the same slider drag while the path-traced reference of the view renders in the background
            page.get_by_role("button", name="Path-trace this view").click()
            page.get_by_text(re.compile(r"Reference: \d+ passes")).first.wait_for(timeout=300000)
            b = measure_drag(page, slider, args.seconds, 120)
            rows.append((r + 1, atm or VIEW_DEFAULT, base, first, viewer.seconds_to_serve, s, v, b))
            print(f"round {r + 1}, --atmosphere {atm or VIEW_DEFAULT}: slider {s['fps']:.1f} fps, view {v['fps']:.1f} fps, "
                  f"slider with the reference running {b['fps']:.1f} fps; load average {os.getloadavg()[0]:.1f}",
                  flush=True)

    print(f"\nviewer: {recipe.label}, view 320x240, default mode; the slicer alone in this process:")
    for atm, base in bases.items():
        print(f"  --atmosphere {atm or VIEW_DEFAULT}: full {1000 * base['full']:.0f} ms ({1 / base['full']:.1f} fps), "
              f"draft {1000 * base['draft']:.0f} ms ({1 / base['draft']:.1f} fps)")
    print("\n| round | atmosphere | first frame s (serve s) | drag | fps received | ratio to draft alone | "
          "median latency ms | p90 ms | render ms (max) | queued ms | draft width |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r, atm, base, first, serve, *drags in rows:
        for name, d in zip(("slider", "view", "slider, reference running"), drags):
            print(f"| {r} | {atm} | {first:.1f} ({serve:.1f}) | {name} | {d['fps']:.1f} | {d['fps'] * base['draft']:.2f} | "
                  f"{d['latency_ms']:.0f} | {d['p90_ms']:.0f} | {d['render_ms']:.0f} ({d['max_render_ms']:.0f}) | "
                  f"{d['queued_ms']:.0f} | {d['width']:.0f} |")


if __name__ == "__main__":
    main()
