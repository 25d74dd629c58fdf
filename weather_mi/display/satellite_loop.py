"""A loop of synthetic satellite images (``weather-mi satellite --time all``): every time of a series rendered
by ``satellite.imagery`` (one band) or ``satellite.truecolor`` (``--rgb``), written as one CF NetCDF with a
``time`` dimension, a PNG and an EXR per time (named with the valid time) and an MP4 loop.

One exposure for all frames: a band's PNG shows the reflectance itself (0-1, sRGB-encoded, as the single
image's), a true-colour PNG the operational recipe (``truecolor.true_color``): fixed scales, so that a
brightening storm gets brighter rather than re-exposed.

Resumable: while the loop runs, ``OUT.nc.parts/`` holds the dataset of every finished time and the
checkpoint of the unfinished one; a resumed loop reads the finished times back (not rendered again), the
unfinished one resumes from its checkpoint, and the folder goes once the loop's NetCDF and MP4 are written.
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


def frame_of(ds) -> np.ndarray:
    """The 8-bit (H, W, 3) picture of one time's dataset: the true-colour recipe where it has a band
    dimension, else the reflectance at exposure 1 (sRGB-encoded, grey)."""
    if "band" in ds.dims:
        from ..satellite.truecolor import true_color8
        return true_color8(ds)
    from ..io.image import to_srgb8
    refl = np.asarray(ds["reflectance"].values, np.float64)
    return to_srgb8(np.repeat(refl[..., None], 3, axis=2), 1.0)


def satellite_loop(hyds: list, render_time, nc, *, resume: bool = False, fps: float = 4.0,
                   report=print) -> SatelliteLoop:
    """Render every time of ``hyds`` (Hydrometeors, one per time, each with its ``valid_time``) and write
    the loop (see the module): ``nc`` (one NetCDF, a CF ``time`` coordinate), OUT_<time>.png and .exr per time,
    OUT.mp4.

    render_time : callable (hyd, checkpoint path, resume: bool) -> (dataset, Image) of one time
                  (``imagery.render_satellite`` or ``truecolor.render_true_color`` with the scene of ``hyd``).
    resume      : read back the finished times from OUT.nc.parts, resume the unfinished one's checkpoint.
    """
    import xarray as xr
    from ..io.image import write_png8
    from ..io.output_paths import written_atomically
    from .movie import write_mp4
    nc = Path(nc)
    work = parts_folder(nc)
    check_unfinished_loop(nc, resume)
    tags = [time_tag(h.attrs.get("valid_time") or h.attrs.get("time", k)) for k, h in enumerate(hyds)]
    if len(set(tags)) != len(tags):
        raise ValueError(f"the selected times are not distinct ({', '.join(tags)}): select each time once")
    work.mkdir(parents=True, exist_ok=True)
    parts, frames, pngs, rendered = [], [], [], 0
    for k, (hyd, tag) in enumerate(zip(hyds, tags)):
        part, ckpt = work / f"{tag}.nc", work / f"{tag}.exr.ckpt.npz"
        if resume and part.is_file():
            ds = xr.load_dataset(part)
            for v in ds.variables.values():  # written again as the loop's: xarray's encoding of this file goes
                v.encoding = {}
            report(f"time {k + 1}/{len(hyds)} ({tag}): finished before, read back from {part}")
        else:
            ds, img = render_time(hyd, ckpt, resume and ckpt.is_file())
            img.save(nc.with_name(f"{nc.stem}_{tag}.exr"))
            with written_atomically(part, "NetCDF file") as tmp:
                ds.to_netcdf(tmp)
            ckpt.unlink(missing_ok=True)
            rendered += 1
            report(f"time {k + 1}/{len(hyds)} ({tag}): {img.metadata['spp']} spp, {img.metadata['seconds']:.1f} s")
        frame = frame_of(ds)
        pngs.append(write_png8(nc.with_name(f"{nc.stem}_{tag}.png"), frame))
        parts.append(ds)
        frames.append(frame)
    loop = loop_dataset(parts)
    with written_atomically(nc, "NetCDF file") as tmp:
        loop.to_netcdf(tmp)
    mp4 = write_mp4(nc.with_suffix(".mp4"), frames, fps=fps)
    shutil.rmtree(work, ignore_errors=True)
    return SatelliteLoop(nc, mp4, pngs, rendered)


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
           "time_tag", "frame_of"]
