"""Simulated turbulent detail (paper section 5.4): multiply the hydrometeor fields by fractal noise.

The paper adds "a more turbulent noise function" to smooth model output so that storm-scale
simulations show the small-scale structure an observer would see; the amount is user-adjustable.

Noise: spectral synthesis on the periodic lattice of the grid
-------------------------------------------------------------
A complex Gaussian white spectrum on the grid's real-FFT half space is shaped by a radial filter
``H(f)`` (``f`` = |frequency| in cycles per metre, from the grid spacing, so anisotropic grids get
isotropic noise in metres) and transformed back with one inverse real FFT (``scipy.fft``, float32).
``H`` is a sum of octaves: octave ``k`` is a log-normal shell centred on ``f_k = 2**k / base_wavelength_m``
(standard deviation half an octave), normalised so that, alone, it would have variance
``persistence**(2 k)``; this is Perlin's fractal sum (each octave twice the frequency and
``persistence`` times the amplitude of the previous) done in the Fourier domain. Because every
frequency is a lattice frequency, the field is exactly periodic: it tiles seamlessly across opposite
faces of the grid. The result is then normalised to zero mean and unit variance over the grid
(exactly, up to float32 rounding).

- ``persistence=0.5`` (default) is the classic Perlin fBm (amplitude ~ 1/f per octave, smooth);
  ``persistence=2**(-1/3)`` (about 0.794) gives octave amplitudes ~ f^(-1/3), the Kolmogorov /
  Obukhov-Corrsin -5/3 spectrum of a passive scalar in the inertial range.
- Octaves whose centre frequency is above the finest Nyquist frequency of the grid
  (``max over axes of 1 / (2 spacing)``) cannot be represented and are dropped; an octave larger
  than the domain collapses onto the lowest lattice frequencies.
- Mean preservation holds in expectation: where a species fills only a few noise wavelengths, its
  total water changes by the local mean of the multiplier (``exact_total=True`` rescales it back).
- Deterministic: the same shape, parameters and seed give bit-identical arrays.

Detail on Hydrometeors
----------------------
``add_detail`` multiplies each species' mixing ratio by ``exp(s n - s^2/2)`` (mean-preserving form:
for Gaussian ``n`` of unit variance the factor is log-normal with expectation 1, always > 0) or by
``max(0, 1 + s n)`` (linear form; its mean exceeds 1 once clipping starts, ``s`` >~ 0.5), ``s`` the
species' amplitude. By default all species share the same random phases (``correlated=True``): the
same eddies modulate cloud, ice and precipitation, as turbulence mixes them together; per-species
amplitudes and wavelengths still differ. The report gives the relative change of the total water
(sum over the grid of rho_air q dV, i.e. of the domain-mean water path) per species and overall.

``field`` returns a mean-one float32 multiplier of shape (z, y, x) to pass as ``detail_field=`` to the
half-angle slicer (``weather_mi.slicing.SliceRenderer``), which multiplies the extinction by it.
"""
from __future__ import annotations

import functools
import json
from collections.abc import Mapping, Sequence

import numpy as np
import scipy.fft
import xarray as xr

from ..io.hydrometeors import DIMS, SPECIES_NAMES, check_species_name, spacing_of, validate

__all__ = ["noise", "field", "add_detail", "total_water", "default_wavelength", "DEFAULT_AMPLITUDE"]

#: Default relative amplitude ``s`` per species (artistic defaults: the paper gives no numbers).
#: Cloud droplets and ice crystals follow the small eddies; snow less; rain and graupel fall through
#: the turbulence and keep smoother fields.
DEFAULT_AMPLITUDE: dict[str, float] = {"cloud": 0.8, "ice": 0.6, "snow": 0.5, "rain": 0.3, "graupel": 0.3}

_OCTAVE_WIDTH = 0.5  # standard deviation of each octave's shell, in octaves (log2 of frequency)


def default_wavelength(spacing_m: Sequence[float], octaves: int = 4) -> float:
    """Default base wavelength (m): ``2**octaves`` times the coarsest grid spacing, so that the finest
    octave (wavelength ``base / 2**(octaves-1)``) is two cells, the Nyquist limit, along every axis."""
    return float(2 ** int(octaves) * max(float(s) for s in spacing_m))


def _check_params(shape, spacing_m, base_wavelength_m, octaves, persistence):
    shape = tuple(int(n) for n in shape)
    if not shape or any(n < 1 for n in shape):
        raise ValueError(f"noise shape must be a tuple of positive sizes, got {shape}")
    spacing = tuple(float(s) for s in spacing_m)
    if len(spacing) != len(shape) or not all(np.isfinite(s) and s > 0 for s in spacing):
        raise ValueError(f"spacing_m must give one positive spacing (m) per axis of {shape}, got {spacing_m}")
    octaves = int(octaves)
    if octaves < 1:
        raise ValueError(f"octaves must be >= 1, got {octaves}")
    wavelength = default_wavelength(spacing, octaves) if base_wavelength_m is None else float(base_wavelength_m)
    if not (np.isfinite(wavelength) and wavelength > 0):
        raise ValueError(f"base_wavelength_m must be a positive length in metres, got {base_wavelength_m}")
    persistence = float(persistence)
    if not (np.isfinite(persistence) and persistence > 0):
        raise ValueError(f"persistence must be > 0, got {persistence}")
    return shape, spacing, wavelength, octaves, persistence


@functools.lru_cache(maxsize=8)
def _spectral_filter(shape: tuple, spacing: tuple, wavelength: float, octaves: int,
                     persistence: float) -> tuple[np.ndarray, int]:
    """The radial amplitude filter on the rfft half space (float32, read-only) and the octaves used."""
    freqs = [scipy.fft.fftfreq(n, d).astype(np.float32) for n, d in zip(shape[:-1], spacing[:-1])]
    freqs.append(scipy.fft.rfftfreq(shape[-1], spacing[-1]).astype(np.float32))
    half_shape = tuple(len(f) for f in freqs)
    rho2 = np.zeros(half_shape, np.float32)
    for axis, f in enumerate(freqs):
        view = [None] * len(shape)
        view[axis] = slice(None)
        rho2 += (f ** 2)[tuple(view)]
    with np.errstate(divide="ignore"):
        log_f = 0.5 * np.log2(rho2)              # -inf at the mean (DC), which gets weight 0
    # the rfft half space holds each frequency pair once, except the kx = 0 and Nyquist planes
    weight = np.full(half_shape[-1], 2.0, np.float32)
    weight[0] = 1.0
    if shape[-1] % 2 == 0 and shape[-1] > 1:
        weight[-1] = 1.0
    nyquist = max(0.5 / d for n, d in zip(shape, spacing) if n > 1) if any(n > 1 for n in shape) else 0.0
    total = np.zeros(half_shape, np.float32)
    used = 0
    inv_two_var = np.float32(1.0 / (2.0 * _OCTAVE_WIDTH ** 2))
    for k in range(octaves):
        f_k = 2.0 ** k / wavelength
        if f_k > nyquist:
            break
        g = log_f - np.float32(np.log2(f_k))
        np.square(g, out=g)
        g *= -inv_two_var
        np.exp(g, out=g)
        energy = float(np.dot((g ** 2).sum(axis=tuple(range(len(shape) - 1)), dtype=np.float64), weight))
        if not energy > 0:
            continue
        total += g * np.float32(persistence ** k / np.sqrt(energy))
        used += 1
    total.setflags(write=False)
    return total, used


def _white_spectrum(half_shape: tuple, seed) -> np.ndarray:
    rng = np.random.default_rng(seed)
    spec = np.empty(half_shape, np.complex64)
    parts = spec.view(np.float32).reshape(half_shape + (2,))
    rng.standard_normal(half_shape + (2,), dtype=np.float32, out=parts)
    return spec


def noise(shape: Sequence[int], spacing_m: Sequence[float] = (1.0, 1.0, 1.0), base_wavelength_m: float | None = None,
          octaves: int = 4, persistence: float = 0.5, seed=0) -> np.ndarray:
    """Tileable fractal noise on a grid: float32, zero mean and unit variance over the grid.

    Periodic along every axis: ``np.roll`` of the field is a seamless tile of it.

    Parameters
    ----------
    shape : sequence of int
        Grid shape, e.g. (nz, ny, nx) (any number of axes).
    spacing_m : sequence of float, default (1.0, 1.0, 1.0)
        Grid spacing per axis in metres (or in cells: (1, 1, 1)).
    base_wavelength_m : float, optional
        Wavelength (same unit as spacing) of the lowest, strongest octave, i.e. base frequency
        1 / base_wavelength_m; default :func:`default_wavelength`.
    octaves : int, default 4
        Number of octaves, each at twice the frequency of the previous.
    persistence : float, default 0.5
        Amplitude ratio of successive octaves.
    seed : int or tuple of int, default 0
        Anything ``numpy.random.default_rng`` accepts.

    Returns
    -------
    numpy.ndarray
        float32 array of ``shape``.

    Raises
    ------
    ValueError
        When no octave fits the grid (base wavelength below two cells, or a one-cell grid).
    """
    shape, spacing, wavelength, octaves, persistence = _check_params(shape, spacing_m, base_wavelength_m,
                                                                     octaves, persistence)
    filt, used = _spectral_filter(shape, spacing, wavelength, octaves, persistence)
    if used == 0:
        raise ValueError(f"no noise octave fits the grid {shape} with spacing {spacing}: base wavelength "
                         f"{wavelength:g} is below two cells (Nyquist) or the grid has one cell")
    spec = _white_spectrum(filt.shape, seed)
    spec *= filt
    out = scipy.fft.irfftn(spec, s=shape, axes=tuple(range(len(shape))), overwrite_x=True, workers=-1)
    out = np.asarray(out, dtype=np.float32)
    # the filter is zero at the mean frequency, so the mean is 0 up to rounding; remove it anyway
    mean = float(out.mean(dtype=np.float64))
    std = float(out.std(dtype=np.float64))
    if not std > 0:
        raise ValueError(f"noise on grid {shape} has no variance (grid too small for the requested scales)")
    out -= np.float32(mean)
    out *= np.float32(1.0 / std)
    return out


def _multiplier(n: np.ndarray, amplitude: float, mean_preserving: bool) -> np.ndarray:
    s = np.float32(amplitude)
    if mean_preserving:
        m = n * s
        m -= np.float32(0.5 * amplitude * amplitude)
        return np.exp(m, out=m)
    m = n * s
    m += np.float32(1.0)
    return np.maximum(m, np.float32(0.0), out=m)


def field(shape: Sequence[int], seed=0, amplitude: float = 0.5, *, spacing_m: Sequence[float] = (1.0, 1.0, 1.0),
          base_wavelength_m: float | None = None, octaves: int = 4, persistence: float = 0.5,
          mean_preserving: bool = True, exact_mean: bool = True) -> np.ndarray:
    """A mean-one float32 multiplier of shape ``shape`` (z, y, x), for the slicer's ``detail_field=``.

    ``exp(s n - s^2/2)`` (or ``max(0, 1 + s n)`` with ``mean_preserving=False``) of :func:`noise`.

    Parameters
    ----------
    shape : sequence of int
        (nz, ny, nx).
    seed : int or tuple of int, default 0
        Seed of the noise (:func:`noise`).
    amplitude : float, default 0.5
        The amplitude s >= 0 (0: all ones).
    spacing_m : sequence of float, default (1.0, 1.0, 1.0)
        Grid spacing (m); defaults to cells: pass ``hydrometeors.spacing_of(hyd)`` for noise isotropic
        in metres.
    base_wavelength_m, octaves, persistence
        As in :func:`noise`.
    mean_preserving : bool, default True
        ``exp(s n - s^2/2)`` (mean 1 in expectation) if True, else ``max(0, 1 + s n)``.
    exact_mean : bool, default True
        Divide by the grid mean, so that the mean extinction, and so the overall optical depth of a
        uniform volume, is unchanged exactly rather than in expectation.

    Returns
    -------
    numpy.ndarray
        float32 multiplier of ``shape``.

    Raises
    ------
    ValueError
        For a negative or non-finite amplitude, or noise that does not fit the grid.
    """
    amplitude = float(amplitude)
    if not (np.isfinite(amplitude) and amplitude >= 0):
        raise ValueError(f"amplitude must be >= 0, got {amplitude}")
    shape = tuple(int(n) for n in shape)
    if amplitude == 0:
        return np.ones(shape, np.float32)
    m = _multiplier(noise(shape, spacing_m, base_wavelength_m, octaves, persistence, seed), amplitude,
                    mean_preserving)
    if exact_mean:
        mean = m.mean(dtype=np.float64)
        if mean > 0:
            m *= np.float32(1.0 / mean)
    return m


def total_water(hyd: xr.Dataset) -> dict[str, float]:
    """Total mass (kg) of each species on the grid, sum of rho_air q dV (float64), and ``"total"``."""
    dv = float(np.prod(spacing_of(hyd)))
    rho = np.asarray(hyd["rho_air"].values, dtype=np.float32)
    out = {name: _mass(rho, np.asarray(hyd[f"q_{name}"].values)) * dv for name in SPECIES_NAMES}
    out["total"] = float(sum(out.values()))
    return out


def _mass(rho: np.ndarray, q: np.ndarray) -> float:
    """sum(rho q) (per unit cell volume): float32 products (exact to 1e-7), float64 pairwise sum."""
    return float(np.multiply(rho, q, dtype=np.float32).sum(dtype=np.float64))


def _per_species(value, default, what: str, allow_none: bool = False) -> dict:
    if isinstance(value, Mapping):
        for name in value:
            check_species_name(name, "add_detail", what)
        return {name: value.get(name, default) for name in SPECIES_NAMES}
    if value is None and not allow_none:
        raise ValueError(f"{what} must be a number or a mapping by species name")
    return {name: value for name in SPECIES_NAMES}


def add_detail(hyd: xr.Dataset, amplitude: float | Mapping[str, float] = DEFAULT_AMPLITUDE,
               base_wavelength_m: float | Mapping[str, float] | None = None, octaves: int = 4,
               persistence: float = 0.5, seed: int = 0, mean_preserving: bool = True, *,
               correlated: bool = True, exact_total: bool = False) -> tuple[xr.Dataset, dict[str, float]]:
    """Hydrometeors with simulated turbulent detail, and a report of the change of total water.

    Parameters
    ----------
    hyd : xarray.Dataset
        A Hydrometeors dataset (validated).
    amplitude : float or mapping of str to float, default DEFAULT_AMPLITUDE
        ``s`` for all species, or by species name (species not named: 0, unchanged).
    base_wavelength_m : float or mapping of str to float, optional
        Wavelength (m) of the lowest octave, one for all species or by species (species not named, or
        None: :func:`default_wavelength` of the grid).
    octaves, persistence, seed
        As in :func:`noise` (the noise is isotropic in metres on the grid).
    mean_preserving : bool, default True
        Multiply by ``exp(s n - s^2/2)`` (mean 1 in expectation) if True, else by ``max(0, 1 + s n)``.
    correlated : bool, default True
        All species use the same random phases (same eddies) if True; independent noise per species
        (seeds ``(seed, i)``) if False.
    exact_total : bool, default False
        Rescale each modified species so that its total water is unchanged exactly.

    Returns
    -------
    new_hyd : xarray.Dataset
        A new validated dataset (input untouched; attribute ``detail`` holds the settings as JSON).
    report : dict of str to float
        For each species and ``"total"``: the relative change (after - before) / before of the total
        water sum(rho_air q dV) (0.0 for an absent species).

    Raises
    ------
    ValueError
        For a negative or non-finite amplitude, or noise that does not fit the grid.
    WeatherDataError
        For invalid hydrometeors or an unknown species name.
    """
    validate(hyd)
    shape = tuple(int(hyd.sizes[d]) for d in DIMS)
    spacing = spacing_of(hyd)
    amps = {name: float(a) for name, a in _per_species(amplitude, 0.0, "amplitude").items()}
    for name, a in amps.items():
        if not (np.isfinite(a) and a >= 0):
            raise ValueError(f"amplitude for {name!r} must be a finite number >= 0, got {a}")
    default_wl = default_wavelength(spacing, octaves)
    wls = {name: default_wl if w is None else float(w)
           for name, w in _per_species(base_wavelength_m, None, "base_wavelength_m", allow_none=True).items()}

    before = total_water(hyd)
    out = hyd.copy(deep=False)
    cache: dict = {}
    for i, name in enumerate(SPECIES_NAMES):
        var = f"q_{name}"
        q = np.asarray(hyd[var].values)
        if amps[name] == 0 or not np.any(q > 0):
            continue
        key = (wls[name], None if correlated else i)
        if key not in cache:
            cache[key] = noise(shape, spacing, wls[name], octaves, persistence,
                               seed if correlated else (int(seed), i))
        m = _multiplier(cache[key], amps[name], mean_preserving)
        m *= q.astype(np.float32, copy=False)
        new = m
        if exact_total:
            after = _mass(np.asarray(hyd["rho_air"].values, dtype=np.float32), new) * float(np.prod(spacing))
            if after > 0:
                new *= np.float32(before[name] / after)
        out[var] = xr.DataArray(new, dims=DIMS, attrs=dict(hyd[var].attrs))

    settings = {"amplitude": amps, "base_wavelength_m": wls, "octaves": int(octaves),
                "persistence": float(persistence), "seed": int(seed), "mean_preserving": bool(mean_preserving),
                "correlated": bool(correlated), "exact_total": bool(exact_total),
                "method": "spectral synthesis (FFT), log-normal octave shells"}
    out.attrs = dict(hyd.attrs)
    out.attrs["detail"] = json.dumps(settings)
    validate(out)
    after = total_water(out)
    report = {k: ((after[k] - before[k]) / before[k] if before[k] > 0 else 0.0) for k in before}
    return out, report
