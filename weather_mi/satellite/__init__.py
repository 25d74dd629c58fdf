"""Synthetic geostationary imagery: the imager's geometry (``geostationary``), its pixels' rays in a
domain (``rays``), its bands (``bands``) and the path-traced product with its CF NetCDF (``imagery``)."""
