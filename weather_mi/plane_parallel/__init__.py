"""One-dimensional radiative transfer, the independent check of the 3-D renderers: DISORT as weather-mi
sets it up (``disort``) and slabs measured with the path tracer (``slab``)."""
