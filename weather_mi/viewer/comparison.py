"""``ReferencePanel``: the ground truth of one tab: "Path-trace this view" starts a ReferenceJob (a
low-priority process), polled twice a second; each estimate gives the B view, the difference map
(CIEDE2000, 0 .. ``DIFF_MAX_DE``) and the metrics of the slicer's full-quality frame against it
(computed on a metrics thread). A change of anything the path tracer sees (``PHYSICAL_FIELDS``) cancels
the reference; a change of the slicer's approximation knobs keeps it, to compare against.
"""
from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import panel as pn

from ..io.image import auto_exposure, to_srgb8
from .frames import jpeg_url
from .state import ViewState

PHYSICAL_FIELDS = ("camera", "sun_azimuth", "sun_elevation", "sun_diameter_deg", "width", "height", "scale", "time",
                   "sky", "ground_albedo", "atmosphere", "aod", "ozone", "water_vapour")  # what the path tracer sees
DIFF_MAX_DE = 20.0  # the difference map's colour scale: CIEDE2000 0 .. 20
SHOW_CHOICES = ["A: slicer", "B: reference", "B: denoised", "difference"]  # B denoised: OIDN, display only
# above this cloud RSE the metrics line also gives A against B denoised: the raw reference's noise adds to the
# colour difference (issue 38: the demo supercell with the air after 45 s, RSE 0.26: CIEDE2000 15.0 raw, 13.2
# against B denoised; benchmarks/viewer_reference_noise.py)
NOISY_RSE = 0.05


class ReferencePanel:
    """The reference job, the A/B/difference toggle and the metrics of one ViewerSession (``session``:
    its state, storm, frame loop, event loop and canvas)."""

    def __init__(self, session, reference_kw: dict):
        self.session = session
        self.reference_kw = reference_kw
        self.job = None              # ReferenceJob
        self.image = None            # the newest reference estimate (Image) and its state
        self.state = None
        self.metrics = None
        self._overlay = None         # (key, data URL) of the last B or difference picture
        self._denoised = None        # (reference Image, its denoised radiance)
        self._waiting = None         # (reference Image, its cloud RSE): metrics that wait for the refined frame
        self._waiting_lock = threading.Lock()  # ``refined`` runs on the frame loop's thread and the event loop's
        self._generation = 0         # counts the cancels: metrics of a cancelled reference are not shown
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="weather-mi metrics")
        w = pn.widgets
        self.show = w.RadioButtonGroup(label="Show", options=SHOW_CHOICES, value="A: slicer", color="default")
        self.show.param.watch(lambda e: session.refresh_canvas(), "value")
        self.trace = w.Button(label="Path-trace this view", color="primary")
        self.trace.on_click(lambda e: self.start())
        self.cancel_button = w.Button(label="Cancel", color="warning", disabled=True)
        self.cancel_button.on_click(lambda e: self.cancel("cancelled"))
        self.ref_text = pn.pane.Markdown("Reference: none", margin=(0, 10))
        self.metric_text = pn.pane.Markdown("", margin=(0, 10))

    @property
    def showing_reference(self) -> bool:
        """Whether the view shows B or the difference, and there is a reference to show."""
        return self.show.value != "A: slicer" and self.image is not None

    def view_changed(self, old: ViewState, new: ViewState) -> None:
        """Cancel the reference where the path tracer would see another scene."""
        if self.job is not None or self.image is not None:
            if any(getattr(old, f) != getattr(new, f) for f in PHYSICAL_FIELDS):
                self.cancel("the view changed: path-trace it again")

    def start(self):
        from .reference_job import ReferenceJob
        self.cancel(None)
        s, storm = self.session.state, self.session.storm
        spec = s.spec(storm.frame, storm.ground_m)
        recipe = storm.recipe if len(storm.times) < 2 else storm.recipe.at(s.time)
        self.job = ReferenceJob(recipe, spec, dict(s.scale) or None, **self.reference_kw)
        self.job.start()
        self.state, self.image, self.metrics = s, None, None
        self.ref_text.object = "Reference: starting (a background process at low priority)..."
        self.metric_text.object = ""
        self.cancel_button.disabled = False

    def cancel(self, why: str | None):
        job, self.job = self.job, None
        if job is not None:
            job.cancel(wait=False)  # reaped on a thread: the event loop goes on
        self.cancel_button.disabled = True
        self._waiting = None
        self._generation += 1
        if why is not None:
            self.image, self.state, self.metrics = None, None, None
            self.ref_text.object = f"Reference: {why}"
            self.metric_text.object = ""
            if self.show.value != "A: slicer":
                self.session.refresh_canvas()

    def poll(self):
        job = self.job
        if job is None:
            return
        upd = job.poll()
        if upd is None:
            return
        if upd.error:
            self.ref_text.object = f"Reference failed: {upd.error}"
            self.cancel(None)
            return
        self.image = upd.image
        rse = "n/a" if upd.rse_mean is None else f"{upd.rse_mean:.3f}"
        self.ref_text.object = (f"Reference: {upd.passes} passes, {upd.spp} spp, {upd.seconds:.0f} s, "
                                f"cloud RSE {rse}{' (done)' if upd.done else ''}")
        if upd.done:
            self.job = None
            self.cancel_button.disabled = True
        self._waiting = (upd.image, upd.rse_mean)
        self.refined(self.session.loop.last_frame)

    def refined(self, frame) -> None:
        """A frame was published (any thread): where it is the refined frame of the current view, the metrics of
        the newest reference estimate that waits for one are computed against it (metrics thread). Never a
        render of their own: a full-quality frame holds the slicer's render lock for 1-3 s, and each reference
        pass during a drag of a slicer knob (which keeps the reference) stalled the drag that long."""
        if frame is None or frame.draft or frame.state != self.session.state:
            return
        with self._waiting_lock:  # taken by one thread only
            waiting, self._waiting = self._waiting, None
        if waiting is None:
            return
        self._executor.submit(self._update_metrics, waiting[0], frame, waiting[1], self._generation)

    def _update_metrics(self, ref_img, f, rse=None, generation=None):
        """Metrics of the slicer's full-quality frame ``f`` of this view against the reference (metrics thread);
        while the reference is noisy (its cloud RSE ``rse`` above NOISY_RSE, or not known yet), also against B
        denoised, said as such: the raw reference's noise is part of the first figures."""
        from ..display.metrics import compare
        try:
            kw = dict(mask="cloud", transmittance=f.transmittance, exposure=f.exposure)
            m = compare(ref_img, f.radiance, **kw)
            self.metrics = (m, f)
            text = (f"**A vs B** over {m['n_pixels']} cloud pixels: CIEDE2000 {m['ciede2000']:.2f}, "
                    f"FLIP {m['flip']:.3f}, reference noise floor {m['noise_floor']:.3g}")
            if rse is None or rse > NOISY_RSE:
                d = compare(self.denoised(ref_img), f.radiance, **kw)
                why = "not known yet" if rse is None else f"{rse:.3f}"
                text += (f"\n\n**A vs B denoised** (the reference is noisy, cloud RSE {why}): "
                         f"CIEDE2000 {d['ciede2000']:.2f}, FLIP {d['flip']:.3f}")
        except Exception as exc:
            text = f"metrics failed: {exc}"
        self.session.on_loop(lambda: self._show_metrics(text, generation))

    def _show_metrics(self, text, generation=None):
        if generation is not None and generation != self._generation:  # the reference was cancelled meanwhile
            return
        self.metric_text.object = text
        if self.show.value != "A: slicer":
            self.session.refresh_canvas()

    def status(self) -> str:
        return self.ref_text.object.replace("Reference: ", "reference: ")

    def overlay_url(self) -> str:
        """The B or difference picture, encoded once per reference update, metrics frame and exposure (not
        once per slicer frame: the slicer keeps publishing while the user drags in the B view)."""
        show = self.show.value
        f = self.session.loop.last_frame
        key = (show, id(self.image), id(self.metrics), f.exposure if f else None)
        if self._overlay is None or self._overlay[0] != key:
            url = {"B: reference": self._reference_url, "B: denoised": self._denoised_url}.get(show, self._difference_url)
            self._overlay = (key, url())
        return self._overlay[1]

    def _reference_url(self) -> str:
        f = self.session.loop.last_frame
        return jpeg_url(to_srgb8(self.image.radiance, f.exposure if f else None))

    def _denoised_url(self) -> str:
        """B denoised (``weather_mi.display.denoise``, once per reference update): for the eye; the metrics and the
        difference map stay on the unbiased radiance."""
        f = self.session.loop.last_frame
        rad = self.denoised()
        return jpeg_url(to_srgb8(rad, f.exposure if f else auto_exposure(rad)))

    def denoised(self, image=None) -> np.ndarray:
        """The denoised radiance of the reference estimate ``image`` (default: the newest), computed once per
        reference update (not per exposure, export or metrics line) on whichever thread asks first."""
        from ..display.denoise import denoise_radiance
        image = self.image if image is None else image
        done = self._denoised
        if done is None or done[0] is not image:
            done = (image, denoise_radiance(np.nan_to_num(image.radiance)))
            self._denoised = done
        return done[1]

    def _difference_url(self) -> str:
        from matplotlib import colormaps
        from ..display.metrics import ciede2000_map, display_lab, display_srgb
        f = self.session.loop.last_frame
        full = self.metrics[1] if self.metrics else f
        if full is None or full.radiance.shape != self.image.radiance.shape:
            return self._reference_url()
        lab_r = display_lab(display_srgb(self.image.radiance, full.exposure))
        lab_a = display_lab(display_srgb(full.radiance, full.exposure))
        de = np.clip(ciede2000_map(lab_r, lab_a) / DIFF_MAX_DE, 0, 1)
        rgb = (colormaps["magma"](de)[..., :3] * 255).astype(np.uint8)
        return jpeg_url(rgb)

    def close(self):
        self.cancel(None)
        self._executor.shutdown(wait=False, cancel_futures=True)
