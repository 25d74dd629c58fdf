"""The BOMEX trade cumulus (LES, 50 m grid) from ../shared/data, back-lit: silver lining.

    .venv/bin/python scenes/les_cumulus.py [--spp 64] [-o out/]
"""
import argparse
from pathlib import Path

import weather_mi as wm

ap = argparse.ArgumentParser()
ap.add_argument("--file", default=str(Path(__file__).resolve().parents[2] / "shared/data/les/bomex_50m.txt"))
ap.add_argument("--spp", type=int, default=64)
ap.add_argument("-o", "--out", default="out")
args = ap.parse_args()

hyd = wm.open_les(args.file)                           # LWC (g/m^3) -> mixing ratio with the standard atmosphere
vol = wm.optical_volume(hyd, species="physical")       # uses the file's effective radii; LES: periodic="transport"
sun = wm.Sun(azimuth=30, elevation=20)
spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=210, elevation=5), sun=sun,   # looking towards the sun
                    sky=wm.Sky("sunsky"), ground=wm.Ground(0.1), width=320, height=240)
img = wm.render_reference(spec, vol, spp=args.spp)
img.save(Path(args.out) / "bomex.exr")
img.save_png(Path(args.out) / "bomex.png")
