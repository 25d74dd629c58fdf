"""``ReferenceJob``: the path-traced reference of the viewer's current view, rendered progressively in a
background process so that it never blocks the interactive slicer.

The child process (multiprocessing "spawn", daemon) lowers its priority (``os.nice``), limits Dr.Jit to
a few worker threads, builds the OpticalVolume from the picklable ``VolumeRecipe`` (not hundreds of
megabytes of arrays through a pipe) and runs ``render_reference`` to a target relative standard error
or a time limit. After every pass it hands the estimate so far to a sender thread that keeps only the
newest one (a slow parent never makes the child wait, and never makes a queue of images grow); the
parent's ``poll`` drains the pipe and returns the newest update. The child exits (``os._exit``, without
the interpreter's teardown) once its final update is sent, when its parent dies (a watchdog thread, and a
check after every pass) and on ``cancel``.

    job = ReferenceJob(recipe, spec, scale={"ice": 2.0}).start()
    ...                                   # in the viewer's periodic callback:
    u = job.poll()                        # None, or the newest ReferenceUpdate since the last poll
    if u is not None and u.error is None: show(u.image.radiance)
    job.cancel()                          # the view changed: terminate the child (idempotent)
"""
from __future__ import annotations

import math
import multiprocessing
import os
import sys
import threading
import time
from dataclasses import dataclass
from typing import Mapping

from ..io.image import Image
from ..scene.spec import SceneSpec
from .recipe import VolumeRecipe

JOIN_TIMEOUT_S = 2.0          # cancel: SIGTERM, then SIGKILL if the child is still alive after this long
WATCHDOG_PERIOD_S = 0.5       # how often the child checks that its parent is alive


@dataclass(frozen=True)
class ReferenceUpdate:
    """One estimate of the reference: ``image`` (mean radiance and standard error, float32 (H, W, 3);
    the standard error is NaN while ``passes`` < 2; the render's metadata), the ``passes`` and samples
    per pixel (``spp``) so far, the render ``seconds`` so far, ``rse_mean`` (mean relative standard
    error over the cloud pixels; None while passes < 2 or where no pixel is cloud), ``done`` (the
    render is finished: the target was met, or max_seconds passed) and ``error`` (the text of an
    exception in the child, then ``image`` is None and ``done`` is True)."""

    image: Image | None
    passes: int
    spp: int
    seconds: float
    rse_mean: float | None
    done: bool = False
    error: str | None = None


def _update(img: Image, done: bool) -> ReferenceUpdate:
    m = img.metadata
    noise = m.get("noise") or {}
    rse = noise.get("rse_mean")
    rse = float(rse) if rse is not None and math.isfinite(rse) else None
    return ReferenceUpdate(img, int(m["passes"]), int(m["spp"]), float(m["seconds"]), rse, done)


class _Newest:
    """A sender thread with a one-item mailbox: ``put`` replaces what has not been sent yet, so that
    only the newest estimate waits while the parent is slow to read (bounded memory, no blocking)."""

    def __init__(self, conn):
        self.conn = conn
        self.cond = threading.Condition()
        self.item = None
        self.closing = False
        self.broken = False
        self.thread = threading.Thread(target=self._run, name="reference-sender", daemon=True)
        self.thread.start()

    def put(self, item) -> None:
        with self.cond:
            self.item = item
            self.cond.notify()

    def _run(self) -> None:
        while True:
            with self.cond:
                while self.item is None and not self.closing:
                    self.cond.wait()
                if self.item is None:
                    return
                item, self.item = self.item, None
            try:
                self.conn.send(item)
            except (OSError, ValueError):  # the parent closed its end (cancelled or gone)
                self.broken = True
                return

    def close(self) -> None:
        """Send what is in the mailbox, then stop (waits for the parent to read it)."""
        with self.cond:
            self.closing = True
            self.cond.notify()
        self.thread.join()


class _ParentGone(Exception):
    pass


def _watch_parent(parent_pid: int) -> None:
    while True:
        time.sleep(WATCHDOG_PERIOD_S)
        if os.getppid() != parent_pid:
            os._exit(0)


EYE_AIR_SAMPLES, EYE_AIR_MU = 33, 17  # the reference's eye-ray air: points per segment, cosines of the sun's table


def with_air(recipe: VolumeRecipe, scale, spec: SceneSpec):
    """(The OpticalVolume to path-trace, a function from its estimates to the picture): with
    ``spec.atmosphere``, as ``weather-mi render --atmosphere clear`` does, the air inside the box in the medium
    (``optics.air.inside.scene_air``, molecules from the storm's ``rho_air`` as the volume keeps it per level:
    the storm is read once) and the air along the eye rays outside it put on every estimate
    (``display.aerial.with_eye_air``, computed once; with ``Sky("air")`` the air's sky's, all orders)."""
    vol = recipe.volume(scale)
    if spec.atmosphere is None:
        return vol, lambda img: img
    from ..display.aerial import eye_air, with_eye_air
    from ..optics.air.eye_path import wide_sun_table
    from ..optics.air.inside import scene_air
    # a coarser sun table and 33 points a ray (the slicer's, slicing/eye_air.py): S within ~1% at an eighth of
    # the time, so that the first estimate comes soon
    sky_air = spec.has_air_sky  # the air's own sky (its envmap: kernel.air_sky)
    air = eye_air(spec, vol, sky_air, wide_sun_table(spec.atmosphere, spec.sun.mu0, n_mu=EYE_AIR_MU), EYE_AIR_SAMPLES)
    return scene_air(vol, spec.atmosphere), lambda img: with_eye_air(img, spec, vol, sky_air, air=air)


def _child_main(conn, parent_pid: int, recipe: VolumeRecipe, spec: SceneSpec, scale, spp: int,
                target_rse, max_seconds, threads, nice: int, variant, render_kw: dict) -> None:
    """The background process: render and send every estimate, then the final image, or the error."""
    import signal
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C in the viewer's terminal: the parent cancels us
    threading.Thread(target=_watch_parent, args=(parent_pid,), name="reference-watchdog", daemon=True).start()
    sender = _Newest(conn)
    try:
        if nice:
            try:
                os.nice(int(nice))
            except OSError:  # a negative increment without the privilege: keep the priority
                pass
        from tqdm import tqdm
        # a thread lock for tqdm (render_reference's progress bar, disabled): its default creates a
        # multiprocessing semaphore, which a terminated child would leave to the resource tracker's
        # "leaked semaphore" warning at the parent's exit
        tqdm.set_lock(threading.RLock())
        import drjit as dr
        if threads is not None:
            dr.set_thread_count(int(threads))
        from ..reference.render import render_reference
        from ..kernel.variant import set_variant
        set_variant(variant)
        vol, seen = with_air(recipe, scale, spec)

        def on_pass(img: Image) -> None:
            if os.getppid() != parent_pid or sender.broken:
                raise _ParentGone
            sender.put(_update(seen(img), done=False))

        img = render_reference(spec, vol, spp, progress=False, target_rse=target_rse, max_seconds=max_seconds,
                               on_pass=on_pass, **render_kw)
        sender.put(_update(seen(img), done=True))
    except _ParentGone:
        os._exit(0)
    except BaseException as exc:  # noqa: BLE001 - everything reaches the parent as text
        sender.put(ReferenceUpdate(None, 0, 0, 0.0, None, done=True, error=f"{type(exc).__name__}: {exc}"))
    sender.close()
    conn.close()
    # the last word is sent: exit at once. The interpreter's teardown (Dr.Jit, Mitsuba, atexit, module
    # clean-up) keeps nothing and costs ~0.5 s of CPU, several seconds at nice 10 on a busy machine: past
    # the parent's JOIN_TIMEOUT_S, after which its poll would SIGTERM a child that had finished
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (AttributeError, OSError, ValueError):
            pass
    os._exit(0)


class ReferenceJob:
    """A progressive path-traced reference of ``spec`` (the viewer's view) of the storm of ``recipe``
    with per-species extinction ``scale``, rendered in a background process.

    spp        : samples per pixel of the first estimate; passes of max(1, spp // 16) samples per pixel
                 (``render_reference``'s plan) follow until the target is met. The default, 2, gives a
                 first image after one pass of 1 spp (the fastest first update) and a standard error
                 after two; max_seconds is not checked before the first estimate is complete.
    target_rse : stop when the mean relative standard error over the cloud pixels is at most this
                 (None: render ``spp`` and stop).
    max_seconds: or when this many seconds of rendering have passed (the child's clock; the volume's
                 construction and the first kernel compilation come on top).
    target_pixels: the pixels the passes past the first estimate render (``render_reference``'s): "all" (the
                 default: the page shows every pixel, and the sky and ground seen through the air in the box
                 scatter: with "cloud" they kept the first estimate's 2 spp, a white speckle over the blue sky;
                 issue 38, ``benchmarks/viewer_reference_noise.py``) or "cloud".
    threads    : Dr.Jit worker threads of the child (None: Dr.Jit's default, every core).
    nice       : the child's priority increment (``os.nice``; 0: unchanged).
    variant    : the child's Mitsuba variant (None: ``default_variant()``, cuda_ad_rgb where there is a GPU).
    render_kw  : further ``render_reference`` options (integrator, max_depth, passes, forward_peak_deg, ...).

    ``start()`` launches it (and returns the job); ``poll()`` returns the newest ``ReferenceUpdate`` since
    the last poll, without blocking; ``cancel()`` terminates the child. ``running``, ``done`` and
    ``error`` describe the updates polled so far. A context manager cancels on exit."""

    def __init__(self, recipe: VolumeRecipe, spec: SceneSpec, scale: Mapping[str, float] | None = None, *,
                 target_rse: float | None = 0.02, max_seconds: float | None = 600.0, spp: int = 2,
                 threads: int | None = 1, nice: int = 10, variant: str | None = None, target_pixels: str = "all",
                 **render_kw):
        if not isinstance(recipe, VolumeRecipe):
            raise TypeError(f"recipe must be a VolumeRecipe, got {type(recipe).__name__}")
        if not isinstance(spec, SceneSpec):
            raise TypeError(f"spec must be a SceneSpec, got {type(spec).__name__}")
        for name in ("on_pass", "progress", "checkpoint", "resume", "client"):
            if name in render_kw:
                raise TypeError(f"ReferenceJob sets render_reference's {name!r} itself")
        self.recipe, self.spec = recipe, spec
        self.scale = dict(scale or {})
        self.spp, self.target_rse, self.max_seconds = spp, target_rse, max_seconds
        self.threads, self.nice, self.variant = threads, nice, variant
        self.render_kw = {"target_pixels": target_pixels, **render_kw}
        self._proc = None
        self._conn = None
        self._last: ReferenceUpdate | None = None
        self._finished = False
        self._cancelled = False
        self.started_at: float | None = None

    # ------------------------------------------------------------------ lifecycle

    def start(self) -> "ReferenceJob":
        if self._proc is not None or self._cancelled:
            raise RuntimeError("a ReferenceJob starts once: make a new one for another render")
        ctx = multiprocessing.get_context("spawn")
        reader, writer = ctx.Pipe(duplex=False)
        self._proc = ctx.Process(
            target=_child_main, name="weather-mi reference", daemon=True,
            args=(writer, os.getpid(), self.recipe, self.spec, self.scale, self.spp, self.target_rse,
                  self.max_seconds, self.threads, self.nice, self.variant, self.render_kw))
        self.started_at = time.monotonic()
        self._proc.start()
        writer.close()  # the child holds the only writer: its death reads as EOF here
        self._conn = reader
        return self

    def poll(self) -> ReferenceUpdate | None:
        """The newest update that arrived since the last poll (older ones are dropped), or None."""
        if self._conn is None or self._finished:
            return None
        newest = None
        while True:
            try:
                if not self._conn.poll():
                    break
                newest = self._conn.recv()
            except (EOFError, OSError):  # the child is gone: finished, or died without a word
                if newest is None or not (newest.done or newest.error):
                    newest = self._died(newest)
                break
            if newest.done or newest.error:
                break
        if newest is not None:
            self._last = newest
            if newest.done or newest.error:
                self._finish()
        return newest

    def _died(self, last: ReferenceUpdate | None) -> ReferenceUpdate:
        self._proc.join(JOIN_TIMEOUT_S)
        code = self._proc.exitcode
        base = last or self._last
        return ReferenceUpdate(base.image if base else None, base.passes if base else 0, base.spp if base else 0,
                               base.seconds if base else 0.0, base.rse_mean if base else None, done=True,
                               error=f"the reference process ended unexpectedly (exit code {code})")

    def _finish(self) -> None:
        self._finished = True
        if self._proc is not None:
            self._proc.join(JOIN_TIMEOUT_S)
            if self._proc.is_alive():  # sent its last word but does not exit: no zombie
                self._stop_process()
        self._close_conn()

    def cancel(self, wait: bool = True) -> None:
        """Terminate the child (SIGTERM, SIGKILL after JOIN_TIMEOUT_S) and reap it; no update follows.
        Idempotent. ``wait=False``: the SIGTERM and the reaping on a thread of its own (the viewer's event loop
        does not wait for a child at the lowest priority to end on a loaded machine: 0.3 s measured)."""
        self._cancelled = True
        self._finished = True
        if self._proc is not None:
            if wait:
                self._stop_process()
            else:  # a dead child is reaped there too (join(0))
                threading.Thread(target=self._stop_process, name="reference-reaper", daemon=True).start()
        self._close_conn()

    def _stop_process(self) -> None:
        p = self._proc
        if p.is_alive():
            p.terminate()
            p.join(JOIN_TIMEOUT_S)
            if p.is_alive():
                p.kill()
                p.join(JOIN_TIMEOUT_S)
        else:
            p.join(0)

    def _close_conn(self) -> None:
        if self._conn is not None:
            self._conn.close()
            self._conn = None

    # ------------------------------------------------------------------ state

    @property
    def pid(self) -> int | None:
        return None if self._proc is None else self._proc.pid

    @property
    def running(self) -> bool:
        """Started, not finished (no final or error update polled), not cancelled, the child alive."""
        return (self._proc is not None and not self._finished and not self._cancelled
                and self._proc.is_alive())

    @property
    def done(self) -> bool:
        """The final update (target met or max_seconds, or an error) has been polled."""
        return self._last is not None and self._last.done

    @property
    def cancelled(self) -> bool:
        return self._cancelled

    @property
    def error(self) -> str | None:
        """The text of the child's exception (or of its unexpected end), once polled."""
        return None if self._last is None else self._last.error

    @property
    def last(self) -> ReferenceUpdate | None:
        """The newest update polled so far (kept after the poll that returned it)."""
        return self._last

    def __enter__(self) -> "ReferenceJob":
        return self

    def __exit__(self, *exc) -> None:
        self.cancel()

    def __del__(self):
        try:
            self.cancel()
        except Exception:  # noqa: BLE001 - interpreter shutdown
            pass

    def __repr__(self) -> str:
        state = ("cancelled" if self._cancelled else "error" if self.error else "done" if self.done
                 else "running" if self.running else "not started" if self._proc is None else "ended")
        return f"ReferenceJob({self.recipe.label}, {self.spec.width}x{self.spec.height}, {state})"
