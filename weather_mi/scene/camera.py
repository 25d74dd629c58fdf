"""The view both renderers draw from: ``Camera`` (a pinhole or an orthographic camera, and the framings of a
volume: ``orbit``, ``ground_view``, ``orthographic``) and ``RayTable`` (every pixel's rays from a table: a
satellite's view). ``scene.spec``'s SceneSpec holds one of each (the table optional); both are importable from
there as before.

Conventions (docs/design.md): world frame x east, y north, z up, metres. Directions are given by azimuth
(degrees clockwise from north) and elevation (degrees above the horizon). Perspective field of view is
horizontal (degrees).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def direction_from_angles(azimuth_deg: float, elevation_deg: float) -> np.ndarray:
    """Unit vector towards (azimuth clockwise from north, elevation above horizon): (east, north, up)."""
    a, e = math.radians(azimuth_deg), math.radians(elevation_deg)
    return np.array([math.sin(a) * math.cos(e), math.cos(a) * math.cos(e), math.sin(e)])


def _finite(value, name: str) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return float(value)


def check_fov_deg(fov) -> float:
    """A perspective camera's horizontal field of view in degrees, 0 < fov < 180; ValueError otherwise."""
    if not 0.0 < _finite(fov, "Camera fov") < 180.0:
        raise ValueError(f"Camera fov must be in (0, 180) degrees, got {fov!r}")
    return float(fov)


@dataclass(frozen=True)
class Camera:
    """A pinhole camera (``origin`` looking at ``target``) or an orthographic one.

    Parameters
    ----------
    origin : tuple of 3 float
        Position (m, world frame: x east, y north, z up).
    target : tuple of 3 float
        A point the camera looks at (m), not the origin.
    up : tuple of 3 float, default (0.0, 0.0, 1.0)
        Up direction of the image, not parallel to the viewing direction.
    fov : float, default 45.0
        Horizontal field of view (degrees) of a perspective camera, 0 < fov < 180.
    kind : {"perspective", "orthographic"}, default "perspective"
        Pinhole or orthographic projection.
    ortho_width, ortho_height : float, default 0.0
        The orthographic film's size in metres (positive for ``kind="orthographic"``).

    Raises
    ------
    ValueError
        For non-finite positions, a target at the origin, an up vector along the view, an unknown kind,
        a field of view out of range or an orthographic film without a size.

    See Also
    --------
    Camera.orbit, Camera.ground_view, Camera.orthographic : cameras framing a volume.
    """

    origin: tuple
    target: tuple
    up: tuple = (0.0, 0.0, 1.0)
    fov: float = 45.0
    kind: str = "perspective"
    ortho_width: float = 0.0
    ortho_height: float = 0.0

    def __post_init__(self):
        o, t, u = (np.asarray(v, dtype=np.float64) for v in (self.origin, self.target, self.up))
        if o.shape != (3,) or t.shape != (3,) or u.shape != (3,) or not np.all(np.isfinite(np.r_[o, t, u])):
            raise ValueError("Camera origin, target and up must be three finite numbers each")
        fwd = t - o
        if np.linalg.norm(fwd) == 0:
            raise ValueError("Camera target must differ from its origin")
        if np.linalg.norm(np.cross(fwd, u)) < 1e-9 * np.linalg.norm(fwd) * np.linalg.norm(u):
            raise ValueError("Camera up vector must not be parallel to the viewing direction")
        if self.kind not in ("perspective", "orthographic"):
            raise ValueError(f"Camera kind must be 'perspective' or 'orthographic', got {self.kind!r}")
        if self.kind == "perspective":
            check_fov_deg(self.fov)
        if self.kind == "orthographic" and not (self.ortho_width > 0 and self.ortho_height > 0):
            raise ValueError("An orthographic camera needs a positive width and height in metres")
        for name, v in (("origin", o), ("target", t), ("up", u)):
            object.__setattr__(self, name, tuple(float(x) for x in v))

    @property
    def forward(self) -> np.ndarray:
        f = np.subtract(self.target, self.origin)
        return f / np.linalg.norm(f)

    @classmethod
    def orbit(cls, vol_or_bbox, azimuth: float = 200.0, elevation: float = 8.0, distance: float | None = None,
              fov: float = 45.0, target=None) -> "Camera":
        """A camera on a sphere around the volume.

        Given an OpticalVolume, it frames the cloud (the box of cells with extinction), else the box.

        Parameters
        ----------
        vol_or_bbox : OpticalVolume or tuple of 2 tuple of 3 float
            The volume, or a box ((x0, y0, z0), (x1, y1, z1)) in metres.
        azimuth : float, default 200.0
            Where the camera stands, degrees clockwise from north, seen from the target.
        elevation : float, default 8.0
            Degrees above the target, in [-90, 90].
        distance : float, optional
            From the target in metres (positive); default: the box fits the view.
        fov : float, default 45.0
            Horizontal field of view (degrees), 0 < fov < 180.
        target : tuple of 3 float, optional
            The point looked at (m); default the box centre.

        Returns
        -------
        Camera
            A perspective camera.

        Raises
        ------
        ValueError
            For a field of view, elevation or distance out of range.
        """
        fov = check_fov_deg(fov)
        azimuth, elevation = _finite(azimuth, "Camera.orbit azimuth"), _finite(elevation, "Camera.orbit elevation")
        if not -90.0 <= elevation <= 90.0:
            raise ValueError(f"Camera.orbit elevation must be in [-90, 90] degrees, got {elevation!r}")
        if distance is not None and not _finite(distance, "Camera.orbit distance") > 0:
            raise ValueError(f"Camera.orbit distance must be positive (m), got {distance!r}")
        (x0, y0, z0), (x1, y1, z1) = _occupied_bbox(vol_or_bbox)
        centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2]) if target is None else np.asarray(target, float)
        if distance is None:
            radius = 0.5 * math.dist((x0, y0, z0), (x1, y1, z1))
            distance = 1.05 * radius / math.sin(math.radians(fov) / 2)
        origin = centre + distance * direction_from_angles(azimuth, elevation)
        up = (0.0, 0.0, 1.0) if abs(elevation) < 89.9 else tuple(-direction_from_angles(azimuth, 0.0))
        return cls(tuple(origin), tuple(centre), up, fov)

    @classmethod
    def ground_view(cls, vol, distance_km: float = 40.0, height_m: float = 1500.0, azimuth: float = 200.0,
                    fov: float = 70.0, aspect: float = 4.0 / 3.0, ground_m: float = 0.0,
                    below_horizon_deg: float = 3.0) -> "Camera":
        """A photographer's view of a storm, looking towards the middle of the cloud's box with a level
        horizon.

        Parameters
        ----------
        vol : OpticalVolume or tuple of 2 tuple of 3 float
            The volume (its core is the column of largest optical depth), or a box
            ((x0, y0, z0), (x1, y1, z1)) in metres (its core is the box centre).
        distance_km : float, default 40.0
            Horizontal distance (km) from the storm's core, positive.
        height_m : float, default 1500.0
            Height of the camera above the ground (m), positive.
        azimuth : float, default 200.0
            Where the camera stands, degrees clockwise from north, seen from the core.
        fov : float, default 70.0
            Horizontal field of view (degrees), 0 < fov < 180; widened if the top of the cloud (or box)
            would not fit under the top of an image of this ``aspect``.
        aspect : float, default 4/3
            Width / height of the image, positive.
        ground_m : float, default 0.0
            Height of the ground (m).
        below_horizon_deg : float, default 3.0
            The horizon this many degrees above the bottom of the frame.

        Returns
        -------
        Camera
            A perspective camera.

        Raises
        ------
        ValueError
            For a non-positive distance, height or aspect, or a field of view out of range.
        """
        if not distance_km > 0 or not height_m > 0:
            raise ValueError(f"ground_view needs a positive distance and height, got {distance_km} km, {height_m} m")
        fov = check_fov_deg(fov)
        if not aspect > 0:
            raise ValueError(f"ground_view needs a positive aspect (width / height), got {aspect}")
        (x0, y0, z0), (x1, y1, z1) = _occupied_bbox(vol)
        core = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
        if hasattr(vol, "beta_total"):
            (bx0, by0, _), _ = _bbox(vol)
            dz, dy, dx = vol.spacing
            column = np.asarray(vol.beta_total, np.float64).sum(axis=0)
            j, i = np.unravel_index(int(np.argmax(column)), column.shape)
            core = np.array([bx0 + (i + 0.5) * dx, by0 + (j + 0.5) * dy])
        d = 1000.0 * float(distance_km)
        h = float(ground_m) + float(height_m)
        origin = np.r_[core + d * direction_from_angles(azimuth, 0.0)[:2], h]
        half_v = math.degrees(math.atan(math.tan(math.radians(fov) / 2) / aspect))
        top = math.degrees(math.atan2(z1 - h, d))  # elevation of the cloud top above the core
        if top + below_horizon_deg > 2 * half_v - 1.0:  # widen so that the top fits with 1 deg to spare
            half_v = min((top + below_horizon_deg + 1.0) / 2, 80.0)
            fov = 2 * math.degrees(math.atan(math.tan(math.radians(half_v)) * aspect))
            fov = min(fov, 170.0)
        pitch = half_v - below_horizon_deg
        # look towards the middle of the cloud (an anvil spreads downwind of the core)
        mid = np.array([(x0 + x1) / 2, (y0 + y1) / 2]) - origin[:2]
        heading = math.degrees(math.atan2(mid[0], mid[1])) if np.hypot(*mid) > 0 else (azimuth + 180.0) % 360.0
        look = direction_from_angles(heading, pitch)
        return cls(tuple(origin), tuple(origin + 1000.0 * look), (0.0, 0.0, 1.0), float(fov))

    @classmethod
    def orthographic(cls, center, direction=(0.0, 0.0, -1.0), width: float = 1.0, height: float = 1.0,
                     up=None) -> "Camera":
        """An orthographic camera looking along ``direction`` through ``center``.

        Parameters
        ----------
        center : tuple of 3 float
            A point on the view axis (m).
        direction : tuple of 3 float, default (0.0, 0.0, -1.0)
            Viewing direction (normalised here); the default looks straight down.
        width, height : float, default 1.0
            The film's size in metres.
        up : tuple of 3 float, optional
            Up direction of the image; default north when looking (nearly) straight down, else z up, so
            that looking straight down the top of the image is north.

        Returns
        -------
        Camera
            An orthographic camera.
        """
        c = np.asarray(center, dtype=np.float64)
        d = np.asarray(direction, dtype=np.float64)
        d = d / np.linalg.norm(d)
        if up is None:
            up = (0.0, 1.0, 0.0) if abs(d[2]) > 0.99 else (0.0, 0.0, 1.0)
        return cls(tuple(c), tuple(c + d), tuple(up), 0.0, "orthographic", float(width), float(height))


def _bbox(vol_or_bbox):
    bbox = getattr(vol_or_bbox, "bbox", vol_or_bbox)
    lo, hi = (tuple(float(v) for v in p) for p in bbox)
    return lo, hi


def _occupied_bbox(vol_or_bbox):
    """((x0, y0, z0), (x1, y1, z1)) m: a volume's occupied box (where its cloud is), or a box as given."""
    return _bbox(vol_or_bbox.occupied_bbox() if hasattr(vol_or_bbox, "occupied_bbox") else vol_or_bbox)


@dataclass(frozen=True, eq=False)
class RayTable:
    """Every pixel's rays from a table (a geostationary imager's view, ``weather_mi.satellite.rays``): a
    ray at every pixel corner, bilinear in between (the ``raytable`` sensor).

    Parameters
    ----------
    origins_m : array_like, shape (H + 1, W + 1, 3)
        Ray origins at the pixel corners (m, world frame; row 0 the film's top edge, column 0 its left).
    directions : array_like, shape (H + 1, W + 1, 3)
        Ray directions there (normalised here).

    Raises
    ------
    ValueError
        For tables of another shape, non-finite values or zero directions.
    """

    origins_m: np.ndarray
    directions: np.ndarray

    def __post_init__(self):
        o, d = (np.array(v, dtype=np.float64) for v in (self.origins_m, self.directions))
        if o.ndim != 3 or o.shape[2] != 3 or o.shape[0] < 2 or o.shape[1] < 2 or d.shape != o.shape:
            raise ValueError("RayTable origins_m and directions must both have shape (H + 1, W + 1, 3), got "
                             f"{o.shape} and {d.shape}")
        norm = np.linalg.norm(d, axis=-1, keepdims=True)
        if not (np.all(np.isfinite(o)) and np.all(np.isfinite(d)) and np.all(norm > 0)):
            raise ValueError("RayTable origins_m and directions must be finite, the directions non-zero")
        d = d / norm
        for name, v in (("origins_m", o), ("directions", d)):
            v.flags.writeable = False
            object.__setattr__(self, name, v)

    @property
    def film_size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return self.origins_m.shape[1] - 1, self.origins_m.shape[0] - 1

    def shifted(self, offset_m) -> "RayTable":
        """The same rays with their origins moved by ``offset_m`` (m)."""
        return RayTable(self.origins_m + np.asarray(offset_m, np.float64), self.directions)

    def to_dict(self) -> dict:
        """Shape and a SHA-256 digest of the table (for metadata and checkpoint fingerprints; a table of a
        million pixels is not written out)."""
        import hashlib
        h = hashlib.sha256(np.ascontiguousarray(self.origins_m).tobytes())
        h.update(np.ascontiguousarray(self.directions).tobytes())
        return {"kind": "raytable", "shape": list(self.origins_m.shape), "sha256": h.hexdigest()}


__all__ = ["Camera", "RayTable", "check_fov_deg", "direction_from_angles"]
