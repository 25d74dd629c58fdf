"""True colour as the operational products make it: the 0.47, 0.64 and 0.86 um bands (AHI: 0.47, 0.51, 0.64)
rendered in one run (``bands.rgb_volume``: one band per channel, one path set), written as one CF NetCDF with
a ``band`` dimension, and made into an RGB picture by the recipe of the operational true-colour products.

The recipe (``true_color``), per pixel, in the order satpy's ``true_color`` composite applies it (satpy
``etc/composites/abi.yaml`` / ``ahi.yaml``: each band ``sunz_corrected`` then ``rayleigh_corrected``, ABI's
0.86 um band only ``sunz_corrected``; enhancement ``true_color_default``: ``cira_stretch``):

1. The imager's reflectance factor pi L / E0 (ABI L1b's kappa0 L, GOES-R PUG vol. 3 sec. 5.1.3.6.5; what satpy
   reads as ``toa_bidirectional_reflectance``): the render's pi L / (E0 cos theta0) times cos theta0 of the one
   sun that lit it.
2. Solar-zenith correction: divided by cos(SZA) at the pixel, capped at SZA 88 deg and falling off to zero at
   95 deg as satpy's ``sunzen_corr_cos`` (satpy/modifiers/angles.py, limit 88, max_sza 95).
3. Rayleigh correction, only where the render's atmosphere has molecules (``--rayleigh``, inside the domain):
   the molecular reflectance of the domain's air column over a black surface at the pixel's angles (DISORT, the
   role of pyspectral's LUT, pyspectral/rayleigh.py ``get_reflectance``), times the fraction of that column's
   optical depth that the pixel's line of sight crosses inside the domain's box (1 where it enters through the
   top and leaves through the floor; less where a slant line of sight enters or leaves through a side: the
   render has air only in the box, so the full column's reflectance over-subtracted there, a black frame
   around the domain), relaxed where the red band (0.64 um, sun-corrected, in percent) is bright:
   x (1 - (red - 20) / 80) above 20 %, clipped to 0-100 % (pyspectral's
   ``_relax_rayleigh_refl_correction_where_cloudy``), subtracted, the result clipped at zero.
4. ABI's simulated green (CIMSS; Bah, Schmit, Gunshor et al. 2018, "GOES-16 Advanced Baseline Imager (ABI)
   true color imagery", AMS/CIMSS; satpy abi.yaml ``green`` with fractions [0.45, 0.45, 0.1]):
   G = 0.45 R0.47 + 0.45 R0.64 + 0.10 R0.86. AHI's green is its 0.51 um band.
5. CIRA stretch (Miller et al. 2016, BAMS 97, 1803, CIRA's log stretch; satpy enhancements ``_cira_stretch``):
   v = (log10(R) - log10(0.0223)) / (0.75 (1 - log10(0.0223))) with R the reflectance factor (satpy's
   percent x 0.01), clipped to [0, 1] and written as 8-bit values without a further transfer function (satpy's
   image writers).

Molecules: their extinction goes as lambda^-4, and one render has one extinction for its three channels; with
``--rayleigh`` the bands are therefore rendered one at a time (three path sets), each with its own air and its
own checkpoint (``band_checkpoint``), so that an interrupted render resumes band by band.
"""
from __future__ import annotations

import numpy as np

from .bands import SEA_ALBEDO, true_color_bands

ABI_GREEN = {"0.47": 0.45, "0.64": 0.45, "0.86": 0.10}  # Bah et al. (2018), CIMSS; satpy abi.yaml ``green``
SUNZ_LIMIT_DEG, SUNZ_MAX_DEG = 88.0, 95.0  # satpy ``sunzen_corr_cos`` defaults
CIRA_ROOT = 0.0223  # satpy ``_cira_stretch``: log10(0.0223) maps to 0
CIRA_SCALE = 0.75  # ... and (1 - log10(0.0223)) * 0.75 is the denominator
RAYLEIGH_RELAX_PCT = (20.0, 80.0)  # pyspectral: 1 - (red - 20) / 80 above 20 % red reflectance


def sun_zenith_correction(refl, sza_deg, limit_deg: float = SUNZ_LIMIT_DEG, max_deg: float = SUNZ_MAX_DEG):
    """``refl`` / cos(SZA), capped at ``limit_deg`` and falling off to zero at ``max_deg`` (satpy's
    ``_sunzen_corr_cos_ndarray``: factor 1 - ln(1 + t) / ln 2, t the fraction of the way from limit to max)."""
    cos_zen = np.cos(np.radians(np.asarray(sza_deg, np.float64)))
    limit, top = np.radians(limit_deg), np.radians(max_deg)
    with np.errstate(invalid="ignore", divide="ignore"):
        fall = np.clip(1.0 - np.log((np.arccos(cos_zen) - limit) / (top - limit) + 1.0) / np.log(2.0), 0.0, None)
        corr = np.where(cos_zen > np.cos(limit), 1.0 / cos_zen, fall / np.cos(limit))
    return np.asarray(refl, np.float64) * np.where(np.isnan(cos_zen), 0.0, corr)


def relaxed_rayleigh(rayleigh_refl, red_refl):
    """The Rayleigh reflectance to subtract (reflectance factors, not percent): reduced where the sun-corrected
    red band is bright, as pyspectral does (module docstring), clipped to [0, 1]."""
    low, span = RAYLEIGH_RELAX_PCT
    red_pct = 100.0 * np.asarray(red_refl, np.float64)
    r = np.asarray(rayleigh_refl, np.float64)
    return np.clip(np.where(red_pct < low, r, (1.0 - (red_pct - low) / span) * r), 0.0, 1.0)


def cira_stretch(refl):
    """satpy's ``_cira_stretch`` of reflectance factors (0-1), clipped to [0, 1] as its image writers do."""
    root = np.log10(CIRA_ROOT)
    v = (np.log10(np.clip(np.asarray(refl, np.float64), np.finfo(float).eps, None)) - root) / ((1.0 - root) * CIRA_SCALE)
    return np.clip(v, 0.0, 1.0)


def simulated_green(r047, r064, r086):
    """ABI's simulated green, G = 0.45 R0.47 + 0.45 R0.64 + 0.10 R0.86 (Bah et al. 2018)."""
    return ABI_GREEN["0.47"] * r047 + ABI_GREEN["0.64"] * r064 + ABI_GREEN["0.86"] * r086


def corrected_bands(ds) -> dict:
    """Band name -> steps 1-3 of the recipe (module docstring) on ``ds`` (``rgb_dataset``): sun-corrected
    and, where the render has molecules, Rayleigh-corrected reflectance factors (the 0.86 um band never)."""
    cos0 = np.cos(np.radians(float(ds.attrs["rendered_solar_zenith_deg"])))
    sza = ds.solar_zenith_angle.values
    out = {str(b): sun_zenith_correction(ds.reflectance.sel(band=b).values * cos0, sza) for b in ds.band.values}
    if "rayleigh_reflectance" in ds:
        red = out["0.64"]
        for b in out:
            if b != "0.86":
                out[b] = np.maximum(out[b] - relaxed_rayleigh(
                    np.nan_to_num(ds.rayleigh_reflectance.sel(band=b).values), red), 0.0)
    return out


def true_color(ds) -> np.ndarray:
    """The (H, W, 3) true-colour picture in [0, 1] of a true-colour dataset (``rgb_dataset``)."""
    r = corrected_bands(ds)
    green = r["0.51"] if "0.51" in r else simulated_green(r["0.47"], r["0.64"], r["0.86"])
    return np.stack([cira_stretch(r["0.64"]), cira_stretch(green), cira_stretch(r["0.47"])], axis=-1)


def true_color8(ds) -> np.ndarray:
    """``true_color(ds)`` as 8-bit values (x 255, no transfer function: the stretch is the display's)."""
    return np.round(true_color(ds) * 255.0).astype(np.uint8)


def write_true_color_png(ds, path):
    """``true_color8(ds)`` as an 8-bit RGB PNG."""
    from ..io.image import write_png8
    return write_png8(path, true_color8(ds))


def true_color_scenes(hyd, vol, sat, resolution_km: float, *, rayleigh: bool = False, ground_albedo=None,
                      seed: int = 0, atmosphere=None, **surface_kw) -> list:
    """The ``SatelliteScene``(s) of a true-colour image: one with the three bands in its channels (with
    ``atmosphere``, each channel's air at its band's wavelength: ``satellite.air``), or, with ``rayleigh``, one
    per band with that band's air. ``ground_albedo`` None: the sea's ``SEA_ALBEDO`` per band
    (where the file has no ground); ``surface_kw``: ``satellite_scene``'s ``surface``, ``wind_m_s``. Raises the ValueErrors of ``satellite_scene`` (and a satellite without
    the bands) before anything is rendered."""
    from .geostationary import satellite
    from .imagery import satellite_scene
    sat = satellite(sat) if isinstance(sat, str) else sat
    bands = true_color_bands(sat)
    albedo = {b.name: (SEA_ALBEDO[b.name] if ground_albedo is None else float(ground_albedo)) for b in bands}
    if not rayleigh:
        return [satellite_scene(hyd, vol, sat, bands[0].name, resolution_km, rgb=True, seed=seed,
                                ground_albedo=tuple(albedo[b.name] for b in bands), atmosphere=atmosphere,
                                **surface_kw)]
    return [satellite_scene(hyd, vol, sat, b.name, resolution_km, rayleigh=True, ground_albedo=albedo[b.name],
                            seed=seed, **surface_kw) for b in bands]


def render_true_color(scenes, spp: int = 64, **reference_kw):
    """Render ``true_color_scenes`` (``render_reference`` with ``normalize="reflectance"``; the
    per-band renders of ``--rayleigh`` without checkpoints). Returns (``rgb_dataset``, Image with the bands in
    the channels red, green, blue)."""
    from ..reference.render import render_reference
    from .air import with_air_outside
    from .imagery import satellite_dataset
    if len(scenes) == 1:
        s = scenes[0]
        img = with_air_outside(s, render_reference(s.spec, s.vol, spp=spp, normalize="reflectance", **reference_kw))
        return rgb_dataset([_with_air_column(satellite_dataset(s, img, c), s, c) for c in range(3)]), img
    ckpt, resume = reference_kw.pop("checkpoint", None), reference_kw.pop("resume", None)
    imgs = []
    for s in scenes:  # a checkpoint per band: finished bands are read back, the unfinished one resumed
        own = None if ckpt is None else band_checkpoint(ckpt, s.band.name)
        imgs.append(render_reference(s.spec, s.vol, spp=spp, normalize="reflectance", checkpoint=own,
                                     resume=own if resume and own is not None and own.is_file() else None,
                                     **reference_kw))
    parts = [_with_rayleigh_column(satellite_dataset(s, im), s) for s, im in zip(scenes, imgs)]
    img = imgs[0]
    img.radiance = np.stack([np.asarray(im.radiance)[..., 0] for im in imgs], axis=-1)
    img.stderr = np.stack([np.asarray(im.stderr)[..., 0] for im in imgs], axis=-1)
    img.metadata["seconds"] = sum(float(im.metadata.get("seconds", 0.0)) for im in imgs)
    return rgb_dataset(parts), img


def band_checkpoint(ckpt, band_name: str):
    """The checkpoint of one band of a per-band (``--rayleigh``) true-colour render: OUT.exr.ckpt.npz ->
    OUT.exr.<band>.ckpt.npz."""
    from pathlib import Path
    ckpt = Path(ckpt)
    return ckpt.with_name(f"{ckpt.name.removesuffix('.ckpt.npz')}.{band_name}.ckpt.npz")


def band_checkpoints(ckpt) -> list:
    """``ckpt`` and every band's ``band_checkpoint`` of it (the files an unfinished render may leave)."""
    from .bands import BANDS
    return [ckpt] + [band_checkpoint(ckpt, name) for name in BANDS]


def column_path_fraction(vol, rays) -> np.ndarray:
    """(H, W) fraction of the domain's molecular column optical depth (its column-mean profile) that each
    pixel centre's line of sight crosses inside the box (``rays.box_segment``): the slant optical depth in
    the box over the full column's tau / mu (mu cancels): 1 through top and floor, 0 outside the box."""
    from .rays import box_segment
    k = list(vol.species).index("rayleigh")
    (_, _, z0), (_, _, z1) = vol.bbox
    profile = np.asarray(vol.beta_ext[k], np.float64).mean(axis=(1, 2))  # (nz,) 1/m, the column mean
    edges = np.linspace(z0, z1, profile.size + 1)
    cum = np.r_[0.0, np.cumsum(profile * np.diff(edges))]  # tau below each level edge
    t0, t1, o, d = box_segment(rays, vol.bbox)
    z_in, z_out = o[..., 2] + d[..., 2] * t0, o[..., 2] + d[..., 2] * np.maximum(t1, t0)
    tau_in = np.interp(z_in, edges, cum) - np.interp(z_out, edges, cum)
    return np.where(t0 <= t1, np.clip(tau_in / cum[-1], 0.0, 1.0), 0.0) if cum[-1] > 0 else np.zeros_like(t0)


def _with_air_column(ds, scene, channel: int):
    """``ds`` (channel ``channel`` of a true-colour render) with, where the scene has the clear atmosphere, the
    molecular reflectance of its whole column from the ground (``satellite.air.column_rayleigh_optical_depth``)
    over a black surface at every pixel's angles (``rayleigh_reflectance``): the air is everywhere, so every
    line of sight crosses all of it."""
    atm = scene.spec.atmosphere
    if atm is None:
        return ds
    from .air import column_rayleigh_optical_depth, ground_height_m
    tau = column_rayleigh_optical_depth(atm, scene.bands[channel].wavelength_m * 1e9, ground_height_m(scene))
    refl = rayleigh_reflectance(tau, ds.solar_zenith_angle.values, ds.sensor_zenith_angle.values,
                                ds.solar_azimuth_angle.values, ds.sensor_azimuth_angle.values)
    ds["rayleigh_reflectance"] = (("y", "x"), refl.astype(np.float32), {
        "long_name": "reflectance factor of the atmosphere's molecules alone (whole column) over a black "
                     "surface (DISORT), what the Rayleigh correction subtracts", "units": "1",
        "grid_mapping": "fixed_grid_projection"})
    ds.attrs["rayleigh_optical_depth"] = tau
    return ds


def _with_rayleigh_column(ds, scene):
    """``ds`` with the domain's molecular optical depth (column mean) and the molecular reflectance over a
    black surface at each in-domain pixel's angles (``rayleigh_reflectance``) times the fraction of the column
    its line of sight crosses in the box (``column_path_fraction``)."""
    vol = scene.vol
    k = list(vol.species).index("rayleigh")
    dz = (vol.bbox[1][2] - vol.bbox[0][2]) / vol.beta_total.shape[0]
    tau = float(np.asarray(vol.beta_ext[k], np.float64).sum(axis=0).mean() * dz)
    fraction = column_path_fraction(vol, scene.view.rays)
    refl = rayleigh_reflectance(tau, ds.solar_zenith_angle.values, ds.sensor_zenith_angle.values,
                                ds.solar_azimuth_angle.values, ds.sensor_azimuth_angle.values,
                                ds.in_domain.values == 1) * fraction
    ds["rayleigh_reflectance"] = (("y", "x"), refl.astype(np.float32), {
        "long_name": "reflectance factor of the domain's air alone over a black surface (DISORT), what the "
                     "Rayleigh correction subtracts: the column's times rayleigh_path_fraction", "units": "1",
        "grid_mapping": "fixed_grid_projection"})
    ds["rayleigh_path_fraction"] = (("y", "x"), fraction.astype(np.float32), {
        "long_name": "fraction of the domain's molecular column optical depth on the line of sight inside the "
                     "domain's box", "units": "1", "grid_mapping": "fixed_grid_projection"})
    ds.attrs["rayleigh_optical_depth"] = tau
    return ds


def rayleigh_reflectance(tau: float, sza, vza, saa, vaa, where=None, n_streams: int = 16,
                         nodes: int = 9) -> np.ndarray:
    """Reflectance factor pi I / (mu0 F0) of a conservative Rayleigh layer of optical depth ``tau`` over a black
    surface (DISORT; Chandrasekhar's phase function with depolarisation, Legendre moments 1, 0,
    (1 - gamma) / (10 (1 + 2 gamma))), at each pixel's solar and view zenith and azimuth (deg, the view
    azimuth towards the satellite); NaN outside ``where``.

    As pyspectral's look-up table: DISORT solved at ``nodes`` solar zeniths spanning the pixels' (one solve
    each, all its view zeniths and azimuths at once, on ``nodes`` x ``nodes`` spanning theirs), the pixels
    interpolated linearly in that (SZA, VZA, relative azimuth) table; not one solve per pixel."""
    from scipy.interpolate import RegularGridInterpolator
    from ..optics.rayleigh import DEPOLARISATION
    from ..optics.disort import solve
    gamma = DEPOLARISATION / (2.0 - DEPOLARISATION)
    moments = np.zeros((1, n_streams + 1))
    moments[0, 0], moments[0, 2] = 1.0, (1.0 - gamma) / (10.0 * (1.0 + 2.0 * gamma))
    sza, vza = np.asarray(sza, np.float64), np.asarray(vza, np.float64)
    phi = np.mod(np.asarray(vaa, np.float64) - np.asarray(saa, np.float64) - 180.0, 360.0)  # 0: forward
    out = np.full(sza.shape, np.nan)
    mask = (np.ones(sza.shape, bool) if where is None else np.asarray(where, bool)) & (sza < 90.0)
    if not mask.any():
        return out
    pts = np.stack([sza[mask], vza[mask], phi[mask]], axis=-1)
    axes = [np.linspace(lo, max(hi, lo + 1e-6), nodes) for lo, hi in zip(pts.min(axis=0), pts.max(axis=0))]
    mu0s, mus = np.cos(np.radians(axes[0])), np.cos(np.radians(axes[1]))
    table = np.empty((nodes, nodes, nodes))
    for i, mu0 in enumerate(mu0s):
        res = solve([tau], [1.0 - 1e-7], mu0, mus[::-1], [0.0], axes[2], moments=moments, n_streams=n_streams)
        table[i] = [[np.pi * res.intensities(nodes - 1 - m, 0, p) / mu0 for p in range(nodes)] for m in range(nodes)]
    out[mask] = RegularGridInterpolator(axes, table)(pts)
    return out


def rgb_dataset(parts):
    """One CF-1.8 dataset of the per-band datasets ``parts`` (``imagery.satellite_dataset``): reflectance and
    its standard error (and the Rayleigh reflectance where rendered) on a ``band`` dimension in order of
    wavelength, with each band's central wavelength (``wavelength``, um) and imager channel name."""
    import xarray as xr
    parts = sorted(parts, key=lambda d: float(d.attrs["band_wavelength_m"]))
    names = [str(d.attrs["band_um"]) for d in parts]
    per_band = [v for v in ("reflectance", "reflectance_standard_error", "rayleigh_reflectance") if v in parts[0]]
    ds = parts[0].drop_vars(per_band)
    for v in per_band:
        ds[v] = xr.concat([d[v] for d in parts], dim="band")
    wl_um = [float(d.attrs["band_wavelength_m"]) * 1e6 for d in parts]
    ds = ds.assign_coords(band=("band", names, {"long_name": "imager band (central wavelength, um)"}),
                          wavelength=("band", np.asarray(wl_um), {"standard_name": "radiation_wavelength",
                                                                  "units": "um", "long_name": "central wavelength"}))
    ds["reflectance"].attrs.update(long_name="bidirectional reflectance factor pi L / (E0 cos theta0) per band",
                                   wavelength=wl_um, coordinates="lat lon wavelength",
                                   channel=[str(d["reflectance"].attrs.get("channel", "")) for d in parts])
    if "rayleigh_reflectance" in ds:
        ds["rayleigh_optical_depth"] = ("band", np.asarray([d.attrs["rayleigh_optical_depth"] for d in parts]),
                                        {"long_name": "the molecular optical depth under the Rayleigh correction "
                                                      "(the domain's column mean; the whole column with the clear "
                                                      "atmosphere)", "units": "1"})
        ds.attrs.pop("rayleigh_optical_depth", None)
    ds.attrs.update(title=ds.attrs["title"].replace(f"{names[0]} um", "true-colour (" + ", ".join(names) + " um)"),
                    band_um=" ".join(names), band_wavelength_m=[w * 1e-6 for w in wl_um],
                    true_color_recipe="weather_mi.satellite.truecolor: sun-zenith (satpy), Rayleigh (pyspectral, "
                                      "where rendered), green (Bah et al. 2018 for ABI), CIRA stretch")
    return ds


__all__ = ["ABI_GREEN", "sun_zenith_correction", "relaxed_rayleigh", "cira_stretch", "simulated_green",
           "corrected_bands", "true_color", "true_color8", "write_true_color_png", "true_color_scenes", "render_true_color",
           "rayleigh_reflectance", "rgb_dataset", "band_checkpoint", "band_checkpoints", "column_path_fraction"]
