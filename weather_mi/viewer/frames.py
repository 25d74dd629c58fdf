"""``FrameLoop``: the slicer behind the viewer, one background thread per browser session.

Requests are views (``ViewState`` plus the client input number they answer); the newest request wins,
older ones are dropped unrendered. While the user drags (requests closer together than ``IDLE_S``), a
request is rendered as a draft; once the input has been idle for ``IDLE_S`` (``HOLD_IDLE_S`` while the mouse
button is still held on the view or a slider, ``hold``: the drag may go on), the same view is refined at
full quality (all slices, each pixel the mean of REFINE_SUPERSAMPLE^2 points with slab jitter, state.py).
Drafts adapt to the machine: the loop keeps the finest of ``DRAFT_LEVELS`` (pixels per side divided by,
slices) whose frames take at most ``DRAFT_BUDGET_S``, so that dragging stays above 10 frames a second where
the cores are shared (with the browser, on a laptop) and sharp where they are not. Frames go out as JPEG
data URLs through ``publish(frame)`` (the app hands them to the page on its event loop).

Storms (one OpticalVolume per time of the input) and SliceRenderers (one per time, mode and quality)
are kept in small LRU caches: scrubbing the time slider back and forth does not rebuild them.
"""
from __future__ import annotations

import base64
import io
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from ..io.image import auto_exposure, to_srgb8
from .state import REFINE_JITTER, REFINE_SUPERSAMPLE, ViewState

DRAFT_LEVELS = ((2, 32), (3, 24), (4, 16))  # (divisor of the width and height, slices), finest first
DRAFT_BUDGET_S = 0.07
IDLE_S = 0.25
# while the mouse button is held on the view or a slider (``hold``), the refine waits this long instead of IDLE_S:
# a refine (1-3 s on a loaded 2-core machine) cannot be interrupted, and a drag paused for a moment and then
# resumed waited for it (issue 38: the sun slider pressed, held 0.3 s, then dragged: one 1.3-3.0 s frame, 4-10
# frames/s against the view's 15-17; benchmarks/viewer.py)
HOLD_IDLE_S = 2.0
JPEG_QUALITY = 88


@dataclass(frozen=True)
class Frame:
    """A rendered view: the radiance (H, W, 3) and eye transmittance (H, W), the JPEG data URL, whether
    it is a draft, the client input number it answers, the state it shows and the render's seconds."""

    radiance: np.ndarray
    transmittance: np.ndarray
    url: str
    draft: bool
    seq: int
    state: ViewState
    seconds: float
    spec: object
    exposure: float
    slices: int
    queued_s: float = 0.0  # from the request to the start of its render


class LRU(OrderedDict):
    def __init__(self, size: int):
        super().__init__()
        self.size = size

    def get_or(self, key, make):
        if key in self:
            self.move_to_end(key)
            return self[key]
        value = make()
        self[key] = value
        while len(self) > self.size:
            self.popitem(last=False)
        return value


def jpeg_url(srgb8: np.ndarray, quality: int = JPEG_QUALITY) -> str:
    from PIL import Image as PILImage
    buf = io.BytesIO()
    PILImage.fromarray(srgb8).save(buf, format="JPEG", quality=quality)
    return "data:image/jpeg;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def release_kernel_cache() -> None:
    """Hand the kernel's freed grid-sized buffers (the textures' temporaries, which Dr.Jit keeps for reuse) back to
    the system."""
    import drjit as dr
    dr.flush_malloc_cache()


class Storm:
    """The input's times as OpticalVolumes (LRU), the camera frame, and the detail noise: shared by the
    sessions of one viewer (read-only after construction; building a volume takes a lock). A WRF file with
    several times is read once, every time on one height grid (``VolumeRecipe.series``)."""

    def __init__(self, recipe, cache: int = 4):
        from .state import VolumeFrame
        self.recipe = recipe
        self.times = recipe.times()
        self._lock = threading.Lock()
        self._volumes = LRU(cache)
        self._series = recipe.series() if len(self.times) > 1 else None
        t0 = len(self.times) - 1  # the last time, as the other commands
        first_volume = self.volume(t0)
        self.first_time = t0
        self.frame = VolumeFrame(first_volume)
        self.ground_m = min(0.0, float(first_volume.bbox[0][2]))
        self.species = tuple(first_volume.species)
        self.shape, self.spacing = tuple(first_volume.shape), tuple(first_volume.spacing)
        self._noise = None
        self._warm = {}                      # renderers warmed up before the first tab, for the first session
        self._warm_lock = threading.RLock()  # the warm-up itself asks take_warm (same thread)

    def warm_up(self, state: ViewState) -> None:
        """Build and run the slicer for ``state`` at full and draft quality (kernels compiled, the view's
        rays cached), keeping the renderer for the first session that asks. Call from any thread."""
        with self._warm_lock:
            loop = FrameLoop(self, publish=lambda f: None)
            try:
                loop.render(state)
                loop.render(state, draft=True)
            finally:
                loop.stop()
            self._warm.update(loop._renderers)
        release_kernel_cache()


    def take_warm(self, key):
        """A warmed-up renderer for ``key`` (waits for a warm-up in progress), once; else None."""
        with self._warm_lock:
            return self._warm.pop(key, None)

    def hydrometeors(self, t: int):
        return self.recipe.hydrometeors() if self._series is None else self._series[t]

    def volume(self, t: int):
        return self._optics(t)[0]

    def mixing_ratios(self, t: int):
        """The mixing ratios of time ``t``'s dense cells (``pick.DenseMixingRatios``), for the hover read-out."""
        return self._optics(t)[1]

    def _optics(self, t: int):
        with self._lock:
            return self._volumes.get_or(t, lambda: self._build(t))

    def _build(self, t: int):
        """(The OpticalVolume of time ``t``, its DenseMixingRatios); its Hydrometeors are let go. The volume keeps
        what the slicer and the read-out read: the per-species extinction and the total; the albedo grid only where
        the species have no table (``SliceRenderer`` reads the table's). Hydrometeors read for this build alone (not
        a series' or a notebook's Dataset, which stay whole) let their effective radii go as they are used."""
        from .pick import DenseMixingRatios
        hyd = self.hydrometeors(t)
        own = self._series is None and self.recipe.dataset is None  # read from the file (or a demo) for this build
        vol = self.recipe.volume(hyd=hyd, keep=("beta_ext",), release=("r_eff",) if own else ())
        dense = DenseMixingRatios(hyd, vol)
        if vol.species_set is not None:
            vol.release("albedo")
        return vol, dense

    def detail_noise(self) -> np.ndarray:
        """Unit-variance turbulent noise on the grid (isotropic in metres), built once."""
        with self._lock:
            if self._noise is None:
                from ..optics.detail import noise
                self._noise = noise(self.shape, self.spacing, seed=0)
            return self._noise


class FrameLoop:
    """The render thread of one session. ``submit(state, seq, interactive)`` asks for a view;
    ``publish(frame)`` is called from the thread with every rendered Frame; ``stop()`` ends it."""

    def __init__(self, storm: Storm, publish, on_error=None, renderers: int = 4):
        self.storm = storm
        self.publish = publish
        self.on_error = on_error or (lambda exc: None)
        self._renderers = LRU(renderers)
        self._cond = threading.Condition()
        self._pending: tuple | None = None
        self._last_input = 0.0
        self._stopped = False
        self._refine: tuple | None = None
        self._held = False  # the mouse button is held on the view or a slider (``hold``)
        self.exposure: float | None = None  # the session's automatic exposure, fixed by its first full frame
        self.last_frame: Frame | None = None
        self.draft_level = 0  # index into DRAFT_LEVELS, adapted to the measured draft time
        # the renderers hold per-frame state (textures, light volume): one render at a time, whichever thread
        # asks (the loop, the metrics thread, an export, the MP4 path)
        self._render_lock = threading.Lock()
        self.frames_rendered = 0
        self._thread = threading.Thread(target=self._run, name="weather-mi frames", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ requests
    def submit(self, state: ViewState, seq: int = 0, interactive: bool = False) -> None:
        with self._cond:
            now = time.perf_counter()
            draft = interactive or (now - self._last_input) < IDLE_S
            self._last_input = now
            self._pending = (state, seq, draft, now)
            self._cond.notify()

    def hold(self, held: bool) -> None:
        """The mouse button is pressed (True) or released (False) on the view or a slider: while it is held, the
        refine waits ``HOLD_IDLE_S`` of idle input, not ``IDLE_S`` (a refine cannot be interrupted); on release it
        comes ``IDLE_S`` after the last input, as before."""
        with self._cond:
            self._held = bool(held)
            self._cond.notify()

    def stop(self) -> None:
        with self._cond:
            self._stopped = True
            self._cond.notify()
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout=10)

    @property
    def alive(self) -> bool:
        return self._thread.is_alive()

    # ------------------------------------------------------------------ the thread
    def _next(self):
        with self._cond:
            while not self._stopped:
                if self._pending is not None:
                    req, self._pending = self._pending, None
                    if req[2]:
                        self._refine = (req[0], req[1], False, None)
                    else:
                        self._refine = None
                    return req
                if self._refine is not None:
                    idle = HOLD_IDLE_S if self._held else IDLE_S
                    wait = idle - (time.perf_counter() - self._last_input)
                    if wait <= 0:
                        req, self._refine = self._refine, None
                        return req
                    self._cond.wait(wait)
                else:
                    self._cond.wait()
            return None

    def _run(self):
        while True:
            req = self._next()
            if req is None:
                return
            state, seq, draft, t_submit = req
            try:
                frame = self.render(state, seq, draft, t_submit)
            except Exception as exc:  # a bad parameter must not kill the session's renderer
                self.on_error(exc)
                continue
            self.last_frame = frame
            if draft:
                self._adapt(frame.seconds)
            self.publish(frame)

    def _adapt(self, seconds: float) -> None:
        """Coarser drafts when one took longer than the budget, finer when there is room for the next level."""
        if seconds > DRAFT_BUDGET_S and self.draft_level < len(DRAFT_LEVELS) - 1:
            self.draft_level += 1
        elif seconds < 0.5 * DRAFT_BUDGET_S and self.draft_level > 0:
            self.draft_level -= 1

    def renderer(self, state: ViewState, draft: bool):
        from ..slicing import SliceRenderer
        mode = state.slice_mode()

        def make():
            warm = self.storm.take_warm((state.time, mode))
            if warm is not None:
                return warm
            vol = self.storm.volume(state.time)
            noise = self.storm.detail_noise() if mode.detail else None
            return SliceRenderer(vol, mode, slices=state.slices, detail_noise=noise)
        r = self._renderers.get_or((state.time, mode), make)
        r.slices = min(DRAFT_LEVELS[self.draft_level][1], state.slices) if draft else state.slices  # compiles nothing
        return r

    def render(self, state: ViewState, seq: int = 0, draft: bool = False, t_submit: float | None = None) -> Frame:
        """Render one view now (in the calling thread; waits for a render in progress)."""
        with self._render_lock:
            return self._render(state, seq, draft, t_submit)

    def _render(self, state: ViewState, seq: int, draft: bool, t_submit: float | None) -> Frame:
        t0 = time.perf_counter()
        queued = 0.0 if t_submit is None else t0 - t_submit
        r = self.renderer(state, draft)
        div = DRAFT_LEVELS[self.draft_level][0] if draft else 1
        w, h = max(state.width // div, 8), max(state.height // div, 8)
        spec = state.spec(self.storm.frame, self.storm.ground_m, w, h)
        params = state.slice_params()
        if draft:
            img = r.frame(spec, params)
        else:
            img = r.frame(spec, params.updated(slab_jitter=REFINE_JITTER), supersample=REFINE_SUPERSAMPLE)
        if self.exposure is None:
            self.exposure = auto_exposure(img.radiance)
        exposure = self.exposure * 2.0 ** state.exposure_ev
        url = jpeg_url(to_srgb8(img.radiance, exposure))
        self.frames_rendered += 1
        return Frame(img.radiance, r.transmittance.copy(), url, draft, seq, state, time.perf_counter() - t0, spec,
                     exposure, r.slices, queued)
