"""What comes in and goes out. In: the readers that turn model output into the Hydrometeors contract
(``hydrometeors``; ``wrf``, ``les``, ``series`` over ``wrfout``, ``times``, ``georef``, ``vertical``,
``schemes``, ``map_factors``), any input by one call (``sources``), the demo storms (``synthetic``,
``standard_atmosphere``), the input's map projection (``projection``) and ground (``terrain``). Out: the
Image of either renderer, EXR and PNG (``image``), files never half written (``output_paths``)."""
from .les import open_les
from .series import time_steps
from .wrf import open_wrf

__all__ = ["open_les", "open_wrf", "time_steps"]
