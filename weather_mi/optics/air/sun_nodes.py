"""Tables over the sun's cosine: the nodes of cos(zenith) at which the air's diffuse light is solved (DISORT) and
the rule between them, shared by the slicer's multiple scattering along its eye rays (``slicing.air_multiple``)
and the ``--sky air`` skylight on a horizontal plane (``kernel.air_sky.sky_irradiance``)."""
from __future__ import annotations

import numpy as np

# the sun's cosines of the nodes (denser low: the diffuse light changes fastest near the horizon)
MU_NODES = np.array([0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.85, 1.0])


def between_nodes(mu0: float, at):
    """The value at the sun's cosine ``mu0`` of a quantity known at the nodes, ``at(node)`` (``node`` one of
    ``MU_NODES``, a float): linear in mu0 between the two nodes around it; under the lowest node the lowest
    node's value times mu0 / MU_NODES[0] (0 with the sun at or below the horizon)."""
    mu0 = float(mu0)
    if mu0 <= MU_NODES[0]:
        return at(float(MU_NODES[0])) * max(mu0, 0.0) / MU_NODES[0]
    k = int(np.clip(np.searchsorted(MU_NODES, mu0) - 1, 0, MU_NODES.size - 2))
    u = (mu0 - MU_NODES[k]) / (MU_NODES[k + 1] - MU_NODES[k])
    return (1.0 - u) * at(float(MU_NODES[k])) + u * at(float(MU_NODES[k + 1]))


__all__ = ["MU_NODES", "between_nodes"]
