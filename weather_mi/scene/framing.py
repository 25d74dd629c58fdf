"""Framing a storm: where a photographer stands by default, and the SceneSpec of the scene options of
``weather-mi render`` and ``animate`` (camera, sun, sky, ground, size, seed), for any front end that
offers the same options (the CLI, the viewer's first view).
"""
from __future__ import annotations

from .spec import Camera, Ground, SceneSpec, Sky, Sun

# the keyword arguments of ``scene_spec`` besides the volume and the size, as the CLI names its options
SCENE_OPTIONS = ("camera", "camera_azimuth", "camera_elevation", "distance", "camera_distance_km", "camera_height",
                 "fov", "sun_azimuth", "sun_elevation", "sun_diameter", "sky", "ground_albedo", "seed",
                 "atmosphere", "aod", "ozone", "water_vapour")


def default_ground_distance_km(vol) -> float:
    """How far a photographer stands from a storm: 0.55 x the cloud's horizontal extent, and at least
    1.2 x the height of its top (40 km for the demo supercell, 5.6 km for the demo cumulus).

    Parameters
    ----------
    vol : OpticalVolume or VolumeFrame
        Anything with ``occupied_bbox()`` (m).

    Returns
    -------
    float
        The horizontal distance (km).
    """
    (x0, y0, _), (x1, y1, z1) = vol.occupied_bbox()
    return max(0.55 * max(x1 - x0, y1 - y0), 1.2 * z1) / 1000.0


REGIONAL_DOMAIN_KM = 300.0  # wider domains get an aerial view by default (camera "auto")
AERIAL_ELEVATION_DEG = 50.0


def scene_spec(vol, size: tuple[int, int] = (320, 240), *, camera: str = "ground", camera_azimuth: float = 200.0,
               camera_elevation: float = 8.0, distance: float | None = None, camera_distance_km: float | None = None,
               camera_height: float = 1500.0, fov: float | None = None, sun_azimuth: float = 290.0,
               sun_elevation: float = 35.0, sun_diameter: float = 0.53, sky: str = "sunsky",
               ground_albedo: float = 0.15, seed: int = 0, atmosphere: str = "none", aod: float | None = None,
               ozone: float | None = None, water_vapour: float | None = None) -> SceneSpec:
    """The SceneSpec of the scene options for ``vol``.

    Parameters
    ----------
    vol : OpticalVolume
        The storm the camera is aimed at.
    size : (int, int)
        Width and height (pixels).
    camera : {"ground", "orbit", "auto"}
        A photographer near the ground (``Camera.ground_view``) or a camera on a sphere around the cloud
        (``Camera.orbit``); "auto": the ground camera for a storm-scale box, and for a domain wider than
        ``REGIONAL_DOMAIN_KM`` an aerial oblique (the orbit camera at ``AERIAL_ELEVATION_DEG``, fitting the
        box): from the ground a regional domain is sky and a strip of horizon, from a low orbit a smear
        (``weather-mi satellite`` is the view from space).
    camera_azimuth : float
        Where the camera stands, seen from the storm (degrees clockwise from north).
    camera_elevation, distance : float
        Orbit camera: elevation (degrees) and distance (m; None: fits the box).
    camera_distance_km, camera_height : float
        Ground camera: horizontal distance from the storm's core (km; None: ``default_ground_distance_km``)
        and height above the ground (m).
    fov : float, optional
        Horizontal field of view (degrees); None: 70 ground, 45 orbit.
    sun_azimuth, sun_elevation, sun_diameter : float
        The sun (degrees clockwise from north, degrees above the horizon, angular diameter in degrees; 0: a
        point sun).
    sky : {"sunsky", "constant", "none", "air"}
    ground_albedo : float
        Negative: no ground; else a ground at min(0, the volume's bottom).
    seed : int
        The path tracer's seed.
    atmosphere : {"none", "clear"}
        "clear": the sun coloured by a clear atmosphere on its path (``optics.air.Atmosphere``; the
        path tracer, and the slicer's sun per height) with aerosol optical depth ``aod`` at 550 nm, ozone column
        ``ozone`` (atm-cm) and precipitable water ``water_vapour`` (cm) (None: the Atmosphere's defaults, 0.1, 0.3
        and 1.4); "none": no air outside the box.

    Returns
    -------
    SceneSpec
    """
    width, height = size
    air = atmosphere_of(atmosphere, aod, ozone, water_vapour)
    if camera == "auto":
        (x0, y0, _), (x1, y1, _) = vol.bbox
        regional = max(x1 - x0, y1 - y0) > REGIONAL_DOMAIN_KM * 1e3
        camera = "orbit" if regional else "ground"
        if regional:
            camera_elevation = AERIAL_ELEVATION_DEG
    if sky == "air" and air is None:
        raise ValueError("--sky air is the clear atmosphere's own sky: give it with --atmosphere clear")
    sky_ = None if sky == "none" else Sky(sky)  # "air": its light into the box (kernel.air_sky), along eye rays display.aerial
    ground = None if ground_albedo < 0 else Ground(albedo=ground_albedo, height=min(0.0, vol.bbox[0][2]))
    if camera == "orbit":
        cam = Camera.orbit(vol, azimuth=camera_azimuth, elevation=camera_elevation, distance=distance,
                           fov=45.0 if fov is None else fov)
    else:
        terrain = getattr(vol, "terrain", None)  # a photographer above the highest terrain, not inside it
        ground_m = 0.0 if ground is None else ground.height if terrain is None else float(terrain.height_m.max())
        cam = Camera.ground_view(vol, azimuth=camera_azimuth, fov=70.0 if fov is None else fov, aspect=width / height,
                                 distance_km=camera_distance_km or default_ground_distance_km(vol),
                                 height_m=camera_height, ground_m=ground_m)
    return SceneSpec(camera=cam, sun=Sun(sun_azimuth, sun_elevation, angular_diameter_deg=sun_diameter),
                     sky=sky_, ground=ground, width=width, height=height, seed=seed, atmosphere=air)


def atmosphere_of(kind: str, aod: float | None, ozone: float | None, water_vapour: float | None = None):
    """The Atmosphere of the options ``--atmosphere``, ``--aod``, ``--ozone``, ``--water-vapour`` (ValueError naming
    them)."""
    from ..optics.air import Atmosphere
    if kind not in ("none", "clear"):
        raise ValueError(f"--atmosphere must be 'none' or 'clear', got {kind!r}")
    if kind == "none":
        given = [name for name, v in (("--aod", aod), ("--ozone", ozone), ("--water-vapour", water_vapour))
                 if v is not None]
        if given:
            raise ValueError(f"{' and '.join(given)} describe the air: give them with --atmosphere clear")
        return None
    kw = {k: v for k, v in (("aod_550", aod), ("ozone_atm_cm", ozone), ("water_vapour_cm", water_vapour))
          if v is not None}
    return Atmosphere(**kw)


def largest(volumes):
    """The volume whose cloud's box (``occupied_bbox``) is the largest: the one to frame a series by."""
    import numpy as np
    return max(volumes, key=lambda v: np.prod(np.subtract(*v.occupied_bbox()[::-1])))
