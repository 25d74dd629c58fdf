"""Not a validation: the README's storm-spotter pictures (issue 38 part 4), path-traced.

    .venv/bin/python validation/storm_spotter_pictures.py --out docs/images [--spp 64]
        [--only rainbow|anvil|wrf-anvil|haze] [--data ../shared/data]

``rainbow_in_rain_shaft.png``: a shaft of light rain (0.12 g/kg, 0.7 mm drops) under a cloud deck, 3-15 km
north of a camera 150 m up looking 22 deg above the horizon, the sun 8 deg high in the south behind it, coloured
by the clear air on its path (``--atmosphere clear``), Hosek-Wilkie sky, a 0.15 ground; denoised (OIDN).
The bows' angles in such a shaft are measured by ``validation/rainbow.py``.

``sunset_anvil.png``: the demo supercell at a 4 deg sun with the clear air (issue 38's headline view):
``weather-mi render --demo supercell --sun-elevation 4 --sun-azimuth 260 --camera-azimuth 290
--atmosphere clear``; ``sunset_anvil_wrf.png``: the same view of the real WRF supercell
(``--data``/wrf/wrfout_quarter_ss_0130.nc, WSM6, 1 km grid).

``distant_storm_haze.png``: the blue haze of a distant storm (aerial perspective): the demo supercell from a
camera 300 m up at 40, 90 and 150 km, the same 10 deg field of view scaled with the distance so the storm is the
same size, with ``render``'s default clear atmosphere (the air in the box, on the sun's path and along the eye
rays, ``--sky air``): ``weather-mi render --demo supercell --camera ground --camera-distance-km D
--camera-height 300 --fov F --sun-elevation 35``.
"""
from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

ANVIL_VIEW = ["--sun-elevation", "4", "--sun-azimuth", "260", "--camera-azimuth", "290", "--atmosphere", "clear"]
WRF_SUPERCELL = "wrf/wrfout_quarter_ss_0130.nc"  # under --data


def rainbow_scene(size=(320, 200), sun_elevation: float = 8.0, seed: int = 0):
    """(SceneSpec, OpticalVolume): a rain shaft with soft edges under a cloud deck, the sun behind the camera."""
    import weather_mi as wm
    from weather_mi.optics.air import Atmosphere
    spacing = (300.0, 500.0, 500.0)  # dz, dy, dx (m)
    z, y, x = ((np.arange(n) + 0.5) * d + o for n, d, o in zip((30, 24, 48), spacing, (0.0, 3000.0, -12000.0)))
    zz, yy, xx = np.meshgrid(z, y, x, indexing="ij")
    sides = np.clip((12000 - np.abs(xx)) / 2000, 0, 1) * np.clip((15000 - yy) / 2000, 0, 1)
    rain = 1.2e-4 * sides * np.clip((yy - 3000) / 1500, 0, 1) * (zz < 5000)
    cloud = 3e-4 * sides * np.clip((yy - 2000) / 1500, 0, 1) * (zz > 5000) * (zz < 7000)
    hyd = wm.from_arrays({"rain": rain.astype(np.float32), "cloud": cloud.astype(np.float32)}, rho_air=1.0,
                         spacing=spacing, origin=(z[0], y[0], x[0]), source="storm_spotter_pictures rain shaft")
    vol = wm.optical_volume(hyd, wm.species.preset("physical"))
    e = np.radians(22.0)
    cam = wm.Camera(origin=(0.0, 0.0, 150.0), target=(0.0, 1000.0 * np.cos(e), 150.0 + 1000.0 * np.sin(e)),
                    fov=100.0)
    spec = wm.SceneSpec(camera=cam, sun=wm.Sun(180.0, sun_elevation), width=size[0], height=size[1], seed=seed,
                        atmosphere=Atmosphere())
    return spec, vol


def rainbow_picture(out: Path, spp: int, size=(320, 200)) -> Path:
    import weather_mi as wm
    from weather_mi.display.denoise import denoise_image
    spec, vol = rainbow_scene(size)
    img = denoise_image(wm.render_reference(spec, vol, spp=spp, progress=True), spec, vol)
    return img.save_png(out / "rainbow_in_rain_shaft.png")


def anvil_picture(out: Path, spp: int, source: list[str], name: str, size=(320, 240)) -> Path:
    """``weather-mi render SOURCE ANVIL_VIEW`` (``source``: ["--demo", "supercell"] or [a wrfout]) as ``name``."""
    from weather_mi.cli.commands import main as cli
    with tempfile.TemporaryDirectory() as tmp:
        exr = Path(tmp) / "anvil.exr"
        rc = cli(["render", *source, *ANVIL_VIEW, "--size", f"{size[0]}x{size[1]}", "--spp", str(spp), "-o", str(exr)])
        if rc:
            raise SystemExit(f"weather-mi render failed ({rc})")
        return Path(shutil.copy(exr.with_suffix(".png"), out / name))


HAZE_DISTANCES_KM = (40.0, 90.0, 150.0)


def haze_picture(out: Path, spp: int, size=(200, 150)) -> Path:
    """The demo supercell at ``HAZE_DISTANCES_KM`` (a field of view of 10 deg at 40 km, narrower farther away),
    side by side: the farther, the bluer and paler the storm and the ground."""
    import matplotlib.image as mpimg
    from weather_mi.cli.commands import main as cli
    from weather_mi.io.image import Image, auto_exposure
    panels, exposure = [], None
    with tempfile.TemporaryDirectory() as tmp:
        for d in HAZE_DISTANCES_KM:
            fov = float(np.degrees(2 * np.arctan(np.tan(np.radians(5.0)) * 40.0 / d)))
            exr = Path(tmp) / f"haze_{d:g}.exr"
            rc = cli(["render", "--demo", "supercell", "--camera", "ground", "--camera-distance-km", f"{d:g}",
                      "--camera-height", "300", "--fov", f"{fov:.3f}", "--sun-elevation", "35",
                      "--size", f"{size[0]}x{size[1]}", "--spp", str(spp), "-o", str(exr)])
            if rc:
                raise SystemExit(f"weather-mi render failed ({rc})")
            img = Image.load(exr)
            exposure = auto_exposure(img.radiance) if exposure is None else exposure  # the nearest one's, for all
            panels.append(mpimg.imread(img.save_png(Path(tmp) / f"haze_{d:g}_same.png", exposure))[..., :3])
    gap = np.ones((size[1], 4, 3), np.float32)
    row = np.concatenate([x for p in panels for x in (p, gap)][:-1], axis=1)
    path = out / "distant_storm_haze.png"
    mpimg.imsave(path, np.clip(row, 0, 1))
    return path


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="docs/images")
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--only", choices=("rainbow", "anvil", "wrf-anvil", "haze"))
    p.add_argument("--data", default="../shared/data", help="folder holding " + WRF_SUPERCELL)
    a = p.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    if a.only in (None, "rainbow"):
        print("wrote", rainbow_picture(out, a.spp))
    if a.only in (None, "anvil"):
        print("wrote", anvil_picture(out, a.spp, ["--demo", "supercell"], "sunset_anvil.png"))
    if a.only in (None, "haze"):
        print("wrote", haze_picture(out, a.spp))
    if a.only in (None, "wrf-anvil"):
        wrf = Path(a.data) / WRF_SUPERCELL
        if not wrf.exists():
            raise SystemExit(f"{wrf}: not found (the real WRF supercell; --data names its folder)")
        print("wrote", anvil_picture(out, a.spp, [str(wrf)], "sunset_anvil_wrf.png"))


if __name__ == "__main__":
    main()
