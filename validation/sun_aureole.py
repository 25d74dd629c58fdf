"""The sun's size only matters near the sun: looking at the sun through a thin cloud, a disk sun (0.53
deg) and a point sun give the same radiance away from the sun and differ in the aureole, where the
cloud droplets' diffraction peak (about 1 deg wide) is averaged over the disk.

    .venv/bin/python validation/sun_aureole.py [--spp 256] [--size 96] [-o out/aureole]

A layer of cloud droplets (the "physical" preset's Mie table, optical depth --tau) 1-2 km above the
ground; a camera on the ground looks at the sun (elevation 40 deg) with a --fov field of view and a
constant sky. Prints the mean radiance of the two suns in rings of angular distance from the sun
(with standard errors) and writes a figure: both images and the radial profiles.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import weather_mi as wm  # noqa: E402
from weather_mi.scene.spec import direction_from_angles  # noqa: E402

SUN_AZ, SUN_EL = 180.0, 40.0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--size", type=int, default=96)
    ap.add_argument("--fov", type=float, default=8.0, help="horizontal field of view (degrees)")
    ap.add_argument("--tau", type=float, default=0.5, help="vertical optical depth of the layer")
    ap.add_argument("--forward-peak", type=float, default=0.1,
                    help="delta-M cone (render_reference's forward_peak_deg; its default, 3 deg, would count the "
                         "aureole inside 3 deg as the sun's beam): this thin layer converges without it")
    ap.add_argument("-o", "--output", default="out/aureole")
    args = ap.parse_args(argv)

    n = 8
    beta = np.zeros((n, n, n), np.float32)
    beta[:] = args.tau / 1000.0
    cloud = wm.species.preset("physical")["cloud"]
    table = wm.phase.for_species([cloud], mode="per_species")[0]
    vol = wm.OpticalVolume.from_arrays(beta_ext=beta, albedo=1.0, phase=table,
                                       bbox=((-20000.0, -20000.0, 1000.0), (20000.0, 20000.0, 2000.0)))
    to_sun = direction_from_angles(SUN_AZ, SUN_EL)
    origin = np.array([0.0, 0.0, 10.0])
    cam = wm.Camera(tuple(origin), tuple(origin + 1000.0 * to_sun), fov=args.fov)
    images = {}
    for label, diameter in (("disk 0.53 deg", 0.53), ("point", 0.0)):
        spec = wm.SceneSpec(camera=cam, sun=wm.Sun(SUN_AZ, SUN_EL, angular_diameter_deg=diameter),
                            sky=wm.Sky("constant", radiance=0.02), ground=wm.Ground(0.1), width=args.size,
                            height=args.size)
        images[label] = wm.render_reference(spec, vol, spp=args.spp, forward_peak_deg=args.forward_peak)
    # angular distance of every pixel's centre from the sun (small-angle pinhole geometry)
    half = np.tan(np.radians(args.fov) / 2)
    u = (np.arange(args.size) + 0.5) / args.size * 2 - 1
    xx, yy = np.meshgrid(u * half, u * half)
    ang = np.degrees(np.arctan(np.hypot(xx, yy)))
    edges = [0.0, 0.3, 0.6, 1.0, 1.5, 2.0, 3.0, args.fov / 2]
    print(f"thin cloud (optical depth {args.tau}) in front of the sun, {args.size}^2, {args.spp} spp")
    print(f"{'ring (deg)':>12s} {'disk':>22s} {'point':>22s} {'(disk-point)/se':>16s}")
    profile = []
    for a, b in zip(edges[:-1], edges[1:]):
        ring = (ang >= a) & (ang < b)
        vals = []
        for img in images.values():
            lum, se = img.radiance.mean(axis=2), img.stderr.mean(axis=2)
            if ring.any() and np.isfinite(se[ring]).all():
                vals.append((float(lum[ring].mean()), float(np.sqrt((se[ring] ** 2).sum()) / ring.sum())))
            else:
                vals.append((float(lum[ring].mean()) if ring.any() else np.nan, np.nan))
        (d, sd), (p, sp) = vals
        z = (d - p) / np.hypot(sd, sp) if np.isfinite(sd) and np.isfinite(sp) else np.nan
        profile.append((a, b, d, sd, p, sp))
        print(f"{a:5.1f} - {b:4.1f} {d:12.4g} +- {sd:7.2g} {p:12.4g} +- {sp:7.2g} {z:16.1f}")
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(13, 4))
    vmax = np.percentile(images["disk 0.53 deg"].radiance.mean(axis=2), 99.5)
    for k, (label, img) in enumerate(images.items()):
        ax[k].imshow(np.log10(np.maximum(img.radiance.mean(axis=2), 1e-4)), vmin=-3, vmax=np.log10(vmax),
                     extent=[-args.fov / 2, args.fov / 2, -args.fov / 2, args.fov / 2])
        ax[k].set_title(f"{label}: log10 radiance")
        ax[k].set_xlabel("degrees")
    mids = [(a + b) / 2 for a, b, *_ in profile]
    ax[2].errorbar(mids, [r[2] for r in profile], yerr=[r[3] for r in profile], label="disk 0.53 deg")
    ax[2].errorbar(mids, [r[4] for r in profile], yerr=[r[5] for r in profile], label="point")
    ax[2].set_yscale("log")
    ax[2].set_xlabel("angle from the sun's centre (deg)")
    ax[2].set_ylabel("mean radiance in the ring")
    ax[2].legend()
    fig.tight_layout()
    fig.savefig(out / "aureole.png", dpi=90)
    print(f"wrote {out / 'aureole.png'}")


if __name__ == "__main__":
    main()
