"""What an astronaut's eye would see from the satellite's position (``satellite --view natural``): the
top-of-atmosphere spectrum of every pixel as CIE XYZ and linear sRGB (D65).

The spectrum. The reflectance factor R(lambda) = pi L / (E0 mu0) is path-traced at ``NATURAL_NM`` (9
wavelengths, 400-700 nm, every 37.5 nm), three to a render (``imagery.satellite_scene`` with one wavelength per
channel: the hydrometeors' optics there, ``bands.rgb_volume``; the clear atmosphere's air in the box at each,
on the sun's path and outside the box, ``satellite.air``). The satellite's ``raytable`` sensor is not spectral
(``docs/spectral.md``), so the wavelengths are rendered as channels rather than sampled by ``llvm_ad_spectral``. R is linear in wavelength
between the nodes (the air's, the clouds' and the ground's reflectance are smooth over 37.5 nm) and held at its
end values outside them.

The colour. The radiance L = R E0 mu0 / pi under the ASTM G173-03 sun above the air (``optics.spectrum``):
    X = integral R(lambda) E0(lambda) xbar(lambda) dlambda / integral E0(lambda) ybar(lambda) dlambda   (Y, Z alike)
so a white Lambertian reflector lit by the sun above the air has Y = 1 and the sun's own chromaticity
((0.3234, 0.3327)); linear sRGB (D65) by colour-science without adaptation: a camera set to daylight.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

NATURAL_NM = tuple(float(w) for w in np.linspace(400.0, 700.0, 9))


def natural_bands(nodes_nm=NATURAL_NM) -> list:
    """The wavelengths ``nodes_nm`` (a multiple of 3) as ``bands.Band``s, in renders of three."""
    from .bands import Band
    if len(nodes_nm) % 3:
        raise ValueError(f"the natural view renders three wavelengths at a time: got {len(nodes_nm)}")
    bands = [Band(f"{w:.1f}nm", w * 1e-9, {}, {}) for w in nodes_nm]
    return [tuple(bands[i:i + 3]) for i in range(0, len(bands), 3)]


def sea_albedo(wavelength_nm) -> np.ndarray:
    """The sea's stand-in albedo (``bands.SEA_ALBEDO``) between its bands, linear in wavelength."""
    from .bands import BANDS, SEA_ALBEDO
    wl = [BANDS[k].wavelength_m * 1e9 for k in SEA_ALBEDO]
    return np.interp(wavelength_nm, wl, list(SEA_ALBEDO.values()))


def natural_scenes(hyd, vol, sat, resolution_km: float, *, atmosphere=None, ground_albedo=None, seed: int = 0,
                   nodes_nm=NATURAL_NM, **surface_kw) -> list:
    """The ``SatelliteScene``s of the natural view, three wavelengths each (``ground_albedo`` None: the sea's
    stand-in where the file has no ground; ``surface_kw``: ``satellite_scene``'s ``surface``, ``wind_m_s``)."""
    from .imagery import satellite_scene
    out = []
    for group in natural_bands(nodes_nm):
        albedo = tuple(float(sea_albedo(b.wavelength_m * 1e9)) if ground_albedo is None else float(ground_albedo)
                       for b in group)
        out.append(satellite_scene(hyd, vol, sat, resolution_km=resolution_km, seed=seed, ground_albedo=albedo,
                                   atmosphere=atmosphere, channel_bands=group, **surface_kw))
    return out


def xyz_weights(nodes_nm) -> np.ndarray:
    """(3, n) weights w such that XYZ = w @ R(nodes) (module docstring): the G173 sun times the CIE 1931
    functions on the 5 nm grid, R linear between the nodes, over the sun's luminance."""
    from ..optics import spectrum
    wl = spectrum.WAVELENGTHS_NM
    nodes = np.asarray(nodes_nm, np.float64)
    interp = np.stack([np.interp(wl, nodes, np.eye(nodes.size)[k]) for k in range(nodes.size)], axis=-1)  # hats
    sun = spectrum.solar_toa_w_m2_nm(wl)
    y_sun = float(spectrum.xyz(sun, wl)[1])
    return np.stack([spectrum.xyz(sun * interp[:, k], wl) for k in range(nodes.size)], axis=-1) / y_sun


def natural_colour(refl, se, nodes_nm):
    """(XYZ (H, W, 3), its standard error, linear sRGB (H, W, 3), its standard error) of the reflectance
    ``refl`` (H, W, n) at ``nodes_nm`` and its standard error (the nodes' errors taken as independent)."""
    from ..optics import spectrum
    w = xyz_weights(nodes_nm)
    xyz = np.asarray(refl, np.float64) @ w.T
    xyz_se = np.sqrt((np.asarray(se, np.float64) ** 2) @ (w.T ** 2))
    m = spectrum.linear_srgb(np.eye(3))                            # rows: the sRGB of X, Y, Z alone
    rgb = xyz @ m
    return xyz, xyz_se, rgb, np.sqrt((xyz_se ** 2) @ (m ** 2))


def render_natural(scenes, spp: int = 64, **reference_kw):
    """Render ``natural_scenes`` (``render_reference``, reflectance, ``satellite.air`` outside the box; a
    checkpoint per render as ``truecolor.band_checkpoint`` names it after its first wavelength). Returns
    (dataset: ``imagery.satellite_dataset``'s geometry and masks with ``X``, ``Y``, ``Z``, ``R``, ``G``, ``B`` and
    the ``spectral_reflectance`` on a ``wavelength`` dimension; Image with the linear sRGB)."""
    from ..reference.render import render_reference
    from .air import with_air_outside
    from .imagery import satellite_dataset
    from .truecolor import band_checkpoint
    ckpt, resume = reference_kw.pop("checkpoint", None), reference_kw.pop("resume", None)
    imgs = []
    for s in scenes:
        own = None if ckpt is None else band_checkpoint(ckpt, s.bands[0].name)
        img = render_reference(s.spec, s.vol, spp=spp, normalize="reflectance", checkpoint=own,
                               resume=own if resume and own is not None and own.is_file() else None, **reference_kw)
        imgs.append(with_air_outside(s, img))
    nodes = [b.wavelength_m * 1e9 for s in scenes for b in s.bands]
    refl = np.concatenate([np.asarray(im.radiance, np.float64) for im in imgs], axis=-1)
    se = np.concatenate([np.asarray(im.stderr, np.float64) for im in imgs], axis=-1)
    xyz, xyz_se, rgb, rgb_se = natural_colour(refl, se, nodes)
    ds = natural_dataset(satellite_dataset(scenes[0], imgs[0], 0), refl, xyz, xyz_se, rgb, nodes)
    img = replace(imgs[0], radiance=rgb.astype(np.float32), stderr=rgb_se.astype(np.float32),
                  metadata={**imgs[0].metadata, "seconds": sum(float(im.metadata.get("seconds", 0.0)) for im in imgs),
                            "view": "natural"})
    return ds, img


def natural_dataset(base, refl, xyz, xyz_se, rgb, nodes_nm):
    """``base`` (one channel's ``satellite_dataset``) with the natural view's variables in place of its
    reflectance."""
    dims = ("y", "x")
    gm = {"grid_mapping": "fixed_grid_projection", "coordinates": "lat lon"}
    ds = base.drop_vars(["reflectance", "reflectance_standard_error"])
    what = ("relative to a white Lambertian reflector lit by the sun above the air (ASTM G173-03, its Y = 1), "
            "CIE 1931 2 deg")
    for k, name in enumerate("XYZ"):
        ds[name] = (dims, xyz[..., k].astype(np.float32), {"long_name": f"CIE {name} {what}", "units": "1", **gm})
        ds[f"{name}_standard_error"] = (dims, xyz_se[..., k].astype(np.float32),
                                        {"long_name": f"standard error of {name} (Monte Carlo)", "units": "1", **gm})
    for k, name in enumerate("RGB"):
        ds[name] = (dims, rgb[..., k].astype(np.float32),
                    {"long_name": f"linear sRGB (D65, no adaptation) {name} of X, Y, Z", "units": "1", **gm})
    ds["spectral_reflectance"] = (("wavelength",) + dims, np.moveaxis(refl, -1, 0).astype(np.float32), {
        "long_name": "bidirectional reflectance factor pi L / (E0 cos theta0) at each wavelength", "units": "1", **gm})
    ds = ds.assign_coords(wavelength=("wavelength", np.asarray(nodes_nm), {"standard_name": "radiation_wavelength",
                                                                            "units": "nm"}))
    ds.attrs.update(title=f"weather-mi synthetic {ds.attrs['satellite']} natural colour", view="natural",
                    band_um="", band_wavelength_m=[w * 1e-9 for w in nodes_nm],
                    natural_colour="weather_mi.satellite.natural: reflectance at the wavelengths, G173 sun, CIE 1931 "
                                   "XYZ, linear sRGB (D65) through colour-science")
    return ds


def natural_checkpoints(ckpt) -> list:
    """The checkpoints ``render_natural`` keeps (one per render, ``truecolor.band_checkpoint``)."""
    from .truecolor import band_checkpoint
    return [band_checkpoint(ckpt, group[0].name) for group in natural_bands()]


__all__ = ["NATURAL_NM", "natural_bands", "sea_albedo", "natural_scenes", "xyz_weights", "natural_colour",
           "render_natural", "natural_dataset", "natural_checkpoints"]
