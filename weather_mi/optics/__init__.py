"""Optics of the hydrometeors (paper Eq. 1-8): the five species and their constants (``species``), the
OpticalVolume (``volume``: extinction, albedo, Eq. 8 weights), phase tables (``phase/``), forward peaks
(``forward_peak``), molecular scattering (``rayleigh``) and turbulent detail (``detail``)."""
