"""``ViewState``: everything a viewer user controls, as one frozen value (camera, sun, species scalings,
the slicer's mode and parameters, the time), and how it becomes the renderers' inputs: a SceneSpec (both
renderers), SliceParams and a SliceMode (the slicer), and a Python snippet that reproduces the view.

Two cameras, both aimed at the storm: "ground" (a photographer ``height_m`` above the ground,
``distance_km`` from the storm's core, ``Camera.ground_view``; dragging walks around the storm and up or
down) and "orbit" (a sphere around the cloud, ``Camera.orbit``; dragging turns and tilts). The wheel
changes the distance in both.
"""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from ..optics.air.atmosphere import Atmosphere
from ..scene.spec import Camera, Ground, SceneSpec, Sky, Sun, default_sky
from ..io.sources import kind
from ..slicing.modes import MODES, SliceMode, SliceParams

# the viewer's refined frame (once input stops): each pixel the mean of REFINE_SUPERSAMPLE^2 points with slab
# jitter REFINE_JITTER, the setting whose accuracy validation/calibrate_slicer.py measures against the path
# tracer's box-filtered pixels (drafts: pixel centres, aligned slabs)
REFINE_SUPERSAMPLE, REFINE_JITTER = 2, 1.0

DEFAULT_MODE = "per-species/multiple"  # the calibrated light model beyond the paper (issue 12)
DRAG_DEG_PER_PX = 0.4          # camera turn per pixel of mouse drag
WHEEL_ZOOM_PER_100 = 1.1       # distance factor per 100 units of wheel
HEIGHT_RANGE_M = (10.0, 20000.0)


@dataclass(frozen=True)
class ViewCamera:
    """kind "ground": azimuth (deg clockwise from north, seen from the storm's core), distance_km,
    height_m; kind "orbit": azimuth, elevation_deg, distance_km (from the cloud's centre). fov: the
    horizontal field of view (degrees)."""

    kind: str = "ground"
    azimuth: float = 200.0
    distance_km: float = 40.0
    height_m: float = 1500.0
    elevation_deg: float = 20.0
    fov: float = 70.0

    def __post_init__(self):
        if self.kind not in ("ground", "orbit"):
            raise ValueError(f"ViewCamera.kind must be 'ground' or 'orbit', got {self.kind!r}")

    def dragged(self, dx_px: float, dy_px: float) -> "ViewCamera":
        """Drag right: the camera walks (or turns) anticlockwise around the storm; drag up: higher."""
        az = (self.azimuth - DRAG_DEG_PER_PX * dx_px) % 360.0
        if self.kind == "orbit":
            return replace(self, azimuth=az, elevation_deg=float(np.clip(self.elevation_deg + DRAG_DEG_PER_PX * dy_px,
                                                                          -5.0, 89.0)))
        h = float(np.clip(self.height_m * math.exp(0.01 * dy_px), *HEIGHT_RANGE_M))
        return replace(self, azimuth=az, height_m=h)

    def zoomed(self, wheel_dy: float) -> "ViewCamera":
        return replace(self, distance_km=float(np.clip(self.distance_km * WHEEL_ZOOM_PER_100 ** (wheel_dy / 100.0),
                                                       0.5, 2000.0)))

    def camera(self, frame, width: int, height: int, ground_m: float) -> Camera:
        """The Camera for a storm ``frame`` (a VolumeFrame, or an OpticalVolume)."""
        if self.kind == "orbit":
            return Camera.orbit(frame, azimuth=self.azimuth, elevation=self.elevation_deg,
                                distance=1000.0 * self.distance_km, fov=self.fov)
        return Camera.ground_view(frame, distance_km=self.distance_km, height_m=self.height_m, azimuth=self.azimuth,
                                  fov=self.fov, aspect=width / height, ground_m=ground_m)


class VolumeFrame:
    """What the cameras need of a storm, computed once (the box, the cloud's box, the column of largest
    optical depth), so that the camera stays put while the time slider changes the storm and costs
    nothing per frame."""

    def __init__(self, vol):
        self.bbox = vol.bbox
        self.spacing = vol.spacing
        self._occupied = vol.occupied_bbox()
        self.beta_total = np.sum(vol.beta_total, axis=0, dtype=np.float64)[None]  # (1, y, x): the columns

    def occupied_bbox(self):
        return self._occupied


@dataclass(frozen=True)
class ViewState:
    """One view of the viewer. ``scale``, ``detail``: per species; ``albedo``/``forward_fraction`` None:
    the species' own (from the phase tables); ``time``: index into the input's times."""

    camera: ViewCamera = field(default_factory=ViewCamera)
    sun_azimuth: float = 290.0
    sun_elevation: float = 35.0
    sun_diameter_deg: float = 0.53
    width: int = 320
    height: int = 240
    mode: str = DEFAULT_MODE
    species_colors: bool = False
    slices: int = 128
    scale: tuple = ()             # ((species, factor), ...)
    detail: tuple = ()            # ((species, amplitude), ...): the detail mode's noise amplitude per species
    albedo: float | None = None
    cone_angle_deg: float = 10.0
    forward_fraction: float | None = None
    ambient: float = 0.0
    exposure_ev: float = 0.0
    time: int = 0
    sky: str = "auto"             # "auto": the air's own sky with the clear atmosphere, sunsky without (as render's)
    ground_albedo: float = 0.15
    atmosphere: str = "none"      # "clear": the 1-D atmosphere (optics.air) on the sun's and the eye's paths
    aod: float = 0.1              # its aerosol optical depth at 550 nm
    ozone: float = 0.3            # its ozone column, atm-cm
    water_vapour: float = 1.4     # its precipitable water, cm

    def __post_init__(self):
        if self.mode not in MODES:
            raise ValueError(f"unknown slicer mode {self.mode!r}; expected one of {list(MODES)}")
        if self.atmosphere not in ("none", "clear"):
            raise ValueError(f"ViewState atmosphere must be 'none' or 'clear', got {self.atmosphere!r}")
        self.air()  # range checks of --aod, --ozone and --water-vapour now
        SliceParams(**self._param_kw())  # range checks now, before anything renders

    def updated(self, **kw) -> "ViewState":
        return replace(self, **kw)

    def with_scale(self, species: str, factor: float) -> "ViewState":
        return replace(self, scale=tuple(sorted({**dict(self.scale), species: float(factor)}.items())))

    def with_detail(self, species: str, amplitude: float) -> "ViewState":
        return replace(self, detail=tuple(sorted({**dict(self.detail), species: float(amplitude)}.items())))

    # ------------------------------------------------------------------ the renderers' inputs
    def slice_mode(self) -> SliceMode:
        return replace(MODES[self.mode], species_colors=bool(self.species_colors))

    def _param_kw(self) -> dict:
        return dict(scale=dict(self.scale), albedo=self.albedo, cone_angle_deg=self.cone_angle_deg,
                    forward_fraction=self.forward_fraction, ambient=self.ambient, detail=dict(self.detail))

    def slice_params(self) -> SliceParams:
        return SliceParams(**self._param_kw())

    def air(self) -> Atmosphere | None:
        """The view's atmosphere (None for "none"); a ValueError names --aod, --ozone or --water-vapour out of
        range."""
        if self.atmosphere != "clear":
            return None
        return Atmosphere(aod_550=self.aod, ozone_atm_cm=self.ozone, water_vapour_cm=self.water_vapour)

    def sky_kind(self) -> str:
        """The sky's kind: ``sky``, its "auto" resolved as ``render``'s default (``scene.spec.default_sky``, as
        ``cli.air_option.resolve``)."""
        return default_sky(self.atmosphere) if self.sky == "auto" else self.sky

    def spec(self, frame, ground_m: float, width: int | None = None, height: int | None = None) -> SceneSpec:
        """The SceneSpec of this view (``width``/``height``: another resolution of the same view)."""
        w, h = width or self.width, height or self.height
        return SceneSpec(camera=self.camera.camera(frame, w, h, ground_m),
                         sun=Sun(self.sun_azimuth, self.sun_elevation, angular_diameter_deg=self.sun_diameter_deg),
                         sky=None if self.sky == "none" else Sky(self.sky_kind()),
                         ground=None if self.ground_albedo < 0 else Ground(albedo=self.ground_albedo, height=ground_m),
                         width=w, height=h, atmosphere=self.air())

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> "ViewState":
        d = dict(d)
        d["camera"] = ViewCamera(**d["camera"])
        d["scale"] = tuple(tuple(x) for x in d.get("scale", ()))
        d["detail"] = tuple(tuple(x) for x in d.get("detail", ()))
        return cls(**d)


def _reference_lines(state: ViewState) -> str:
    """The snippet's reference render: with the atmosphere, its air inside the box (in the medium) and along the
    eye rays outside it, as the viewer's reference (``reference_job.with_air``)."""
    call = "wm.render_reference(spec, ref_vol, spp=spp, target_rse=target_rse, max_seconds=max_seconds)"
    if state.atmosphere == "none":
        return f"    return {call}\n"
    return ("    from weather_mi.display.aerial import with_eye_air\n"
            f"    image = {call}  # with spec.atmosphere's air in the box\n"
            "    sky_air = spec.sky is not None and spec.sky.kind == 'air'  # the air's own sky (--sky air)\n"
            "    return with_eye_air(image, spec, ref_vol, sky_air=sky_air)  # and along the eye rays outside it\n")


def python_snippet(state: ViewState, recipe, spec: SceneSpec, times: list[str] | None = None,
                   exposure: float | None = None) -> str:
    """A script that renders this view with the slicer and the path tracer (``recipe``: a VolumeRecipe;
    ``exposure``: the view's display exposure, None: automatic)."""
    if getattr(recipe, "dataset", None) is not None:
        load = ("hyd = globals()['hyd']  # the Hydrometeors Dataset given to wm.view (in memory): run this where "
                "it is defined")
    elif recipe.path is None:
        load = f"hyd = wm.synthetic.{recipe.demo or 'supercell'}()"
    elif kind(recipe.path) == "les":
        load = f"hyd = wm.open_les({recipe.path!r})"
    elif times is not None and len(times) > 1:  # every time on one grid, as the viewer reads them
        load = f"hyd = wm.io.time_steps(wm.open_wrf({recipe.path!r}, time=\"all\"))[{state.time}]  # {times[state.time]}"
    else:
        load = f"hyd = wm.open_wrf({recipe.path!r})"
    params = state.slice_params().updated(slab_jitter=REFINE_JITTER)  # the refined frame's
    changed = {k: v for k, v in params.__dict__.items() if v != getattr(SliceParams(), k)}
    mode = state.slice_mode()
    mode_expr = f"MODES[{state.mode!r}]" if mode == MODES[state.mode] else \
        f"replace(MODES[{state.mode!r}], species_colors=True)"
    detail_line = ""
    if mode.detail:
        detail_line = ("detail = wm.detail.noise(vol.shape, spacing_m=vol.spacing, seed=0)  "
                       "# unit-variance noise; per-species amplitudes in params.detail\n")
    return f'''"""weather-mi view exported from the viewer: {recipe.label}."""
from dataclasses import replace  # noqa: F401

import weather_mi as wm
from weather_mi.slicing import MODES, SliceParams, SliceRenderer

{load}
vol = wm.optical_volume(hyd, species={recipe.preset!r}, phase={recipe.phase!r}, sizes={recipe.sizes!r})
spec = wm.SceneSpec.from_dict({json.dumps(spec.to_dict())})
params = SliceParams(**{changed!r})
{detail_line}renderer = SliceRenderer(vol, {mode_expr}, slices={state.slices}{", detail_noise=detail" if mode.detail else ""})
image = renderer.frame(spec, params, supersample={REFINE_SUPERSAMPLE})  # as the viewer's refined frame


def ground_truth(spp=16, target_rse=0.02, max_seconds=600):
    """The path-traced reference of the same view: it sees the scalings, not the slicer's knobs."""
    ref_vol = wm.optical_volume(hyd, species={recipe.preset!r}, phase={recipe.phase!r}, sizes={recipe.sizes!r},
                                scale={dict(state.scale) or None!r})
{_reference_lines(state)}

if __name__ == "__main__":
    image.save_png("view.png", exposure={exposure!r})
    ground_truth().save("view_reference.exr")
'''

