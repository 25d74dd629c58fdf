"""The viewer in a Jupyter notebook: ``view(source)`` (``weather_mi.view``) builds the storm and the first
view (``serve.prepare``) and returns a ``Viewer``, a Panel object that displays one ViewerSession
(``session.py``) without a server.
"""
from __future__ import annotations

import panel as pn

from ..io.sources import DEMOS
from .serve import prepare
from .session import ViewerSession, default_distance_km  # noqa: F401  (the viewer's entry points)
from .state import ViewState


class Viewer(pn.viewable.Viewer):
    """The viewer in a notebook: displays as the app; ``close()`` stops its render thread and reference."""

    def __init__(self, session: ViewerSession, **params):
        super().__init__(**params)
        self.session = session

    def __panel__(self):
        return self.session.layout

    def close(self) -> None:
        self.session.close()


def view(source, *, state: ViewState | None = None, time=None, size: tuple[int, int] = (320, 240),
         **recipe_kw) -> Viewer:
    """The viewer for a Jupyter notebook (run ``pn.extension()`` first): ``source`` is a Hydrometeors
    Dataset, a file path, a demo name ("supercell", "cumulus") or a VolumeRecipe; ``time``: the WRF
    time to start at; ``recipe_kw``: preset=, phase=."""
    import xarray as xr
    from .recipe import VolumeRecipe
    if isinstance(source, VolumeRecipe):
        recipe = source
    elif isinstance(source, xr.Dataset):
        recipe = VolumeRecipe(dataset=source, **recipe_kw)
    elif str(source) in DEMOS:
        recipe = VolumeRecipe(demo=str(source), **recipe_kw)
    else:
        recipe = VolumeRecipe(path=str(source), **recipe_kw)
    storm, first = prepare(recipe, time, progress=lambda *a: None, size=size, warm=False)
    return Viewer(ViewerSession(storm, state or first))
