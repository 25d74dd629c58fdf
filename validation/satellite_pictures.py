"""The README's satellite pictures (issue 40): ``weather-mi satellite`` run as a user runs it, its PNGs put
side by side and made small for docs/images/.

1. The Tibetan-plateau Thompson wrfout (real WRF output on its own Lambert grid, 2005-09-21 03:00 UTC) seen by
   Himawari: true colour (``--rgb --rayleigh``: AHI's 0.47/0.51/0.64 um, sun-zenith and Rayleigh corrected,
   CIRA stretch) beside its 0.64 um band, both denoised, with GSHHG shorelines (the plateau's lakes) and the
   latitude/longitude graticule: docs/images/satellite_plateau_true_colour_and_band.png
2. The bundled 4-time supercell series as a true-colour loop (placed at 35.2 N 97.4 W: an ideal case, so no
   coastlines): its contact sheet, docs/images/satellite_loop_contact_sheet.png

    .venv/bin/python validation/satellite_pictures.py [--resolution 2km] [--spp 64] [--out docs/images]

The commands it runs are printed; the NetCDF, EXR, PNG and MP4 outputs stay in out/satellite_pictures/.
"""
from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MAX_BYTES = 300_000


def run(argv: list[str]) -> None:
    from weather_mi.cli.commands import main
    print("weather-mi " + " ".join(argv), flush=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        if main(argv) != 0:
            raise SystemExit(f"failed: weather-mi {' '.join(argv)}")


def save_small(frame: np.ndarray, path: Path, max_bytes: int = MAX_BYTES) -> Path:
    """``frame`` as a PNG under ``max_bytes``: as it is, else 256 colours, else halved until it fits."""
    from PIL import Image
    img = Image.fromarray(frame)
    while True:
        img.save(path, optimize=True)
        if path.stat().st_size <= max_bytes:
            return path
        img.quantize(256, dither=Image.Dither.NONE).save(path, optimize=True)
        if path.stat().st_size <= max_bytes:
            return path
        img = img.resize((img.width // 2, img.height // 2), Image.LANCZOS)


def side_by_side(left: np.ndarray, right: np.ndarray, gap: int = 6) -> np.ndarray:
    h = max(left.shape[0], right.shape[0])
    pad = [np.pad(a, ((0, h - a.shape[0]), (0, 0), (0, 0)), constant_values=16) for a in (left, right)]
    return np.concatenate([pad[0], np.full((h, gap, 3), 16, np.uint8), pad[1]], axis=1)


def main() -> None:
    from PIL import Image
    ap = argparse.ArgumentParser()
    ap.add_argument("--resolution", default="2km")
    ap.add_argument("--spp", default="64")
    ap.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--work", default=str(ROOT / "out" / "satellite_pictures"))
    ap.add_argument("--out", default=str(ROOT / "docs" / "images"))
    a = ap.parse_args()
    work, out, data = Path(a.work), Path(a.out), Path(a.data)
    work.mkdir(parents=True, exist_ok=True)
    out.mkdir(parents=True, exist_ok=True)
    plateau = [str(data / "wrf" / "wrf_d01_allvars_cropped.nc"), "--time", "1", "--satellite", "himawari",
               "--resolution", a.resolution, "--spp", a.spp]
    run(["satellite", *plateau, "--rgb", "--rayleigh", "-o", str(work / "plateau_rgb.nc")])
    run(["satellite", *plateau, "--band", "0.64", "-o", str(work / "plateau_064.nc")])
    pair = side_by_side(np.asarray(Image.open(work / "plateau_rgb.png")), np.asarray(Image.open(work / "plateau_064.png")))
    print("wrote", save_small(pair, out / "satellite_plateau_true_colour_and_band.png"))
    run(["satellite", str(data / "wrf" / "wrfout_quarter_ss_series.nc"), "--time", "all", "--lat", "35.2", "--lon",
         "-97.4", "--date", "2013-05-20T20:00", "--rgb", "--resolution", a.resolution, "--spp", a.spp,
         "-o", str(work / "loop.nc")])
    sheet = np.asarray(Image.open(work / "loop_contact_sheet.png").convert("RGB"))
    print("wrote", save_small(sheet, out / "satellite_loop_contact_sheet.png"))


if __name__ == "__main__":
    main()
