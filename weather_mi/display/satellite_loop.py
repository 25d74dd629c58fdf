"""A loop of synthetic satellite images (``weather-mi satellite --time all``): every time of a series rendered
by ``satellite.imagery`` (one band) or ``satellite.truecolor`` (``--rgb``), written as one CF NetCDF with a
``time`` dimension, a PNG and an EXR per time (named with the valid time) and an MP4 loop.

One exposure for all frames: each frame is the single image's picture (``satellite_picture.picture``: the
denoised reflectance, a band's at exposure 1 with its colour bar, or the operational true-colour recipe;
coastlines and graticule where the file has its own latitude/longitude): fixed scales, so that a
brightening storm gets brighter rather than re-exposed. The NetCDF holds the raw reflectance.

Resumable: while the loop runs, ``OUT.nc.parts/`` holds the dataset of every finished time, the
checkpoint(s) of the unfinished one and the options the loop was started with (``options.json``); a resumed
loop with other options is refused before rendering (its finished times would not match), otherwise it reads
the finished times back (not rendered again), the unfinished one resumes from its checkpoint(s), and the
folder goes once the loop's NetCDF and MP4 are written.
"""
from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

# constant over the loop (one grid, one satellite): kept once, without a time dimension
STATIC_VARIABLES = ("sensor_zenith_angle", "sensor_azimuth_angle", "in_domain", "fixed_grid_projection")
# attributes of one render that differ between times: variables on the time dimension in the loop
PER_TIME_ATTRS = {"rendered_solar_zenith_deg": ("rendered_solar_zenith_angle", "solar zenith angle of the one sun "
                                                "that lit the render (the domain's centre)", "degree"),
                  "spp": ("spp", "samples per pixel", "1"), "seconds": ("render_seconds", "render time", "s"),
                  "one_sun_max_error_deg": ("one_sun_max_error", "largest angle between the rendered sun and a "
                                            "column's own", "degree")}


@dataclass
class SatelliteLoop:
    netcdf: Path
    mp4: Path
    pngs: list[Path]
    rendered: int        # times rendered by this run (the others were read back from OUT.nc.parts)
    contact_sheet: Path | None = None  # OUT_contact_sheet.png: every time's picture, labelled


def parts_folder(nc) -> Path:
    """The loop's working folder beside ``nc``: OUT.nc.parts (finished times, the unfinished checkpoint)."""
    nc = Path(nc)
    return nc.with_name(nc.name + ".parts")


def check_unfinished_loop(nc, resume: bool) -> None:
    """A ValueError where an unfinished loop's working folder is there and ``--resume`` is not given."""
    work = parts_folder(nc)
    if work.is_dir() and any(work.iterdir()) and not resume:
        raise ValueError(f"{work} holds an unfinished loop: add --resume to continue it (finished times are not "
                         "rendered again), or delete it to render afresh")


def time_tag(valid_time) -> str:
    """A valid time "2024-05-20T21:00:00Z" as a file-name tag "20240520T210000Z"."""
    return str(valid_time).replace("-", "").replace(":", "").replace("_", "T")


def check_loop_options(work: Path, options: dict | None, resume: bool) -> None:
    """Record ``options`` (JSON-able: what the loop's times depend on) in ``work``, or, resuming, compare
    them with those recorded: a ValueError naming each that differs (before anything is rendered)."""
    from ..io.resumable import check_recorded_options
    check_recorded_options(work, options, resume, "times", "the loop")


def satellite_loop(hyds: list, render_time, nc, *, resume: bool = False, fps: float = 4.0,
                   report=print, denoise: bool = True, options: dict | None = None) -> SatelliteLoop:
    """Render every time of ``hyds`` (Hydrometeors, one per time, each with its ``valid_time``) and write
    the loop (see the module): ``nc`` (one NetCDF, a CF ``time`` coordinate), OUT_<time>.png and .exr per time,
    OUT.mp4 and OUT_contact_sheet.png.

    render_time : callable (hyd, checkpoint path, resume: bool) -> (dataset, Image) of one time
                  (``imagery.render_satellite`` or ``truecolor.render_true_color`` with the scene of ``hyd``).
    resume      : read back the finished times from OUT.nc.parts, resume the unfinished one's checkpoint.
    denoise     : the PNGs and the MP4 show the denoised reflectance (``satellite_picture``).
    options     : what the times depend on (the command's options), checked against a resumed loop's
                  (``check_loop_options``).
    """
    import xarray as xr
    from ..io.image import write_png8
    from ..io.output_paths import written_atomically
    from .movie import contact_sheet, write_mp4
    from .satellite_picture import picture, shown_dataset
    nc = Path(nc)
    work = parts_folder(nc)
    check_unfinished_loop(nc, resume)
    tags = [time_tag(h.attrs.get("valid_time") or h.attrs.get("time", k)) for k, h in enumerate(hyds)]
    if len(set(tags)) != len(tags):
        raise ValueError(f"the selected times are not distinct ({', '.join(tags)}): select each time once")
    check_loop_options(work, options, resume)
    work.mkdir(parents=True, exist_ok=True)
    parts, frames, pngs, rendered = [], [], [], 0
    for k, (hyd, tag) in enumerate(zip(hyds, tags)):
        part, ckpt = work / f"{tag}.nc", work / f"{tag}.exr.ckpt.npz"
        if resume and part.is_file():
            ds = xr.load_dataset(part)
            for v in ds.variables.values():  # written again as the loop's: xarray's encoding of this file goes
                v.encoding = {}
            report(f"time {k + 1}/{len(hyds)} ({tag}): finished before, read back from {part}")
            frame = picture(ds, denoise=denoise)
        else:
            started = sorted(work.glob(f"{tag}.exr*.ckpt.npz"))  # its checkpoint, or one per band (--rayleigh)
            ds, img = render_time(hyd, ckpt, bool(resume and started))
            shown = shown_dataset(ds, img, denoise)
            img.save(nc.with_name(f"{nc.stem}_{tag}.exr"))
            with written_atomically(part, "NetCDF file") as tmp:
                ds.to_netcdf(tmp)
            for c in sorted(work.glob(f"{tag}.exr*.ckpt.npz")):
                c.unlink(missing_ok=True)
            rendered += 1
            report(f"time {k + 1}/{len(hyds)} ({tag}): {img.metadata['spp']} spp, {img.metadata['seconds']:.1f} s")
            frame = picture(shown, denoise=False)
        pngs.append(write_png8(nc.with_name(f"{nc.stem}_{tag}.png"), frame))
        parts.append(ds)
        frames.append(frame)
    loop = loop_dataset(parts)
    with written_atomically(nc, "NetCDF file") as tmp:
        loop.to_netcdf(tmp)
    mp4 = write_mp4(nc.with_suffix(".mp4"), frames, fps=fps)
    sheet = contact_sheet(nc.with_name(f"{nc.stem}_contact_sheet.png"), frames,
                          [str(d.attrs.get("valid_time", t)) for d, t in zip(parts, tags)])
    shutil.rmtree(work, ignore_errors=True)
    return SatelliteLoop(nc, mp4, pngs, rendered, sheet)


def loop_dataset(parts: list):
    """One CF-1.8 dataset of the per-time datasets ``parts`` (``imagery.satellite_dataset`` or
    ``truecolor.rgb_dataset``): a ``time`` coordinate (the valid times, CF-encoded by xarray), the
    per-time fields on it, the view's fields once; the render's per-time attributes as variables."""
    import xarray as xr
    times = [np.datetime64(str(d.attrs["valid_time"]).rstrip("Z"), "s") for d in parts]
    varying = [v for v in parts[0].data_vars if v not in STATIC_VARIABLES]
    per_time = [d[varying].drop_vars([c for c in ("lat", "lon") if c in d.coords]) for d in parts]
    ds = xr.concat(per_time, dim="time", combine_attrs="drop_conflicts", coords="minimal", compat="override")
    ds = ds.merge(parts[0][list(STATIC_VARIABLES)])  # the view's fields and lat/lon, once
    ds = ds.assign_coords(time=("time", np.asarray(times, "datetime64[ns]"),
                                {"standard_name": "time", "long_name": "valid time (UTC)", "axis": "T"}))
    for attr, (name, long_name, units) in PER_TIME_ATTRS.items():
        if attr in parts[0].attrs:
            ds[name] = ("time", np.asarray([float(d.attrs[attr]) for d in parts]),
                        {"long_name": long_name, "units": units})
    first = parts[0].attrs
    ds.attrs = {k: v for k, v in first.items() if k not in PER_TIME_ATTRS and k not in ("valid_time", "cloud_rse_mean")
                and all(str(d.attrs.get(k)) == str(v) for d in parts)}
    ds.attrs.update(start_time=str(first["valid_time"]), end_time=str(parts[-1].attrs["valid_time"]),
                    times=len(parts), title=str(first["title"]).replace(" image", " loop"))
    return ds


__all__ = ["SatelliteLoop", "satellite_loop", "loop_dataset", "check_unfinished_loop", "parts_folder",
           "time_tag", "check_loop_options"]
