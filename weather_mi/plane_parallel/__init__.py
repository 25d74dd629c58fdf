"""One-dimensional radiative transfer, the independent check of the 3-D renderers: slabs measured with the path
tracer (``slab``) against DISORT as weather-mi sets it up (``optics.disort``)."""
