"""Synthetic geostationary imagery: the imager's geometry (``geostationary``), its pixels' rays in a
domain (``rays``), its bands (``bands``), the path-traced product with its CF NetCDF (``imagery``), true
colour (``truecolor``) and its 1-D counterpart, each column solved by DISORT (``ipa``)."""
