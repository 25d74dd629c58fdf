"""The real WRF supercell (em_quarter_ss, WSM6, 1 km grid, 01:30 into the run) from ../shared/data.

    .venv/bin/python scenes/wrf_supercell.py [--spp 64] [-o out/]
"""
import argparse
from pathlib import Path

import weather_mi as wm

ap = argparse.ArgumentParser()
ap.add_argument("--file", default=str(Path(__file__).resolve().parents[2] / "shared/data/wrf/wrfout_quarter_ss_0130.nc"))
ap.add_argument("--spp", type=int, default=64)
ap.add_argument("-o", "--out", default="out")
args = ap.parse_args()

hyd = wm.open_wrf(args.file, time=-1)                 # destaggered, regridded onto a uniform height grid
print(wm.cli.commands.info_text(hyd, "physical"))
vol = wm.optical_volume(hyd, species="physical")      # WRF-consistent radii (the paper's make anvils too thin)
spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=160, elevation=10), sun=wm.Sun(250, 30),
                    sky=wm.Sky("sunsky"), ground=wm.Ground(0.15), width=320, height=240)
img = wm.render_reference(spec, vol, spp=args.spp, checkpoint=Path(args.out) / "wrf.ckpt.npz")
img.save(Path(args.out) / "wrf_supercell.exr")
img.save_png(Path(args.out) / "wrf_supercell.png")
