"""Driving the viewer from outside, as a user does (for tests and benchmarks/viewer.py): the ``weather-mi
view`` command in a subprocess on a free port, and a headless Chromium through Playwright (Debian's
``chromium``: no browser download, ``--no-sandbox`` as root).
"""
from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

CHROMIUM_CANDIDATES = ("chromium", "chromium-browser", "google-chrome")


def chromium_path() -> str | None:
    for name in CHROMIUM_CANDIDATES:
        p = shutil.which(name)
        if p:
            return p
    return None


class ViewerProcess:
    """``weather-mi view ARGS --port 0 --no-browser`` in a subprocess; ``url`` once it serves. The
    output lines are kept in ``lines``; ``seconds_to_serve`` from start to the "serving" line."""

    def __init__(self, *args: str, timeout_s: float = 180.0, env: dict | None = None):
        self.args = list(args)
        self.lines: list[str] = []
        self.url = None
        cmd = [sys.executable, "-m", "weather_mi.cli.commands", "view", *self.args, "--no-browser"]
        if "--port" not in self.args:
            cmd += ["--port", "0"]
        self.t_start = time.perf_counter()
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                     env={**os.environ, **(env or {})}, start_new_session=True)
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        deadline = time.perf_counter() + timeout_s
        while self.url is None and time.perf_counter() < deadline:
            if self.proc.poll() is not None:
                self._reader.join(timeout=5)
                raise RuntimeError(f"weather-mi view exited with {self.proc.returncode}:\n" + "\n".join(self.lines))
            time.sleep(0.05)
        if self.url is None:
            self.stop()
            raise TimeoutError("weather-mi view did not serve within {timeout_s} s:\n" + "\n".join(self.lines))
        self.seconds_to_serve = time.perf_counter() - self.t_start

    def _read(self):
        for line in self.proc.stdout:
            self.lines.append(line.rstrip())
            m = re.search(r"serving (http://\S+)", line)
            if m:
                self.url = m.group(1)

    def children(self) -> list[int]:
        """Pids of the viewer's reference processes (multiprocessing's spawned children; not its
        resource tracker)."""
        try:
            out = subprocess.run(["pgrep", "-P", str(self.proc.pid)], capture_output=True, text=True).stdout
        except FileNotFoundError:
            return []
        pids = []
        for p in out.split():
            try:
                cmd = Path(f"/proc/{p}/cmdline").read_bytes()
            except OSError:
                continue
            if b"spawn_main" in cmd:
                pids.append(int(p))
        return pids

    def stop(self):
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGINT)
            try:
                self.proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()


@contextmanager
def browser_page(viewport=(1400, 1000)):
    """A Playwright page in headless Chromium (the system's chromium)."""
    from playwright.sync_api import sync_playwright
    exe = chromium_path()
    if exe is None:
        raise RuntimeError("no chromium on PATH: ./setup.sh installs Debian's chromium")
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=exe, args=["--no-sandbox", "--disable-gpu"])
        try:
            page = browser.new_page(viewport={"width": viewport[0], "height": viewport[1]})
            yield page
        finally:
            browser.close()


def wait_frames(page, n: int = 1, timeout_s: float = 60.0) -> int:
    """Wait until the page has decoded ``n`` frames in all; returns the count."""
    page.wait_for_function(f"window.wmStats && window.wmStats.frames >= {n}", timeout=timeout_s * 1000)
    return page.evaluate("window.wmStats.frames")


def wait_idle(page, quiet_s: float = 1.0, timeout_s: float = 30.0, refined: bool = True,
              since: int | None = None) -> int:
    """Wait until no frame has arrived for ``quiet_s`` and, with ``refined``, the last frame is not a
    draft (the refine after an input has landed, however long it took: a kernel compiled on first use
    can take longer than ``quiet_s``). With ``since`` (a frame count read before an input), first wait
    for a frame after it: on a loaded machine the first frame of a drag can come more than ``quiet_s``
    after the input."""
    if since is not None:
        wait_frames(page, since + 1, timeout_s)
    t_end = time.perf_counter() + timeout_s
    last = page.evaluate("window.wmStats.frames")
    quiet_since = time.perf_counter()
    while time.perf_counter() < t_end:
        time.sleep(0.1)
        now = page.evaluate("window.wmStats.frames")
        if now != last:
            last, quiet_since = now, time.perf_counter()
        elif time.perf_counter() - quiet_since >= quiet_s and not (refined and "(draft)" in last_status(page)):
            return now
    return last


def last_status(page) -> str:
    """The status line of the last frame the page received ("" before the first)."""
    return page.evaluate("(window.wmStats.statuses || []).slice(-1)[0] || ''")


def frame_src(page) -> str:
    return page.evaluate("document.querySelector('body').querySelector('*') && "
                         "(() => { const walk = (root) => { const img = root.querySelector('img.wm-frame'); "
                         "if (img) return img.src; for (const el of root.querySelectorAll('*')) { "
                         "if (el.shadowRoot) { const s = walk(el.shadowRoot); if (s) return s; } } return null; }; "
                         "return walk(document); })()")


def overlay_text(page) -> str | None:
    """The text over the view (``.wm-overlay``: the shown frame's status line), or None before the view exists."""
    return page.evaluate("(() => { const walk = (root) => { const o = root.querySelector('.wm-overlay'); "
                         "if (o) return o.textContent; for (const el of root.querySelectorAll('*')) { "
                         "if (el.shadowRoot) { const s = walk(el.shadowRoot); if (s !== null) return s; } } "
                         "return null; }; return walk(document); })()")


def drag(page, locator, dx: float, dy: float = 0.0, steps: int = 60, seconds: float = 1.0):
    """Press on ``locator``'s centre, move by (dx, dy) in ``steps`` moves over ``seconds``, release."""
    box = locator.bounding_box()
    x0, y0 = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x0, y0)
    page.mouse.down()
    for k in range(1, steps + 1):
        page.mouse.move(x0 + dx * k / steps, y0 + dy * k / steps)
        time.sleep(seconds / steps)
    page.mouse.up()
