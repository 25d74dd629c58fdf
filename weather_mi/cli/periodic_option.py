"""The command line's ``--periodic [view|transport]`` / ``--no-periodic`` (``render``, ``animate``, ``satellite``,
``view``): the horizontal boundaries of the volume (:mod:`weather_mi.optics.periodic`)."""
from __future__ import annotations


def add_periodic_option(p) -> None:
    """``--periodic [view|transport]`` / ``--no-periodic``: the horizontal boundaries (optics/periodic.py)."""
    p.add_argument("--periodic", nargs="?", const="view", default=None, choices=("view", "transport"),
                   help="doubly periodic domain: light crosses the side walls into the periodic copies; 'view' "
                        "(alone: --periodic) the camera sees the copies too, 'transport' (the default for LES "
                        "inputs) the domain's own tile only")
    p.add_argument("--no-periodic", dest="periodic", action="store_const", const="off",
                   help="an isolated box (the default for WRF and the demos)")


def periodic_value(args):
    """``optical_volume``'s ``periodic`` from ``--periodic`` / ``--no-periodic`` (None: the data's default)."""
    return {None: None, "view": True, "transport": "transport", "off": False}[getattr(args, "periodic", None)]
