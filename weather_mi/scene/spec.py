"""The scene description shared by both renderers: camera (``scene.camera``: Camera, RayTable; importable from
here), sun, sky, ground, image size, seed.

Conventions (docs/design.md): world frame x east, y north, z up, metres. Directions are given by azimuth
(degrees clockwise from north) and elevation (degrees above the horizon). The sun is an irradiance
(W/m^2 per RGB channel) on a plane normal to its beam; images are radiance in the same units per sr.
Perspective field of view is horizontal (degrees).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from ..optics.air.atmosphere import Atmosphere
from .camera import Camera, RayTable, check_fov_deg, direction_from_angles  # noqa: F401 (importable from here)


def _positive_int(value, name: str, minimum: int = 1) -> int:
    """``value`` as an int >= minimum (integers of any type, or integral floats); ValueError otherwise."""
    ok = not isinstance(value, (bool, np.bool_)) and isinstance(value, (int, float, np.integer, np.floating)) \
        and math.isfinite(value) and float(value) == int(value) and int(value) >= minimum
    if not ok:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def _rgb(value, name: str) -> tuple[float, float, float]:
    arr = np.broadcast_to(np.asarray(value, dtype=np.float64), (3,))
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise ValueError(f"{name} must be a non-negative number or three numbers (RGB), got {value!r}")
    return tuple(float(v) for v in arr)


SUN_DIAMETER_DEG = 0.53      # the real sun's mean angular diameter
MAX_SUN_DIAMETER_DEG = 5.0


@dataclass(frozen=True)
class Sun:
    """The sun: a uniform disk of radiance irradiance / (pi sin^2(diameter / 2)), or with
    ``angular_diameter_deg=0`` a point (directional) sun.

    Parameters
    ----------
    azimuth : float, default 240.0
        Direction of the sun's centre, degrees clockwise from north.
    elevation : float, default 35.0
        Degrees above the horizon, 0 < elevation <= 90.
    irradiance : float or tuple of 3 float, default (1.0, 1.0, 1.0)
        Irradiance normal to the beam (W/m^2, RGB), >= 0.
    angular_diameter_deg : float, default SUN_DIAMETER_DEG (0.53)
        Angular diameter (degrees) in [0, MAX_SUN_DIAMETER_DEG (5)]; 0 for a point sun.

    Raises
    ------
    ValueError
        For a sun at or below the horizon, a negative irradiance or a diameter out of range.
    """

    azimuth: float = 240.0
    elevation: float = 35.0
    irradiance: tuple = (1.0, 1.0, 1.0)
    angular_diameter_deg: float = SUN_DIAMETER_DEG

    def __post_init__(self):
        if not 0.0 < float(self.elevation) <= 90.0:
            raise ValueError(f"Sun elevation must be above the horizon (0 < elevation <= 90 degrees), "
                             f"got {self.elevation}")
        object.__setattr__(self, "irradiance", _rgb(self.irradiance, "Sun irradiance"))
        d = self.angular_diameter_deg
        if isinstance(d, bool) or not isinstance(d, (int, float, np.integer, np.floating)) or not math.isfinite(d) \
                or not 0.0 <= float(d) <= MAX_SUN_DIAMETER_DEG:
            raise ValueError(f"Sun angular_diameter_deg must be a number in [0, {MAX_SUN_DIAMETER_DEG}] degrees "
                             f"(0: a point sun; the real sun: {SUN_DIAMETER_DEG}), got {d!r}")
        object.__setattr__(self, "angular_diameter_deg", float(d))

    @classmethod
    def at(cls, lat: float, lon: float, time, *, grid_north_deg: float = 0.0, **kw) -> Sun:
        """The sun seen from (``lat``, ``lon``) (degrees) at ``time`` (UTC; ``weather_mi.scene.solar``, NREL SPA).

        ``grid_north_deg``: azimuth of the scene's +y axis, degrees clockwise from true north (the map's
        meridian convergence, ``Georeference.grid_north_deg``); ``kw``: the other fields (irradiance,
        angular_diameter_deg). A ValueError where the sun is below the horizon there and then."""
        from .solar import solar_position
        p = solar_position(time, lat, lon)
        if not p.above_horizon:
            raise ValueError(f"at {time} the sun is {-p.elevation_deg:.2f} degrees below the horizon at "
                             f"latitude {lat:.3f}, longitude {lon:.3f}")
        return cls(azimuth=(p.azimuth_deg - grid_north_deg) % 360.0, elevation=p.elevation_deg, **kw)

    @property
    def to_sun(self) -> np.ndarray:
        """Unit vector pointing towards the sun (the light arrives along -to_sun)."""
        return direction_from_angles(self.azimuth, self.elevation)

    @property
    def mu0(self) -> float:
        """Cosine of the solar zenith angle."""
        return math.sin(math.radians(self.elevation))


@dataclass(frozen=True)
class Sky:
    """Diffuse skylight.

    Parameters
    ----------
    kind : {"sunsky", "constant", "air"}, default "sunsky"
        "sunsky": Hosek-Wilkie (Mitsuba's ``sunsky``), oriented by the Sun and scaled so that its sun
        would give this scene's sun irradiance; "constant": a uniform ``radiance``; "air": the scene's
        clear atmosphere's own sky (``--sky air``: its diffuse light into the box, ``kernel.air_sky``; the
        sky seen along the eye rays is composited after the render, ``display.aerial``).
    radiance : float or tuple of 3 float, default (0.05, 0.07, 0.1)
        The constant sky's radiance (W/m^2/sr, RGB), >= 0.
    turbidity : float, default 3.0
        Atmospheric turbidity of the sunsky model, in [1, 10].
    ground_albedo : float, default 0.3
        Ground albedo of the sunsky model (it brightens the sky near the horizon).

    Raises
    ------
    ValueError
        For an unknown kind, a negative radiance or a turbidity out of range.
    """

    kind: str = "sunsky"
    radiance: tuple = (0.05, 0.07, 0.1)
    turbidity: float = 3.0
    ground_albedo: float = 0.3

    def __post_init__(self):
        if self.kind not in ("sunsky", "constant", "air"):
            raise ValueError(f"Sky kind must be 'sunsky', 'constant' or 'air', got {self.kind!r}")
        object.__setattr__(self, "radiance", _rgb(self.radiance, "Sky radiance"))
        if not 1.0 <= float(self.turbidity) <= 10.0:
            raise ValueError(f"Sky turbidity must be in [1, 10], got {self.turbidity}")


def default_sky(atmosphere: str) -> str:
    """The sky's kind a scene takes when none is asked for (``render``'s ``--sky`` left to its default, the
    viewer's "auto"), by the atmosphere ("clear" or "none"): the air's own sky with the clear atmosphere
    (Hosek-Wilkie's sea-level sky would count the box's air twice), ``sunsky`` without it."""
    return "air" if atmosphere == "clear" else "sunsky"


@dataclass(frozen=True)
class Ground:
    """A flat Lambertian ground.

    Parameters
    ----------
    albedo : float or tuple of 3 float, default (0.15, 0.15, 0.15)
        RGB albedo in [0, 1].
    height : float, default 0.0
        Height of the ground in metres (above MSL).

    Raises
    ------
    ValueError
        For an albedo outside [0, 1].
    """

    albedo: tuple = (0.15, 0.15, 0.15)
    height: float = 0.0

    def __post_init__(self):
        alb = _rgb(self.albedo, "Ground albedo")
        if max(alb) > 1.0:
            raise ValueError(f"Ground albedo must be in [0, 1], got {self.albedo!r}")
        object.__setattr__(self, "albedo", alb)


@dataclass(frozen=True)
class SceneSpec:
    """Everything about a picture except the medium: drives both renderers identically.

    Parameters
    ----------
    camera : Camera
        The view.
    sun : Sun, default Sun()
        The sun.
    sky : Sky or None, default Sky()
        Diffuse skylight; None for none.
    ground : Ground or None, default Ground()
        The ground; None for none. The camera must be above it.
    width, height : int, default 300
        Image size in pixels, >= 1.
    seed : int, default 0
        Seed of the renderers' random numbers, >= 0.
    rays : RayTable or None, default None
        Every pixel's rays from a table (the reference renderer's ``raytable`` sensor; a satellite's
        view) instead of ``camera``'s projection; its film size must be (width, height). ``camera`` then
        only names a nominal view (metadata).
    atmosphere : optics.air.Atmosphere or None, default None
        The clear air around the model's box on the sun's path (the reference renderer colours its sun by
        it: ``optics.air.sunlight``); None: the sun as ``sun`` gives it, no air outside the box.

    Raises
    ------
    ValueError
        For an image size or seed that is not a valid integer, a camera inside the ground or a ray table
        of another size than the image.
    """

    camera: Camera
    sun: Sun = field(default_factory=Sun)
    sky: Sky | None = field(default_factory=Sky)
    ground: Ground | None = field(default_factory=Ground)
    width: int = 300
    height: int = 300
    seed: int = 0
    rays: RayTable | None = None
    atmosphere: Atmosphere | None = None

    def __post_init__(self):
        if self.atmosphere is not None and not isinstance(self.atmosphere, Atmosphere):
            raise ValueError(f"SceneSpec atmosphere must be an optics.air.Atmosphere or None, got {self.atmosphere!r}")
        if self.has_air_sky and self.atmosphere is None:
            raise ValueError("SceneSpec sky 'air' is the clear atmosphere's own sky: it needs an atmosphere")
        object.__setattr__(self, "width", _positive_int(self.width, "Image size (width, pixels)"))
        object.__setattr__(self, "height", _positive_int(self.height, "Image size (height, pixels)"))
        object.__setattr__(self, "seed", _positive_int(self.seed, "SceneSpec seed", minimum=0))
        if self.ground is not None and self.camera.origin[2] <= self.ground.height:
            raise ValueError(f"Camera at z = {self.camera.origin[2]:.1f} m is inside the ground "
                             f"(ground height {self.ground.height:.1f} m)")
        if self.rays is not None and self.rays.film_size != (self.width, self.height):
            raise ValueError(f"the ray table is for a {self.rays.film_size[0]} x {self.rays.film_size[1]} image, "
                             f"the scene is {self.width} x {self.height}")

    @property
    def has_air_sky(self) -> bool:
        """Whether the sky is the clear atmosphere's own (``Sky("air")``: ``kernel.air_sky``), not a sky model
        or none."""
        return self.sky is not None and self.sky.kind == "air"

    def to_dict(self) -> dict:
        """A JSON-serialisable description (for image metadata and checkpoints; a ray table as its digest,
        ``RayTable.to_dict``)."""
        d = asdict(replace(self, rays=None))
        del d["rays"]
        if self.atmosphere is None:  # absent: descriptions and fingerprints as before the atmosphere
            del d["atmosphere"]
        if self.rays is not None:  # absent otherwise: descriptions and fingerprints as before ray tables
            d["rays"] = self.rays.to_dict()
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "SceneSpec":
        if d.get("rays") is not None:
            raise ValueError("a scene description with a ray table keeps only its digest: rebuild the rays "
                             "(weather_mi.satellite.rays.satellite_view)")
        return cls(camera=Camera(**d["camera"]), sun=Sun(**d["sun"]),
                   sky=None if d.get("sky") is None else Sky(**d["sky"]),
                   ground=None if d.get("ground") is None else Ground(**d["ground"]),
                   width=d["width"], height=d["height"], seed=d["seed"],
                   atmosphere=None if d.get("atmosphere") is None else Atmosphere(**d["atmosphere"]))


def default_spec(vol, width: int = 300, height: int = 300, **kw) -> SceneSpec:
    """The demo view: camera to the south-south-west, low, sun in the south-west."""
    return SceneSpec(camera=Camera.orbit(vol, azimuth=kw.pop("camera_azimuth", 200.0),
                                         elevation=kw.pop("camera_elevation", 8.0),
                                         distance=kw.pop("distance", None), fov=kw.pop("fov", 45.0)),
                     width=width, height=height, **kw)


def ground_hits(spec: SceneSpec, origins: np.ndarray, dirs: np.ndarray):
    """Distance along each ray to the ground plane (inf where it does not hit)."""
    if spec.ground is None:
        return np.full(origins.shape[:-1], np.inf)
    dz = dirs[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (spec.ground.height - origins[..., 2]) / dz
    return np.where((dz < 0) & (t > 0), t, np.inf)
