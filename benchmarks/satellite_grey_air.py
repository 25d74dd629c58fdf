"""issue 38 part 5: satellite one band (0.64 um) with the clear air, paired in one process: none, clear tracked as
three equal channels (spectral tracking: ``kernel.plugins.air_levels.is_grey`` patched to False, as before the grey
air) and clear grey; order rotating; medians.

    .venv/bin/python benchmarks/satellite_grey_air.py RESOLUTION_KM SPP ROUNDS   (e.g. 2 64 5)
"""
import sys
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import sys, time, warnings
import numpy as np
warnings.simplefilter("ignore", UserWarning)
import weather_mi as wm
from weather_mi.kernel.plugins import air_levels as medium
from weather_mi.optics.air import Atmosphere
from weather_mi.satellite import imagery as si
from weather_mi.scene.place import assume_place
res, spp, reps = float(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
hyd = assume_place(wm.open_source(None, "supercell"), 35.2, -97.4, "2013-05-20T20:00")
vol = wm.optical_volume(hyd, species="physical")
scenes = {"none": si.satellite_scene(hyd, vol, "goes-east", "0.64", res),
          "clear-rgb3": si.satellite_scene(hyd, vol, "goes-east", "0.64", res, atmosphere=Atmosphere()),
          "clear-grey": si.satellite_scene(hyd, vol, "goes-east", "0.64", res, atmosphere=Atmosphere())}
orig = medium.is_grey
def run(k, n):
    medium.is_grey = (lambda air: False) if k == "clear-rgb3" else orig
    t = time.perf_counter()
    ds, img = si.render_satellite(scenes[k], spp=n, progress=False)
    return time.perf_counter() - t, float((img.metadata.get("noise") or {}).get("rse_mean", float("nan")))
names = list(scenes)
for k in names:
    run(k, 4)
rec = {k: [] for k in names}
for r in range(reps):
    for k in names[r % 3:] + names[:r % 3]:
        rec[k].append(run(k, spp))
for k in names:
    print(k, ", ".join(f"{t:.2f}" for t, _ in rec[k]), f"RSE {rec[k][0][1]:.3f}")
for k in names[1:]:
    rat = sorted(a[0] / b[0] for a, b in zip(rec[k], rec["none"]))
    med = float(np.median(rat))
    print(f"{k}/none per round {', '.join(f'{x:.2f}' for x in rat)}; median {med:.2f}x; same RSE {med * (rec[k][0][1] / rec['none'][0][1]) ** 2:.2f}x")
rat = sorted(a[0] / b[0] for a, b in zip(rec["clear-grey"], rec["clear-rgb3"]))
print(f"grey/rgb3 per round {', '.join(f'{x:.2f}' for x in rat)}; median {float(np.median(rat)):.2f}x")
