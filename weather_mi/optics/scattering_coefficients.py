"""Eq. 8's scattering coefficients of the species, beta_sca,s = w_s beta omega (1/m): the weights w_s times the
voxel's scattering coefficient, the channel-mean albedo times ``beta_total``. What the phase function
interpolates and then normalises (``kernel.medium``), with the box's air's components after them
(``optics.air.inside.medium_grids``)."""
from __future__ import annotations

import numpy as np

from .forward_peak import CHUNK, is_grey


def scattering_coefficients(beta_total, albedo, weights, out: list, start: int = 0, stop: int | None = None) -> None:
    """beta_sca,s = w_s x (channel-mean albedo x beta_total) of the voxels ``start:stop`` of the flattened grid
    (default: all) into ``out[s]`` ((stop - start,) float32 each, views), a chunk of voxels at a time: no
    grid-sized temporaries, and the weights of a ``forward_peak.ScaledWeights`` computed as read. ``beta_total``
    (z, y, x), ``albedo`` (z, y, x, 3; one channel seen three times, ``forward_peak.is_grey``, read as three:
    the same mean), ``weights`` (S, z, y, x), float32."""
    deferred = getattr(weights, "deferred", False)
    n_s = len(weights)
    w = None if deferred else np.asarray(weights, np.float32).reshape(n_s, -1)
    beta = np.asarray(beta_total, np.float32).reshape(-1)
    grey = is_grey(albedo)
    albedo = np.asarray(albedo, np.float32)
    albedo = albedo[..., 0].reshape(-1, 1) if grey else albedo.reshape(-1, albedo.shape[-1])
    stop = beta.size if stop is None else stop
    for first in range(start, stop, CHUNK):
        part = slice(first, min(first + CHUNK, stop))
        a = np.broadcast_to(albedo[part], (part.stop - first, 3)) if grey else albedo[part]
        sca = a.mean(axis=-1)
        sca *= beta[part]
        ws = weights.chunk(part) if deferred else w[:, part]
        for s in range(n_s):
            np.multiply(ws[s], sca, out=out[s][first - start:part.stop - start])


__all__ = ["scattering_coefficients"]
