"""The satellite PNG's denoised layer (issue 40 part 4): its bias on two satellite views, raw and OIDN-denoised
(``display.satellite_picture.denoised``, what ``weather-mi satellite`` shows) at a few spp against a long
render of the same view (another seed), over the reference's cloud pixels (eye-ray transmittance below 1/2):
relative mean bias and relative RMS error (the reference's own noise removed: ``study.denoiser.error_figures``).

Views (0.64 um):
  supercell  the real WRF supercell (wrfout_quarter_ss_0130.nc) placed at 35.2 N 97.4 W, 2013-05-20 20:00 UTC,
             GOES-East
  plateau    the Tibetan-plateau Thompson wrfout (its own Lambert grid and time 1), Himawari

    .venv/bin/python validation/satellite_denoiser_bias.py [--resolution 2] [--ref-spp 1024] [--spp 16,64]

Writes out/satellite_denoiser_bias/{table.md, rows.json} and the references (*_ref.exr, reused by a later run
of the same resolution and spp: delete them to render afresh).
"""
from __future__ import annotations

import argparse
import json
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
VIEWS = {"supercell": ("wrf/wrfout_quarter_ss_0130.nc", None, "goes-east", (35.2, -97.4, "2013-05-20T20:00")),
         "plateau": ("wrf/wrf_d01_allvars_cropped.nc", 1, "himawari", None)}


def scene_of(name: str, data: Path, resolution_km: float):
    import weather_mi as wm
    from weather_mi.satellite.imagery import satellite_scene
    from weather_mi.scene.place import assume_place
    path, time_index, sat, place = VIEWS[name]
    hyd = wm.open_source(str(data / path), None, time_index)
    if place is not None:
        hyd = assume_place(hyd, *place)
    vol = wm.optical_volume(hyd, species="physical")
    hyd = hyd.drop_vars([v for v in hyd.data_vars if v != "rho_air"])
    return satellite_scene(hyd, vol, sat, "0.64", resolution_km)


def main() -> None:
    import weather_mi as wm
    from weather_mi.display.satellite_picture import denoised
    from weather_mi.satellite.imagery import render_satellite, satellite_dataset
    from weather_mi.study.denoiser import error_figures
    from weather_mi.study.report import _table
    ap = argparse.ArgumentParser()
    ap.add_argument("--resolution", type=float, default=2.0, help="pixel size (km)")
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--spp", default="16,64")
    ap.add_argument("--views", default="supercell,plateau")
    ap.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("-o", "--out", default=str(ROOT / "out" / "satellite_denoiser_bias"))
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    warnings.simplefilter("ignore", UserWarning)
    rows, refs = [], []
    for name in a.views.split(","):
        scene = scene_of(name, Path(a.data), a.resolution)
        cached = out / f"{name}_{a.resolution:g}km_{a.ref_spp}spp_ref.exr"
        t0 = time.perf_counter()
        if cached.is_file():
            ref = wm.Image.load(cached)
        else:
            ref = render_satellite(replace(scene, spec=replace(scene.spec, seed=7)), spp=a.ref_spp, progress=False)[1]
            ref.save(cached)
        mask = np.asarray(ref.transmittance) < 0.5
        n = ref.metadata["noise"]
        refs.append({"view": name, "pixels": f"{scene.view.size[0]} x {scene.view.size[1]}", "cloud_pixels": int(mask.sum()),
                     "spp": ref.metadata["spp"], "seconds": time.perf_counter() - t0, "rse_mean": n["rse_mean"],
                     "rms_se_over_mean": n["rms_se_over_mean"]})
        print(refs[-1], flush=True)
        for spp in (int(s) for s in a.spp.split(",")):
            ds, img = render_satellite(scene, spp=spp, progress=False)
            raw = np.repeat(ds["reflectance"].values[..., None], 3, axis=2)
            t0 = time.perf_counter()
            den = denoised(satellite_dataset(scene, img))["reflectance"].values
            t_den = time.perf_counter() - t0
            for label, x, secs in (("raw", raw, float(img.metadata["seconds"])),
                                   ("denoised", np.repeat(den[..., None], 3, axis=2), t_den)):
                f = error_figures(ref, x, mask)
                rows.append({"view": name, "spp": spp, "image": label, "seconds": secs,
                             "rel_bias": f["rel_bias"], "rel_rms": f["rel_rms"]})
                print(rows[-1], flush=True)
    (out / "rows.json").write_text(json.dumps({"refs": refs, "rows": rows}, indent=1))
    text = [f"References ({a.resolution:g} km pixels, 0.64 um, seed 7; cloud pixels: the reference's eye-ray "
            "transmittance below 1/2):", "", _table(refs, list(refs[0])), "",
            "Raw and denoised (the PNG's layer) against them over cloud pixels (rel_rms with the reference's noise "
            "removed; seconds: the render's, or the denoiser's own):", "",
            _table(rows, ["view", "spp", "image", "seconds", "rel_bias", "rel_rms"])]
    (out / "table.md").write_text("\n".join(text))
    print("\n".join(text))


if __name__ == "__main__":
    main()
