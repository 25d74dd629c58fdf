"""The validation study's runs: the interactive approximation (half-angle slicing) against the ground
truth (path tracing), per scene, lighting, mode and setting, written as a report folder (``report.py``
writes it; ``weather_mi.slicing.calibrate`` fits the "multiple" light model on the demo storms' views):

    DIR/report.md      what was rendered, the reference's noise level, the tables, what the slicer misses
    DIR/metrics.csv    one row per (scene, lighting, mode, setting), one column per metric
    DIR/*.png          side-by-side images, error maps, convergence and calibration figures

``weather-mi validate -o DIR [--quick] [--data FOLDER]`` runs it. The configurations (``CONFIGS``)
differ only in size, samples and scenes; scenes from data files are read from ``data_dir`` only (the
library reads no repository path) and skipped without it. Every difference smaller than the
reference's own noise floor is marked as not significant.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..display import metrics
from ..io import sources
from ..io.image import auto_exposure
from ..optics.volume import optical_volume
from ..scene.spec import Camera, Ground, SceneSpec, Sky, Sun
from ..slicing import MODES, SliceMode, SliceParams, SliceRenderer
from .report import METRIC_KEYS



@dataclass(frozen=True)
class StudyConfig:
    width: int = 256
    height: int = 192
    spp: int = 256
    slices: int = 128
    light_res: int | None = None  # None: the slicer's automatic light-buffer size
    scenes: tuple = ("demo-supercell", "wrf-supercell", "bomex")
    lightings: tuple = ("front", "side", "back")
    convergence_slices: tuple = (64, 128, 256, 512)
    cone_angles: tuple = (5.0, 10.0, 20.0, 30.0)
    calibration_iterations: int = 30
    calibration_slices: int = 64
    phase_quality: str = "default"
    integrator: str = "majorant"
    species: str = "physical"
    denoise_spp: tuple = (32, 64)  # the denoised display layer's bias: raw and denoised images at these spp


CONFIGS = {
    "full": StudyConfig(),
    "quick": StudyConfig(width=96, height=72, spp=32, slices=96,
                         convergence_slices=(32, 64, 128, 256), calibration_iterations=12, phase_quality="test",
                         denoise_spp=(8,)),
    "tiny": StudyConfig(width=24, height=18, spp=4, slices=24, light_res=24, scenes=("demo-cumulus",),
                        lightings=("front", "back"), convergence_slices=(12, 24), cone_angles=(10.0, 20.0),
                        calibration_iterations=12, calibration_slices=24, phase_quality="test",
                        denoise_spp=(2,)),
}


# ---------------------------------------------------------------- scenes and views

# real model output: scene name -> (path under the data folder, description); ``weather_mi.io.sources``
# opens it (a WRF or LES file by its suffix)
DATA_SCENES = {
    "wrf-supercell": ("wrf/wrfout_quarter_ss_0130.nc", "real WRF supercell (em_quarter_ss, WSM6, 1 km, 01:30)"),
    "wrf-plateau": ("wrf/wrf_d01_allvars_cropped.nc", "real WRF, Tibetan Plateau (Thompson, 30 km, last time)"),
    "bomex": ("les/bomex_50m.txt", "BOMEX trade cumulus (LES, 50 m)"),
    "rico": ("les/rico_20m.txt", "RICO trade cumuli (LES, 20 m)"),
    # the same WRF supercell run at other times than the held-out 01:30 (the slicer calibration's real training
    # storms: validation/calibrate_slicer.py TRAIN)
    "wrf-supercell-0100": ("wrf/wrfout_quarter_ss_series.nc", "real WRF supercell (em_quarter_ss, WSM6, 1 km, 01:00)"),
    "wrf-supercell-0200": ("wrf/wrfout_quarter_ss_series.nc", "real WRF supercell (em_quarter_ss, WSM6, 1 km, 02:00)"),
    # the plateau file's first time: 9 h before the held-out last, 5x its cloud cover (3.3% of the cells above
    # 1e-5 kg/kg of cloud water against 0.65%) and 6x its largest cloud water (0.88 against 0.14 g/kg)
    "wrf-plateau-0000": ("wrf/wrf_d01_allvars_cropped.nc", "real WRF, Tibetan Plateau (Thompson, 30 km, 00:00)"),
}
# the WRF time (a timestamp, weather_mi.io.times) of a data scene from a file of several times; absent: the last
DATA_TIMES = {"wrf-supercell-0100": "0001-01-01_01:00:00", "wrf-supercell-0200": "0001-01-01_02:00:00",
              "wrf-plateau-0000": "2005-09-21_00:00:00"}
THIN_FACTOR = 0.15  # demo-cumulus-thin: the demo cumulus with its condensate scaled by this (optically thin)
_COARSE_CUMULUS = {"shape": (40, 48, 48), "spacing_m": (100.0, 100.0, 100.0)}
# the demo storms: scene name -> (demo, its grid, scalings of the species, description)
DEMO_STORMS = {
    "demo-supercell": ("supercell", {}, None, "built-in demo supercell (synthetic, 1 km grid)"),
    "demo-cumulus": ("cumulus", _COARSE_CUMULUS, None, "built-in demo cumulus (synthetic, coarse 100 m grid)"),
    "demo-stratocumulus": ("stratocumulus", {}, None, "built-in demo stratocumulus deck (synthetic, 100 m, "
                                                      "dense: tau ~30-40)"),
    "demo-cumulus-thin": ("cumulus", _COARSE_CUMULUS, {s: THIN_FACTOR for s in ("cloud", "rain")},
                          "built-in demo cumulus (synthetic, coarse 100 m grid), its cloud water and rain "
                          f"x {THIN_FACTOR} (optically thin)"),
}
DEMO_SCENES = tuple(DEMO_STORMS)


def load_scene(name: str, cfg: StudyConfig, data_dir=None):
    """(OpticalVolume, description), or None when the scene needs a data file and ``data_dir`` (a
    folder laid out like the project's shared data: wrf/..., les/...) is None or lacks it."""
    scale = None
    if name in DATA_SCENES:
        rel, desc = DATA_SCENES[name]
        path = Path(data_dir) / rel if data_dir is not None else None
        if path is None or not path.is_file():
            return None
        hyd = sources.open_source(path, time=DATA_TIMES.get(name))
    elif name in DEMO_STORMS:
        demo, grid, scale, desc = DEMO_STORMS[name]
        hyd = sources.open_demo(demo, **grid)
    else:
        raise ValueError(f"unknown study scene {name!r}")
    # isolated boxes: the study's LES files are crops of their runs with clear edges (not periodic themselves),
    # and its recorded figures are for the boxes alone (optics/periodic.py)
    vol = optical_volume(hyd, species=cfg.species, phase_quality=cfg.phase_quality, scale=scale, periodic=False)
    return vol, desc


def load_scenes(cfg: StudyConfig, data_dir=None) -> tuple[dict, list[str]]:
    """({name: (OpticalVolume, description)}, skipped names) of the configuration's scenes. A ``data_dir``
    that is not a folder is a ValueError; scenes whose data file is absent are skipped with a warning
    that says why (no ``data_dir`` given, or the missing path)."""
    import warnings
    if data_dir is not None and not Path(data_dir).is_dir():
        raise ValueError(f"--data {data_dir}: expected a folder of real model output (wrf/..., les/...); "
                         "found no such folder")
    scenes, skipped = {}, []
    for name in cfg.scenes:
        loaded = load_scene(name, cfg, data_dir=data_dir)
        if loaded is None:
            skipped.append(name)
        else:
            scenes[name] = loaded
    if skipped:
        why = ("no data folder given (--data ../shared/data)" if data_dir is None else
               "absent: " + ", ".join(str(Path(data_dir) / DATA_SCENES[n][0]) for n in skipped))
        warnings.warn(f"validation: skipped the real-data scenes {', '.join(skipped)}: {why}", UserWarning, stacklevel=3)
    return scenes, skipped


CAMERA_AZIMUTH = 200.0


def view(vol, lighting: str, cfg: StudyConfig, camera_azimuth: float = CAMERA_AZIMUTH) -> SceneSpec:
    """Front-lit: sun behind the camera; side-lit: sun 90 deg to the right; back-lit: the camera looks
    towards the sun (low sun)."""
    sun = {"front": Sun(camera_azimuth, 35.0), "side": Sun(camera_azimuth + 90.0, 35.0),
           "back": Sun(camera_azimuth + 180.0, 20.0)}[lighting]
    return SceneSpec(camera=Camera.orbit(vol, azimuth=camera_azimuth, elevation=8.0, fov=45.0), sun=sun,
                     sky=Sky("sunsky"), ground=Ground(0.15, height=min(0.0, vol.bbox[0][2])),
                     width=cfg.width, height=cfg.height, seed=0)


def low_sun_view(vol, lighting: str, cfg: StudyConfig, elevation: float, atmosphere) -> SceneSpec:
    """:func:`view`'s front-, side- or back-lit view with the sun at ``elevation`` degrees and ``atmosphere``
    (``optics.air.Atmosphere`` or None): the slicer at a low sun (issue 38 part 3). With an atmosphere the sky is
    the air's own (``Sky("air")``, as ``render``'s default with the air): the sea-level Hosek-Wilkie sky already
    holds the whole column's scattering, so with the box's air it would count the air twice."""
    spec = view(vol, lighting, cfg)
    sky = spec.sky if atmosphere is None else Sky("air")
    return replace(spec, sun=replace(spec.sun, elevation=float(elevation)), atmosphere=atmosphere, sky=sky)


def eye_transmittance(vol, spec: SceneSpec, slices: int) -> np.ndarray:
    """Transmittance of each pixel ray through the volume (H, W), from the slicer's eye pass (it does
    not depend on the lighting): the cloud mask of the metrics."""
    r = SliceRenderer(vol, SliceMode("uniform", "low_albedo"), slices=max(slices, 64), light_res=16)
    r.frame(spec, SliceParams(albedo=0.0))
    return r.transmittance


# ---------------------------------------------------------------- one comparison

def _row(scene, lighting, mode, setting, m, t_ref, t_approx, noise):
    row = {"scene": scene, "lighting": lighting, "mode": mode, "setting": setting}
    row.update({k: m.get(k) for k in METRIC_KEYS})
    row["significant"] = bool(m["rmse"] > 2 * noise) if np.isfinite(noise) else True
    row["reference_s"] = t_ref
    row["slicer_s"] = t_approx
    return row


# ---------------------------------------------------------------- the study

def run(outdir, config: str | StudyConfig = "quick", progress: bool = True, data_dir=None) -> Path:
    """Render and compare everything; write report.md, metrics.csv and figures into ``outdir``.
    ``data_dir``: a folder with real model output (wrf/..., les/...); without it only the built-in
    demo storms are studied."""
    from tqdm.auto import tqdm

    from ..reference.render import render_reference
    from .report import plot_convergence, side_by_side, write_csv, write_report
    cfg = CONFIGS[config] if isinstance(config, str) else config
    scenes, skipped = load_scenes(cfg, data_dir)
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    rows, timings = [], []
    convergence = {}
    t_start = time.perf_counter()

    jobs = [(s, l) for s in scenes for l in cfg.lightings]
    bar = tqdm(jobs, desc="validate", disable=not progress)
    refs, denoise_rows = {}, []
    for scene, lighting in bar:
        vol, _ = scenes[scene]
        spec = view(vol, lighting, cfg)
        ref = render_reference(spec, vol, spp=cfg.spp, integrator=cfg.integrator, progress=False)
        trans = eye_transmittance(vol, spec, cfg.slices)
        ref.metadata["transmittance"] = trans.tolist()
        mask = metrics.cloud_mask(trans)
        noise = metrics.noise_floor(ref, mask=mask) if mask.any() else float("nan")
        refs[(scene, lighting)] = (spec, ref, mask)
        stem = f"{scene}_{lighting}"
        ref.save(out / f"{stem}_reference.exr")
        exposure = auto_exposure(ref.radiance)
        mask_arg = mask if mask.any() else "all"
        # every mode (Table IV and the light model beyond it), with the physical and the paper's
        # forward fraction for the translucent ones
        panels = []
        for mode_name, mode in MODES.items():
            settings = [("physical-ff" if mode.light == "translucent" else "defaults", SliceParams())]
            if mode.light == "translucent":
                settings.append(("paper-ff-0.9", SliceParams(forward_fraction=0.9)))
            detail = None
            if mode.detail:
                from ..optics.detail import field as detail_field
                detail = detail_field(vol.shape, seed=0, amplitude=0.5, spacing_m=vol.spacing)
            r = SliceRenderer(vol, mode, slices=cfg.slices, light_res=cfg.light_res, detail_field=detail)
            r.frame(spec)  # warm-up (compilation)
            for setting, params in settings:
                img = r.frame(spec, params)
                m = metrics.compare(ref, img, exposure=exposure, mask=mask_arg,
                                    error_map=out / f"{stem}_{mode_name.replace('/', '-')}_{setting}_error.png")
                rows.append(_row(scene, lighting, mode_name, setting, m, ref.metadata["seconds"],
                                 img.metadata["seconds"], noise))
                if mode_name in ("per-species/translucent", "per-species/multiple") and setting != "paper-ff-0.9":
                    panels.append(img)
        side_by_side(out / f"{stem}_side_by_side.png", ref, panels, exposure)
        # convergence in slice count and cone angle (per-species/translucent)
        mode = MODES["per-species/translucent"]
        for n in cfg.convergence_slices:
            img = SliceRenderer(vol, mode, slices=n, light_res=cfg.light_res).frame(spec)
            m = metrics.compare(ref, img, exposure=exposure, mask=mask_arg)
            convergence.setdefault((scene, lighting, "slices"), []).append((n, m["rmse"], m["ciede2000"]))
            rows.append(_row(scene, lighting, "per-species/translucent", f"slices={n}", m,
                             ref.metadata["seconds"], img.metadata["seconds"], noise))
        r = SliceRenderer(vol, mode, slices=cfg.slices, light_res=cfg.light_res)
        for angle in cfg.cone_angles:
            img = r.frame(spec, SliceParams(cone_angle_deg=angle))
            m = metrics.compare(ref, img, exposure=exposure, mask=mask_arg)
            convergence.setdefault((scene, lighting, "cone"), []).append((angle, m["rmse"], m["ciede2000"]))
            rows.append(_row(scene, lighting, "per-species/translucent", f"cone={angle:g}deg", m,
                             ref.metadata["seconds"], img.metadata["seconds"], noise))
        denoise_rows += _denoiser_rows(scene, lighting, spec, vol, ref, cfg)
        timings.append((scene, lighting, ref.metadata["seconds"], cfg.spp, noise,
                        float(np.mean(ref.radiance[mask]) if mask.any() else np.mean(ref.radiance))))

    figure_pairs = paper_figure_pairs(scenes, cfg, out, progress)

    fitted, history, calib_rows = _calibration(refs, scenes, cfg, out, progress)

    write_csv(out / "metrics.csv", rows, METRIC_KEYS)
    plot_convergence(out, convergence)
    report = write_report(cfg, scenes, skipped, rows, timings, convergence, figure_pairs, fitted, history,
                          calib_rows, time.perf_counter() - t_start, denoise_rows=denoise_rows)
    (out / "report.md").write_text(report)
    return out / "report.md"


def _denoiser_rows(scene, lighting, spec, vol, ref, cfg: StudyConfig) -> list[dict]:
    """The denoised display layer's bias on this view (``study.denoiser``): raw and denoised (default
    auxiliaries) images at ``cfg.denoise_spp``, raw also at half of each (the CIEDE2000 curve), against
    the study's reference. Not in metrics.csv: the slicer's table."""
    if ref.transmittance is None:
        return []
    from .denoiser import bias_rows
    half = tuple(max(1, s // 2) for s in cfg.denoise_spp)
    return bias_rows(scene, lighting, spec, vol, ref, cfg.denoise_spp, raw_spp=half, integrator=cfg.integrator)[0]


def _calibration(refs, scenes, cfg: StudyConfig, out: Path, progress: bool):
    """(fitted SliceParams, loss history, rows) of the calibration of the "multiple" light model: trained
    on the demo storms' views, judged on the others (with only one storm: trained on its first lighting,
    judged on the rest); ``refs``: (scene, lighting) -> (spec, reference, cloud mask)."""
    from ..slicing.calibrate import FIT_START, TrainingView, calibrate
    from .report import plot_history
    fitted, history, calib_rows = SliceParams(), [], []
    if refs:
        train = [k for k in refs if k[0] in DEMO_SCENES]
        if not train or len(train) == len(refs):
            train = [k for k in refs if k[1] == cfg.lightings[0]]
        test = [k for k in refs if k not in train]
        views = [TrainingView(scenes[k[0]][0], refs[k][0], refs[k][1].radiance, refs[k][2]) for k in train]
        fitted, history = calibrate(views, start=FIT_START, iterations=cfg.calibration_iterations,
                                    slices=cfg.calibration_slices, light_res=cfg.light_res or 64, progress=progress)
        mode = MODES["per-species/multiple"]
        for key in train + test:
            spec, ref, mask = refs[key]
            r = SliceRenderer(scenes[key[0]][0], mode, slices=cfg.slices, light_res=cfg.light_res)
            for label, params in (("start", FIT_START), ("fitted", fitted), ("shipped defaults", SliceParams())):
                m = metrics.compare(ref, r.frame(spec, params), mask=mask if mask.any() else "all")
                calib_rows.append({"scene": key[0], "lighting": key[1], "set": "train" if key in train else "held-out",
                                   "params": label, **{k: m[k] for k in ("rmse", "rel_mse", "ciede2000", "flip")}})
        plot_history(out / "calibration_loss.png", history)
    return fitted, history, calib_rows


def paper_figure_pairs(scenes, cfg: StudyConfig, out: Path, progress: bool) -> list[dict]:
    """The paper's figure pairs, each rendered by both renderers on the first scene, side-lit."""
    from ..reference.render import render_reference
    from .report import image_grid
    if not scenes:
        return []
    name = next(iter(scenes))
    vol, _ = scenes[name]
    spec = view(vol, "side", cfg)
    base = SliceMode("per_species", "translucent")
    single = _single_field_volume(vol, cfg)
    colours = _species_colour_volume(vol)
    pairs = [
        ("fig3-4_extinction", "one field (all condensate as cloud droplets)", single, base, {},
         "per-species extinction", vol, base, {}),
        ("fig6_phase", "one phase function for all species (cloud droplets' Mie)", _uniform_phase_volume(vol),
         SliceMode("uniform", "translucent"), {},
         "per-species phase", vol, base, {}),
        ("fig7-8_light", "translucent light (reference: all orders of scattering)", vol, base, {},
         "low-albedo light (reference: single scattering, max_depth=2)", vol, SliceMode("per_species", "low_albedo"),
         {"max_depth": 2}),
        ("fig2_colours", "white particles", vol, base, {}, "Table III species colours (reference: species albedo "
         "= colour)", colours, SliceMode("per_species", "translucent", species_colors=True), {}),
    ]
    result = []
    for key, label_a, vol_a, mode_a, ref_kw_a, label_b, vol_b, mode_b, ref_kw_b in pairs:
        imgs = []
        for v, mode, kw in ((vol_a, mode_a, ref_kw_a), (vol_b, mode_b, ref_kw_b)):
            ref = render_reference(spec, v, spp=cfg.spp, integrator=cfg.integrator, progress=False, **kw)
            approx = SliceRenderer(v, mode, slices=cfg.slices, light_res=cfg.light_res).frame(spec)
            imgs.append((ref, approx))
        exposure = auto_exposure(imgs[0][0].radiance)
        image_grid(out / f"{key}.png", [list(imgs[0]), list(imgs[1])], exposure)
        d_ref = float(np.mean(np.abs(imgs[1][0].radiance - imgs[0][0].radiance)))
        d_app = float(np.mean(np.abs(imgs[1][1].radiance - imgs[0][1].radiance)))
        result.append({"figure": key, "a": label_a, "b": label_b, "scene": name,
                       "mean |b - a| reference": d_ref, "mean |b - a| slicer": d_app})
    return result


def _single_field_volume(vol, cfg):
    """The paper's Fig. 3 'incorrect extinction': every species' mass as cloud droplets."""
    from ..io.hydrometeors import SPECIES_NAMES
    sp = vol.species_set
    if sp is None:
        return vol
    beta = np.zeros_like(vol.beta_ext)
    cloud = sp["cloud"]
    for i, s in enumerate(sp):
        beta[0] += vol.beta_ext[i] * (s.density_kg_m3 * s.radius_m) / (cloud.density_kg_m3 * cloud.radius_m) \
            / max(s.scale, 1e-30) * cloud.scale
    weights = np.zeros_like(vol.weights)
    weights[0] = (beta[0] > 0)
    v = replace(vol, beta_ext=beta, beta_total=beta[0].copy(), weights=weights)
    assert v.species == SPECIES_NAMES
    return v


def _uniform_phase_volume(vol):
    """Fig. 6 'one phase function for all' for the path tracer: every species scatters with the first
    species' table (cloud droplets), as the slicer's uniform phase mode does."""
    return replace(vol, phase_tables=(vol.phase_tables[0],) * len(vol.phase_tables))


def _species_colour_volume(vol):
    """Fig. 2 for the path tracer: each species scatters with its Table III colour as albedo."""
    sp = vol.species_set
    if sp is None:
        return vol
    colours = sp.with_overrides({s.name: {"albedo_rgb": tuple(0.02 + 0.98 * np.asarray(s.color_rgb))} for s in sp})
    alb = np.zeros_like(vol.albedo)
    for i, s in enumerate(colours):
        alb += vol.beta_ext[i][..., None] * np.asarray(s.albedo_rgb, np.float32)
    has = vol.beta_total > 0
    alb[has] /= vol.beta_total[has][..., None]
    alb[~has] = 1.0
    return replace(vol, albedo=alb.astype(np.float32), species_set=colours)


