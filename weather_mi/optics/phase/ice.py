"""Ice-crystal phase functions by geometric-optics Monte Carlo (after Wendling et al. 1979).

Particle: a hexagonal prism (side length a = circumradius of the hexagon, length L, aspect
L / (2 a); "column" 2.0, "plate" 0.2, "compact" 1.0), or a sphere (graupel), randomly oriented.
Random orientation is simulated by keeping the crystal fixed and drawing the incident direction d0 uniformly on the
sphere; each ray then carries the weight of the crystal's projected area P(d0) = sum_f A_f max(0,
-n_f . d0), so orientations count in proportion to their geometric cross-section.

Ray tracing (vectorised numpy, unpolarised, per channel refractive index n):
* entry face f drawn with probability A_f max(0, -n_f . d0) / P(d0), entry point uniform on it;
* at every interface, Fresnel reflectance of unpolarised light R = (r_s^2 + r_p^2) / 2 with
  r_s = (n1 cos_i - n2 cos_t) / (n1 cos_i + n2 cos_t), r_p = (n2 cos_i - n1 cos_t) / (n2 cos_i + n1 cos_t),
  Snell n1 sin_i = n2 sin_t, total internal reflection when n sin_i >= 1 (R = 1);
* the externally reflected part (weight R) and at each internal hit the transmitted part (weight
  1 - R) leave the crystal and are tallied by scattering angle theta = angle(d0, d_out); the
  internally reflected part (weight R) is traced on (deterministic splitting of the weight, no
  branching) for at most ``max_events`` internal hits or until its weight drops below 1e-4 of the
  start; internal absorption exp(-4 pi k / lambda * path) (negligible for visible ice);
* rays that leave exactly forward (through two parallel faces: theta < 1e-9 rad) are not a
  physical delta: their energy is added to the diffraction peak below.

Diffraction (Fraunhofer) carries as much energy as the geometric cross-section, i.e. half of the
extinction (Q_ext = 2). Choice: the Airy pattern of a circle of the crystal's orientation-averaged
projected area <P> = S / 4 (Cauchy; S = surface area), p_d ~ [2 J1(x sin theta) / (x sin theta)]^2
((1 + cos theta) / 2)^2 with x = 2 pi r / lambda, averaged over a gamma population of sizes
(v_eff = 0.1) so the Airy rings wash out as they do for real crystal populations. ``radius_m`` is
the effective radius r of that circle (default 30 um: WRF cloud-ice effective radii are 10-125 um).

Habit choices: Wendling et al. ray-traced columns and plates; aspects 2.0 and 0.2 put g inside
the published ranges (columns 0.77-0.83, plates 0.86-0.91; g rises with column length: aspect
1.5 / 2 / 3 / 4 give ~0.79 / 0.81 / 0.84 / 0.85 here, plates 0.1 / 0.15 / 0.3 give 0.92 / 0.89 / 0.84).

Roughness (for snow and graupel): every facet normal used for reflection and refraction is tilted
as m' = normalise(m + roughness * xi), xi a standard normal 3-vector (a Gaussian facet-slope
model like Macke et al. 1996 "distorted" crystals); where the tilt would send a ray through the
wrong side of the true face, the untilted normal is used.

Ice refractive index (Warren & Brandt 2008), n - i k: 650 nm 1.3080 / 1.4e-8, 550 nm 1.3110 /
2.3e-9, 450 nm 1.3157 / 9e-11.
"""
from __future__ import annotations

import numpy as np

from .cache import cached_table
from .table import RGB_WAVELENGTHS_M, PhaseTable, angle_grid

ICE_N = {650e-9: 1.3080, 550e-9: 1.3110, 450e-9: 1.3157}
ICE_K = {650e-9: 1.4e-8, 550e-9: 2.3e-9, 450e-9: 9e-11}

HABIT_ASPECT = {"column": 2.0, "plate": 0.2, "compact": 1.0, "sphere": 1.0}  # L / (2 a); sphere: unused
N_RAYS = {"test": 150_000, "default": 1_000_000, "high": 10_000_000}
_CHUNK = 100_000
_FORWARD_EPS = 1e-9  # rad: exactly-forward rays (through parallel faces)
_W_MIN = 1e-4        # stop tracing internal rays below this fraction of their start weight


def go_bin_edges_deg() -> np.ndarray:
    """Histogram bin edges (deg) for the ray tally: 0.25 deg up to 60 deg with 0.1 deg around the
    22 and 46 deg halos (20-24.5 and 44-48.5 deg), 1 deg from 60 to 180 deg (smooth region)."""
    return np.unique(np.round(np.concatenate([
        np.arange(0, 20, 0.25), np.arange(20, 24.5, 0.1), np.arange(24.5, 44, 0.25),
        np.arange(44, 48.5, 0.1), np.arange(48.5, 60, 0.25), np.arange(60, 180.5, 1.0)]), 8))


class HexPrism:
    """Hexagonal prism centred at the origin, c-axis along z: faces 0-5 prism faces (outward normals
    at 30 + 60 k deg, distance a sqrt(3)/2, area a L), 6 and 7 basal faces (+z, -z; distance L/2,
    area 3 sqrt(3)/2 a^2). Lengths in metres."""

    def __init__(self, a: float, length: float):
        self.a, self.length = float(a), float(length)
        phi = np.radians(30 + 60 * np.arange(6))
        self.normals = np.zeros((8, 3))
        self.normals[:6, 0], self.normals[:6, 1] = np.cos(phi), np.sin(phi)
        self.normals[6, 2], self.normals[7, 2] = 1.0, -1.0
        self.offsets = np.r_[np.full(6, a * np.sqrt(3) / 2), length / 2, length / 2]
        self.areas = np.r_[np.full(6, a * length), np.full(2, 1.5 * np.sqrt(3) * a * a)]
        ang = np.radians(60 * np.arange(7))
        self.vertices = a * np.stack([np.cos(ang), np.sin(ang)], axis=1)  # hexagon corners, closed

    @classmethod
    def with_area_radius(cls, radius_m: float, aspect: float) -> "HexPrism":
        """Prism of aspect L/(2a) whose mean projected area S/4 equals pi radius_m^2."""
        s1 = 3 * np.sqrt(3) + 6 * 2 * aspect  # surface area for a = 1, L = 2 aspect
        a = radius_m * np.sqrt(4 * np.pi / s1)
        return cls(a, 2 * aspect * a)

    @property
    def surface_area(self) -> float:
        return float(self.areas.sum())

    def sample_entry(self, d: np.ndarray, rng: np.random.Generator):
        """(outward normal of the entry face, entry point, projected area P(d)) for incident
        directions d (N, 3): face f with probability A_f max(0, -n_f . d) / P(d), point uniform."""
        proj = np.maximum(0.0, -(d @ self.normals.T)) * self.areas  # (N, 8)
        total = proj.sum(axis=1)
        cum = np.cumsum(proj, axis=1) / total[:, None]
        face = np.minimum((rng.random(d.shape[0])[:, None] > cum).sum(axis=1), 7)
        n = d.shape[0]
        u1, u2 = rng.random(n), rng.random(n)
        pts = np.empty((n, 3))
        side = face < 6
        k = face[side]
        v0, v1 = self.vertices[k], self.vertices[k + 1]
        pts[side, :2] = v0 + u1[side, None] * (v1 - v0)
        pts[side, 2] = (u2[side] - 0.5) * self.length
        b = ~side
        tri = rng.integers(0, 6, b.sum())
        sq = np.sqrt(u1[b])[:, None]
        r2 = u2[b][:, None]
        pts[b, :2] = sq * ((1 - r2) * self.vertices[tri] + r2 * self.vertices[tri + 1])
        pts[b, 2] = np.where(face[b] == 6, 0.5, -0.5) * self.length
        return self.normals[face], pts, total


    def exit(self, pos: np.ndarray, d: np.ndarray):
        """(path length to the exit face, its outward normal) for rays inside at ``pos`` going ``d``:
        the nearest plane among faces with d . n_f > 0 (convex body)."""
        dn = d @ self.normals.T  # (N, 8)
        dist = np.full_like(dn, np.inf)
        np.divide(self.offsets - pos @ self.normals.T, dn, out=dist, where=dn > 1e-12)
        face = dist.argmin(axis=1)
        return np.maximum(np.take_along_axis(dist, face[:, None], 1)[:, 0], 0.0), self.normals[face]


class Sphere:
    """Sphere of radius ``radius`` (m) centred at the origin: the quasi-spherical body used for
    graupel (with facet roughness standing in for the rime)."""

    def __init__(self, radius: float):
        self.radius = float(radius)

    @classmethod
    def with_area_radius(cls, radius_m: float, aspect: float = 1.0) -> "Sphere":
        return cls(radius_m)

    @property
    def surface_area(self) -> float:
        return 4 * np.pi * self.radius ** 2

    def sample_entry(self, d: np.ndarray, rng: np.random.Generator):
        """(outward normal at entry, entry point, projected area pi R^2) for directions d (N, 3):
        the ray's offset is uniform on the projected disk."""
        n = d.shape[0]
        # orthonormal basis (e1, e2) perpendicular to d
        helper = np.where(np.abs(d[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
        e1 = np.cross(d, helper)
        e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
        e2 = np.cross(d, e1)
        rho = self.radius * np.sqrt(rng.random(n))
        phi = 2 * np.pi * rng.random(n)
        off = rho[:, None] * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2)
        pts = off - np.sqrt(np.maximum(self.radius ** 2 - rho ** 2, 0.0))[:, None] * d
        return pts / self.radius, pts, np.full(n, np.pi * self.radius ** 2)

    def exit(self, pos: np.ndarray, d: np.ndarray):
        """Chord to the far side: |pos + t d| = R with |pos| = R gives t = -2 pos . d."""
        t = np.maximum(-2 * np.einsum("ij,ij->i", pos, d), 0.0)
        q = pos + t[:, None] * d
        return t, q / np.linalg.norm(q, axis=1, keepdims=True)


def _fresnel_unpolarised(n1, n2, cos_i, cos_t):
    """R = (r_s^2 + r_p^2) / 2."""
    rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)
    rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t)
    return 0.5 * (rs * rs + rp * rp)


def _tilt(m: np.ndarray, roughness: float, rng: np.random.Generator) -> np.ndarray:
    if roughness <= 0:
        return m
    t = m + roughness * rng.standard_normal(m.shape)
    return t / np.linalg.norm(t, axis=1, keepdims=True)


def _dot(a, b):
    return np.einsum("ij,ij->i", a, b)


def _angle(d0, d):
    """Scattering angle between unit vectors: arccos(d0 . d), and atan2(|d0 x d|, d0 . d) near
    forward and backward where arccos loses precision."""
    c = _dot(d0, d)
    th = np.arccos(np.clip(c, -1.0, 1.0))
    near = np.abs(c) > 0.99
    if near.any():
        th[near] = np.arctan2(np.linalg.norm(np.cross(d0[near], d[near]), axis=1), c[near])
    return th


def trace(body, n_ice: float, alpha_per_m: float, n_rays: int, rng: np.random.Generator,
          edges_rad: np.ndarray, roughness: float = 0.0, max_events: int = 16, progress=None):
    """Trace ``n_rays`` rays through randomly oriented ``body`` (a HexPrism or Sphere; refractive index ``n_ice``,
    absorption coefficient ``alpha_per_m`` = 4 pi k / lambda). Returns (hist, forward, geometric):
    energy per theta bin (``edges_rad``), energy leaving exactly forward, and the total projected
    area sum (the diffraction energy), all in the same units (projected area, m^2, summed).
    ``progress(n)`` is called after each chunk of n rays."""
    hist = np.zeros(edges_rad.size - 1)
    forward = 0.0
    geometric = 0.0
    nb = hist.size

    def tally(d0, d_out, w):
        nonlocal forward
        th = _angle(d0, d_out)
        fwd = th < _FORWARD_EPS
        forward += float(w[fwd].sum())
        idx = np.clip(np.searchsorted(edges_rad, th[~fwd], side="right") - 1, 0, nb - 1)
        hist[:] += np.bincount(idx, weights=w[~fwd], minlength=nb)

    done = 0
    while done < n_rays:
        n = min(_CHUNK, n_rays - done)
        done += n
        # incident direction uniform on the sphere (crystal fixed = random crystal orientation)
        z = 2 * rng.random(n) - 1
        ph = 2 * np.pi * rng.random(n)
        s = np.sqrt(1 - z * z)
        d0 = np.stack([s * np.cos(ph), s * np.sin(ph), z], axis=1)
        m_true, pos, proj = body.sample_entry(d0, rng)
        geometric += float(proj.sum())
        w_start = proj

        # ---- entry: external reflection (tallied) and refraction into the crystal
        m = _tilt(m_true, roughness, rng)
        cos_i = -_dot(d0, m)
        eta = 1.0 / n_ice
        sin2_t = eta * eta * np.maximum(0.0, 1 - cos_i * cos_i)
        cos_t = np.sqrt(np.maximum(0.0, 1 - sin2_t))
        refl = d0 + 2 * cos_i[:, None] * m
        refr = eta * d0 + (eta * cos_i - cos_t)[:, None] * m
        ok = True if roughness <= 0 else (cos_i > 0) & (_dot(refl, m_true) > 0) & (_dot(refr, m_true) < 0)
        if not np.all(ok):  # tilt not admissible: use the true facet normal
            bad = ~ok
            m[bad] = m_true[bad]
            cos_i[bad] = -_dot(d0[bad], m[bad])
            sin2_t[bad] = eta * eta * np.maximum(0.0, 1 - cos_i[bad] ** 2)
            cos_t[bad] = np.sqrt(np.maximum(0.0, 1 - sin2_t[bad]))
            refl[bad] = d0[bad] + 2 * cos_i[bad, None] * m[bad]
            refr[bad] = eta * d0[bad] + (eta * cos_i[bad] - cos_t[bad])[:, None] * m[bad]
        r_ext = _fresnel_unpolarised(1.0, n_ice, cos_i, cos_t)
        tally(d0, refl, w_start * r_ext)
        d = refr  # unit: Snell's construction preserves length (to rounding)
        w = w_start * (1 - r_ext)
        wmin = _W_MIN * w_start

        # ---- internal hits
        for _ in range(max_events):
            if d.shape[0] == 0:
                break
            ell, m_true = body.exit(pos, d)
            pos = pos + ell[:, None] * d
            w = w * np.exp(-alpha_per_m * ell)
            m = _tilt(m_true, roughness, rng)
            cos_i = _dot(d, m)
            sin2_t = n_ice * n_ice * np.maximum(0.0, 1 - cos_i * cos_i)
            cos_t = np.sqrt(np.maximum(0.0, 1 - sin2_t))
            refl = d - 2 * cos_i[:, None] * m
            out = n_ice * d - (n_ice * cos_i - cos_t)[:, None] * m
            tir = sin2_t >= 1.0
            ok = True if roughness <= 0 else (cos_i > 0) & (_dot(refl, m_true) < 0) & (tir | (_dot(out, m_true) > 0))
            if not np.all(ok):
                bad = ~ok
                m[bad] = m_true[bad]
                cos_i[bad] = _dot(d[bad], m[bad])
                sin2_t[bad] = n_ice * n_ice * np.maximum(0.0, 1 - cos_i[bad] ** 2)
                cos_t[bad] = np.sqrt(np.maximum(0.0, 1 - sin2_t[bad]))
                refl[bad] = d[bad] - 2 * cos_i[bad, None] * m[bad]
                out[bad] = n_ice * d[bad] - (n_ice * cos_i[bad] - cos_t[bad])[:, None] * m[bad]
                tir = sin2_t >= 1.0
            r_int = np.where(tir, 1.0, _fresnel_unpolarised(n_ice, 1.0, cos_i, cos_t))
            leave = ~tir
            if leave.any():
                tally(d0[leave], out[leave], w[leave] * (1 - r_int[leave]))
            w = w * r_int
            d = refl
            keep = w > wmin
            if not keep.all():
                d, pos, w, wmin, d0 = d[keep], pos[keep], w[keep], wmin[keep], d0[keep]
        if progress is not None:
            progress(n)
    return hist, forward, geometric


def airy_population(theta: np.ndarray, radius_m: float, wavelength_m: float, v_eff: float = 0.1,
                    n_sizes: int = 48) -> np.ndarray:
    """Fraunhofer diffraction by circles (1/sr, each member normalised to ~1 over 4 pi), averaged
    over an area-weighted gamma population of radii with effective radius ``radius_m``:
    p = x^2 / (4 pi) [2 J1(x sin theta) / (x sin theta)]^2 ((1 + cos theta) / 2)^2, x = 2 pi r / lambda."""
    from scipy.special import j1

    from .mie import gamma_area_quantile_radii
    radii = gamma_area_quantile_radii(radius_m, v_eff, n_sizes)
    st = np.sin(theta)
    obliq = (0.5 * (1 + np.cos(theta))) ** 2
    out = np.zeros_like(theta)
    for r in radii:
        x = 2 * np.pi * r / wavelength_m
        v = x * st
        with np.errstate(divide="ignore", invalid="ignore"):
            airy = np.where(v > 1e-8, 2 * j1(v) / v, 1.0 - v * v / 8)
        out += x * x / (4 * np.pi) * airy ** 2 * obliq
    return out / len(radii)


def _quality(quality: str) -> int:
    if quality not in N_RAYS:
        raise ValueError(f"quality must be one of {', '.join(map(repr, N_RAYS))}, got {quality!r}")
    return N_RAYS[quality]


def _trace_parts(habit, aspect, radius_m, roughness, n_rays, seed, max_events, theta_nodes):
    """Per channel (R, G, B): (geometric-optics density at ``theta_nodes`` (N,), diffraction energy, bookkeeping):
    the ray tally per sr and the energy that diffracts (the geometric cross-section plus the exactly forward rays)."""
    from tqdm.auto import tqdm
    edges = np.radians(go_bin_edges_deg())
    centres = 0.5 * (edges[1:] + edges[:-1])
    solid = 2 * np.pi * (np.cos(edges[:-1]) - np.cos(edges[1:]))  # sr per bin
    body = (Sphere if habit == "sphere" else HexPrism).with_area_radius(radius_m, aspect)
    parts = []
    with tqdm(total=3 * n_rays, desc=f"ice {habit}", unit="ray", unit_scale=True, leave=False,
              disable=n_rays < 500_000) as bar:
        for wl in RGB_WAVELENGTHS_M:
            rng = np.random.default_rng(seed)  # common random numbers across channels
            alpha = 4 * np.pi * ICE_K[wl] / wl  # absorption coefficient, 1/m
            hist, fwd, geo = trace(body, ICE_N[wl], alpha, n_rays, rng, edges, roughness, max_events,
                                   progress=bar.update)
            go_density = np.interp(theta_nodes, centres, hist / solid)  # ray energy per sr
            parts.append((go_density, geo + fwd, {"go_energy": float(hist.sum()), "forward": fwd, "geometric": geo}))
    return parts


def _compute(habit, aspect, radius_m, roughness, n_rays, seed, max_events, theta_nodes):
    """(values (N, 3) unnormalised, per-channel energy bookkeeping)."""
    parts = _trace_parts(habit, aspect, radius_m, roughness, n_rays, seed, max_events, theta_nodes)
    values = np.empty((theta_nodes.size, 3))
    info = {}
    for c, (wl, (go_density, energy, bookkeeping)) in enumerate(zip(RGB_WAVELENGTHS_M, parts)):
        diff = airy_population(theta_nodes, radius_m, wl)  # 1/sr, unit energy
        # diffraction energy = geometric cross-section (Q_ext = 2), plus the exactly forward rays
        values[:, c] = energy * diff + go_density
        info[wl] = bookkeeping
    return values, info


def band_values(parts, theta_nodes, radius_m: float, wavelength_m: float) -> np.ndarray:
    """(N,) unnormalised phase values at one wavelength from :func:`_trace_parts`'s R, G, B parts: the ray
    tally and the diffraction energy linear in wavelength between the channels (held beyond 450 and 650 nm:
    ice's index changes by 0.3% from 450 to 650 nm, which moves the halos by ~0.1 deg), the diffraction
    recomputed at the wavelength (its width ~ wavelength / radius)."""
    wl = np.array(RGB_WAVELENGTHS_M)[::-1]                       # ascending: 450, 550, 650 nm
    go = np.stack([p[0] for p in parts])[::-1]
    energy = np.array([p[1] for p in parts])[::-1]
    lam = float(np.clip(wavelength_m, wl[0], wl[-1]))
    j = int(np.clip(np.searchsorted(wl, lam) - 1, 0, 1))
    t = (lam - wl[j]) / (wl[j + 1] - wl[j])
    go_l = (1 - t) * go[j] + t * go[j + 1]
    e_l = (1 - t) * energy[j] + t * energy[j + 1]
    return e_l * airy_population(theta_nodes, radius_m, float(wavelength_m)) + go_l


_PARTS: dict = {}  # in-process memo of ray traces, so that a wavelength grid's band tables trace once


def _table_theta() -> np.ndarray:
    """The default angle grid plus the centres of the ray-tally bins (0.1 deg at the halos)."""
    e = go_bin_edges_deg()
    return np.unique(np.r_[angle_grid(), np.radians(0.5 * (e[1:] + e[:-1]))])


def ice_crystals(habit: str = "column", aspect: float | None = None, *, n_rays: int | None = None,
                 seed: int = 0, roughness: float = 0.0, radius_m: float = 30e-6, max_events: int = 16,
                 quality: str = "default", cache: bool = True, name: str | None = None,
                 wavelength_m: float | None = None) -> PhaseTable:
    """Randomly oriented ice particles by geometric optics + diffraction (see the module doc).

    habit : "column" (hexagonal prism, aspect L/(2a) = 2.0), "plate" (0.2), "compact" (1.0) or
        "sphere" (used for graupel); ``aspect`` overrides the prism aspect.
    n_rays : rays per channel (by ``quality``: "test" 150 000 (~5 s), "default" 1 000 000 (~30-40 s),
        "high" 10 000 000 (~6 min)).
    roughness : facet-normal tilt (standard deviation per component), 0 for pristine crystals.
    radius_m : effective radius (m) of the diffracting population (circle of equal mean projected
        area); it also sets the absorbing path length.
    wavelength_m : one wavelength's table in all three channels (the spectral mode's, :func:`band_values`), else R, G, B.
    Pristine columns show the 22 and 46 deg halos; g ~ 0.81 (columns), ~0.88 (plates)."""
    if habit not in HABIT_ASPECT:
        raise ValueError(f"habit must be one of {', '.join(map(repr, HABIT_ASPECT))}, got {habit!r}")
    aspect = HABIT_ASPECT[habit] if aspect is None else float(aspect)
    if not aspect > 0:
        raise ValueError(f"aspect must be > 0, got {aspect!r}")
    n = _quality(quality) if n_rays is None else int(n_rays)
    if n < 1000:
        raise ValueError(f"n_rays must be >= 1000, got {n}")
    if not roughness >= 0:
        raise ValueError(f"roughness must be >= 0, got {roughness!r}")
    if not radius_m > 0:
        raise ValueError(f"radius_m must be > 0, got {radius_m!r}")
    theta = _table_theta()
    params = {"habit": habit, "aspect": aspect, "n_rays": n, "seed": int(seed), "roughness": float(roughness),
              "radius_m": float(radius_m), "max_events": int(max_events), "theta": theta}
    label = name or (f"ice_crystals({habit!r}, aspect={aspect:g}, roughness={roughness:g}, "
                     f"radius_m={radius_m:g}, n_rays={n})")

    if wavelength_m is not None:
        return _band_table(params, theta, label, float(wavelength_m), cache)

    def compute():
        values, _ = _compute(habit, aspect, float(radius_m), float(roughness), n, int(seed), int(max_events), theta)
        return PhaseTable.from_values(theta, values, name=label)

    table = cached_table("ice_crystals", params, compute, use_cache=cache)
    return table if table.name == label else table.renamed(label)  # the label is not part of the key


def _band_table(params: dict, theta, label: str, wavelength_m: float, cache: bool) -> PhaseTable:
    """The table of ``ice_crystals(**params)`` at one wavelength in all three channels (:func:`band_values`),
    cached on disk per wavelength; the ray trace behind it is done once per process for every wavelength."""
    if not 300e-9 <= wavelength_m <= 1000e-9:
        raise ValueError(f"ice band tables span 300-1000 nm, got {wavelength_m * 1e9:.1f} nm")

    def compute():
        from .cache import cache_key
        key = cache_key("ice_parts", params)
        if key not in _PARTS:
            _PARTS[key] = _trace_parts(params["habit"], params["aspect"], params["radius_m"], params["roughness"],
                                       params["n_rays"], params["seed"], params["max_events"], theta)
        values = band_values(_PARTS[key], theta, params["radius_m"], wavelength_m)
        return PhaseTable.from_values(theta, values, name=f"{label}, {wavelength_m * 1e9:.1f} nm",
                                      wavelengths_m=(wavelength_m,) * 3)

    return cached_table("ice_crystals_band", {**params, "wavelength_m": wavelength_m}, compute, use_cache=cache)


SNOW_ROUGHNESS = 0.3
GRAUPEL_ROUGHNESS = 0.2


def snow(radius_m: float = 1e-3, *, quality: str = "default", cache: bool = True,
         wavelength_m: float | None = None) -> PhaseTable:
    """Snow: a stand-in for aggregates of many crystals, whose many tilted facets wash out the halos.
    Choice: a hexagonal column (aspect 2) with strongly roughened facets (roughness 0.3), diffraction
    by a 1 mm population. g ~ 0.79 (optics-notes: roughened ice and snow 0.75-0.80); no halos."""
    return ice_crystals("column", roughness=SNOW_ROUGHNESS, radius_m=radius_m, quality=quality, cache=cache,
                        wavelength_m=wavelength_m,
                        name=f"snow(radius_m={radius_m:g}): rough column, roughness {SNOW_ROUGHNESS}")


def graupel(radius_m: float = 1e-3, *, quality: str = "default", cache: bool = True,
            wavelength_m: float | None = None) -> PhaseTable:
    """Graupel: a quasi-spherical rimed particle. Choice: an ice sphere with roughened surface
    (roughness 0.2: the rime bumps remove the rainbows a smooth sphere would show), diffraction by
    a 1 mm population. g ~ 0.85 (optics-notes: graupel 0.8-0.9)."""
    return ice_crystals("sphere", roughness=GRAUPEL_ROUGHNESS, radius_m=radius_m, quality=quality, cache=cache,
                        wavelength_m=wavelength_m,
                        name=f"graupel(radius_m={radius_m:g}): rough ice sphere, roughness {GRAUPEL_ROUGHNESS}")


__all__ = ["ice_crystals", "snow", "graupel", "HexPrism", "Sphere", "trace", "airy_population", "ICE_N", "ICE_K",
           "HABIT_ASPECT", "go_bin_edges_deg"]
