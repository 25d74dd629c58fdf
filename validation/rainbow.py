"""Issue 38 part 4, what a storm spotter knows: the rainbow in a rain shaft with the sun behind the camera.

    .venv/bin/python validation/rainbow.py [--size 120x96] [--spp 64] [--radius-mm 0.7] [--spectral] [--png out.png]

A thin shaft of light rain (0.05 g/kg, the "physical" species' 0.7 mm drops, optical depth ~0.3 along the
eye rays: single scattering dominates) 1.5-4 km in front of a camera looking 24 deg up towards the antisolar
azimuth, the sun 20 deg high behind it (a 0.53 deg disk, white, no sky, no ground), rendered by the path
tracer (``render_reference``, the default estimator). Each pixel's antisolar angle (between its ray and the
direction away from the sun) comes from the camera's pixel-centre rays (``slicing.geometry.camera_rays``,
Mitsuba's perspective sensor); the radiance divided by the eye ray's scattered fraction 1 - T (so that the
shaft's depth along each ray drops out) is averaged in 0.1 deg bins of that angle, per channel (650, 550 and
450 nm). Measured: the primary bow's angle per channel (the profile's maximum in 39.5-44 deg, refined by a
parabola through the 5 bins around it), the secondary's (49-54.5 deg), and Alexander's dark band: its mean
(44.5-48.5 deg) against the mean inside the primary (36-39.5 deg) and outside the secondary (53.5-55.5 deg).

The reference, independent of weather_mi: Descartes' minimum deviation for k internal reflections,
cos^2 i = (n^2 - 1) / (k (k + 2)), D = 2 (i - r) + k (pi - 2 r), sin i = n sin r (primary: antisolar angle
180 - D_1, secondary D_2 - 180), with water's index from the IAPWS formulation (Harvey et al. 1998, J. Phys.
Chem. Ref. Data 27, 761; IAPWS R9-97) at 20 C and 1 atm, relative to air. Mie theory puts the maximum of a
distribution of mm drops a little inside the geometric bow (Airy: ~0.1-0.2 deg for 0.7 mm drops, more for
red), and the sun's 0.53 deg disk blurs it; the target is 0.3 deg. ``--spectral`` measures the spectral mode's
sRGB channels the same way: each is a band of wavelengths (the bow of each wavelength drawn from the rain tables
every 25 nm, ``optics.phase.spectral_tables``), so its Descartes angles are indicative only; it also prints the
primary bow of those tables at 450 / 550 / 650 nm and between nodes against Descartes at each wavelength.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

# IAPWS R9-97 (Harvey, Gallagher & Levelt Sengers 1998), Eq. 1: the Lorentz-Lorenz function of the index
#   (n^2 - 1) / (n^2 + 2) / rho_r = a0 + a1 rho_r + a2 T_r + a3 L^2 T_r + a4 / L^2 + a5 / (L^2 - L_uv^2)
#                                   + a6 / (L^2 - L_ir^2) + a7 rho_r^2
# with T_r = T / 273.15 K, rho_r = rho / 1000 kg/m^3, L = lambda / 0.589 um (vacuum wavelength).
IAPWS_A = (0.244257733, 9.74634476e-3, -3.73234996e-3, 2.68678472e-4, 1.58920570e-3, 2.45934259e-3,
           0.900704920, -1.66626219e-2)
IAPWS_L_UV, IAPWS_L_IR = 0.2292020, 5.432937
WATER_20C_KG_M3 = 998.21            # density of water at 20 C and 1 atm (kg/m^3)
N_AIR = 1.000272                    # air at 20 C, 1013 hPa, 450-650 nm (Ciddor 1996: 1.000271-1.000274)
CHANNEL_NM = (650.0, 550.0, 450.0)  # R, G, B

PRIMARY_WINDOW, SECONDARY_WINDOW = (39.5, 44.0), (49.0, 54.5)   # antisolar angle (deg) where each bow is sought
BAND, INSIDE, OUTSIDE = (44.5, 48.5), (36.0, 39.5), (53.5, 55.5)  # dark band, inside primary, outside secondary


def water_index_iapws(wavelength_nm, temperature_k: float = 293.15, density_kg_m3: float = WATER_20C_KG_M3):
    """Real refractive index of liquid water relative to vacuum (IAPWS R9-97, Eq. 1), at vacuum ``wavelength_nm``."""
    a0, a1, a2, a3, a4, a5, a6, a7 = IAPWS_A
    t, rho = temperature_k / 273.15, density_kg_m3 / 1000.0
    l2 = (np.asarray(wavelength_nm, np.float64) / 589.0) ** 2
    f = rho * (a0 + a1 * rho + a2 * t + a3 * l2 * t + a4 / l2 + a5 / (l2 - IAPWS_L_UV ** 2)
               + a6 / (l2 - IAPWS_L_IR ** 2) + a7 * rho ** 2)
    return np.sqrt((1 + 2 * f) / (1 - f))


def descartes_deg(n, k: int):
    """Antisolar angle (deg) of the k-th order rainbow (k internal reflections) of spheres of relative index n:
    the minimum deviation D (cos^2 i = (n^2 - 1) / (k (k + 2))), folded to the scattering angle, from 180."""
    n = np.asarray(n, np.float64)
    i = np.arccos(np.sqrt((n * n - 1) / (k * (k + 2))))
    r = np.arcsin(np.sin(i) / n)
    deviation = np.degrees(2 * (i - r) + k * (np.pi - 2 * r)) % 360.0
    scattering = np.where(deviation > 180.0, 360.0 - deviation, deviation)  # in [0, 180]
    return 180.0 - scattering


def descartes_bows(wavelengths_nm=CHANNEL_NM) -> tuple[np.ndarray, np.ndarray]:
    """(primary, secondary) antisolar angles (deg) per wavelength for water at 20 C in air (IAPWS)."""
    n = water_index_iapws(wavelengths_nm) / N_AIR
    return descartes_deg(n, 1), descartes_deg(n, 2)


def rain_shaft(size=(120, 96), q_rain: float = 5e-5, radius_m: float | None = None, sun_elevation: float = 20.0,
               view_elevation: float = 24.0, fov: float = 30.0, sky=None, ground=None, box_m=None, seed: int = 0):
    """(SceneSpec, OpticalVolume): a uniform shaft of rain (``q_rain`` kg/kg, air 1.1 kg/m^3; the "physical"
    species, rain drops of ``radius_m`` if given) in front of a camera at 200 m looking north ``view_elevation``
    deg up; the sun in the south at ``sun_elevation``. ``box_m``: ((x0, y0, z0), (x1, y1, z1)) of the shaft."""
    import weather_mi as wm
    (x0, y0, z0), (x1, y1, z1) = box_m or ((-1500.0, 1500.0, 0.0), (1500.0, 4000.0, 3600.0))
    shape = (8, 6, 6)
    dz, dy, dx = (z1 - z0) / shape[0], (y1 - y0) / shape[1], (x1 - x0) / shape[2]
    hyd = wm.from_arrays({"rain": np.full(shape, q_rain, np.float32)}, rho_air=1.1, spacing=(dz, dy, dx),
                         origin=(z0 + dz / 2, y0 + dy / 2, x0 + dx / 2), source="validation/rainbow.py rain shaft")
    species = wm.species.preset("physical")
    if radius_m is not None:
        species = wm.species.preset("physical", {"rain": {"radius_m": radius_m}})
    vol = wm.optical_volume(hyd, species)
    e = np.radians(view_elevation)
    cam = wm.Camera(origin=(0.0, 0.0, 200.0), target=(0.0, 1000.0 * np.cos(e), 200.0 + 1000.0 * np.sin(e)), fov=fov)
    spec = wm.SceneSpec(camera=cam, sun=wm.Sun(180.0, sun_elevation), sky=sky, ground=ground,
                        width=size[0], height=size[1], seed=seed)
    return spec, vol


def antisolar_angles_deg(spec) -> np.ndarray:
    """(H, W) angle (deg) between each pixel-centre ray and the antisolar direction."""
    from weather_mi.slicing.geometry import camera_rays
    _, dirs = camera_rays(spec)
    return np.degrees(np.arccos(np.clip(dirs @ -spec.sun.to_sun, -1.0, 1.0)))


def bow_profile(radiance, transmittance, alpha_deg, step_deg: float = 0.1, lo: float = 30.0, hi: float = 60.0):
    """(bin centres (deg), (n, 3) mean of radiance / (1 - T) per bin of antisolar angle; NaN where empty)."""
    edges = np.arange(lo, hi + step_deg / 2, step_deg)
    idx = np.digitize(alpha_deg.ravel(), edges) - 1
    ok = (idx >= 0) & (idx < edges.size - 1) & (transmittance.ravel() < 0.999)
    per = radiance.reshape(-1, 3)[ok] / (1.0 - transmittance.ravel()[ok])[:, None]
    count = np.bincount(idx[ok], minlength=edges.size - 1).astype(np.float64)
    sums = np.stack([np.bincount(idx[ok], per[:, c], minlength=edges.size - 1) for c in range(3)], -1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return 0.5 * (edges[1:] + edges[:-1]), sums / count[:, None]


def peak_deg(angles, values, window) -> float:
    """The maximum of ``values`` in ``window`` (deg), refined by a parabola through the 5 samples around it."""
    m = np.flatnonzero((angles >= window[0]) & (angles <= window[1]) & np.isfinite(values))
    j = m[np.argmax(values[m])]
    s = np.arange(max(j - 2, m[0]), min(j + 2, m[-1]) + 1)
    c2, c1, _ = np.polyfit(angles[s] - angles[j], values[s], 2)
    return float(angles[j] + np.clip(-c1 / (2 * c2), -0.1, 0.1)) if c2 < 0 else float(angles[j])


def _mean_in(angles, values, window) -> float:
    m = (angles >= window[0]) & (angles <= window[1]) & np.isfinite(values)
    return float(values[m].mean())


def measure(angles, profile) -> dict:
    """Per channel (R, G, B): primary and secondary bow angles (deg), and the dark band's mean over the means
    inside the primary and outside the secondary (both < 1 where Alexander's band is darker)."""
    out = {k: np.empty(3) for k in ("primary", "secondary", "band_vs_inside", "band_vs_outside")}
    for c in range(3):
        v = profile[:, c]
        out["primary"][c] = peak_deg(angles, v, PRIMARY_WINDOW)
        out["secondary"][c] = peak_deg(angles, v, SECONDARY_WINDOW)
        band = _mean_in(angles, v, BAND)
        out["band_vs_inside"][c] = band / _mean_in(angles, v, INSIDE)
        out["band_vs_outside"][c] = band / _mean_in(angles, v, OUTSIDE)
    return out


def table_profile(table, step_deg: float = 0.02):
    """(antisolar angles (deg), (n, 3) 4 pi p) of a phase table, on a fine grid (its own interpolant)."""
    alpha = np.arange(30.0, 60.0 + step_deg / 2, step_deg)
    return alpha, 4 * np.pi * table.eval(np.radians(180.0 - alpha))


def spectral_table_bows(radius_m: float, wavelengths_nm=(450.0, 462.5, 537.5, 550.0, 637.5, 650.0)):
    """[(wavelength, primary bow (deg) of the spectral mode's rain table there, Descartes' (IAPWS index))]: its
    tables at the nodes (``optics.phase.spectral_tables``) and interpolated between them, as the kernel reads
    them, on a 0.02 deg grid."""
    from weather_mi.optics import phase
    from weather_mi.optics.phase.spectral_tables import SPECTRAL_NM, STEP_NM, interpolated
    alpha = np.arange(30.0, 60.0 + 0.01, 0.02)
    theta = np.radians(180.0 - alpha)
    rows = []
    for nm in wavelengths_nm:
        j = int(np.clip((nm - SPECTRAL_NM[0]) // STEP_NM, 0, SPECTRAL_NM.size - 2))
        nodes = SPECTRAL_NM[j:j + 2]
        stack = [phase.mie_rain(radius=radius_m, wavelength_m=w * 1e-9) for w in nodes]
        p = interpolated(stack, nodes, nm, theta)
        rows.append((nm, peak_deg(alpha, p, PRIMARY_WINDOW),
                     float(descartes_deg(water_index_iapws(nm) / N_AIR, 1))))
    return rows


def render_and_measure(size=(120, 96), spp: int = 64, radius_m: float | None = None, seed: int = 0, variant=None):
    """(measure(...) of the rendered shaft, the Image, its antisolar angles)."""
    import weather_mi as wm
    spec, vol = rain_shaft(size, radius_m=radius_m, seed=seed)
    img = wm.render_reference(spec, vol, spp=spp, progress=False, variant=variant)
    alpha = antisolar_angles_deg(spec)
    angles, prof = bow_profile(img.radiance.astype(np.float64), img.transmittance.astype(np.float64), alpha)
    return measure(angles, prof), img, alpha


def _print_table(title: str, got: dict, primary, secondary) -> None:
    print(f"\n{title}")
    print("| channel | primary (deg) | Descartes | diff | secondary (deg) | Descartes | dark band / inside primary "
          "| dark band / outside secondary |")
    print("|---|---|---|---|---|---|---|---|")
    for c, nm in enumerate(CHANNEL_NM):
        print(f"| {nm:.0f} nm | {got['primary'][c]:.2f} | {primary[c]:.2f} | {got['primary'][c] - primary[c]:+.2f} "
              f"| {got['secondary'][c]:.2f} | {secondary[c]:.2f} | {got['band_vs_inside'][c]:.2f} "
              f"| {got['band_vs_outside'][c]:.2f} |")


def main(argv=None) -> None:
    import time

    from weather_mi.optics import phase
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--size", default="120x96", help="image WxH")
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--radius-mm", type=float, default=0.7, help="rain drops' effective radius (mm)")
    p.add_argument("--png", help="also write the rendered shaft as a PNG here")
    p.add_argument("--spectral", action="store_true",
                   help="also render with llvm_ad_spectral (its sRGB channels are bands, not 650/550/450 nm lines)")
    a = p.parse_args(argv)
    size = tuple(int(v) for v in a.size.lower().split("x"))
    primary, secondary = descartes_bows()
    n = water_index_iapws(CHANNEL_NM) / N_AIR
    print("water at 20 C in air (IAPWS R9-97): n = " + ", ".join(f"{x:.4f}" for x in n) + " at 650, 550, 450 nm")
    radius = a.radius_mm * 1e-3
    _print_table(f"phase table mie_rain(radius={radius:g}) (default quality)",
                 measure(*table_profile(phase.mie_rain(radius=radius))), primary, secondary)
    t0 = time.perf_counter()
    got, img, _ = render_and_measure(size, a.spp, radius)
    _print_table(f"path tracer, {size[0]}x{size[1]}, {a.spp} spp, {time.perf_counter() - t0:.1f} s", got,
                 primary, secondary)
    if a.spectral:
        print("\nthe spectral mode's rain tables (every 25 nm, linear between): primary bow (deg) against Descartes")
        print("| wavelength (nm) | table | Descartes | diff |")
        print("|---|---|---|---|")
        for nm, bow, ref in spectral_table_bows(radius):
            print(f"| {nm:g} | {bow:.2f} | {ref:.2f} | {bow - ref:+.2f} |")
        t0 = time.perf_counter()
        got, _, _ = render_and_measure(size, a.spp, radius, variant="llvm_ad_spectral")
        _print_table(f"spectral path tracer (sRGB channels), {a.spp} spp, {time.perf_counter() - t0:.1f} s", got,
                     primary, secondary)
    if a.png:
        img.save_png(a.png)
        print(f"wrote {a.png}")


if __name__ == "__main__":
    main()
