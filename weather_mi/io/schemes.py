"""WRF microphysics schemes (namelist ``mp_physics``, global attribute ``MP_PHYSICS``): their names and,
for the schemes whose output is well known, the hydrometeor mixing ratios they write to wrfout.

A file that lacks a variable its scheme writes is damaged or cut down (an error); a species a scheme
does not carry is simply zero (a warning). Schemes not in ``SCHEME_VARS`` get the warning only.
"""
from __future__ import annotations

MP_SCHEMES = {0: "none", 1: "Kessler", 2: "Purdue Lin", 3: "WSM3", 4: "WSM5", 5: "Ferrier (Eta)",
              6: "WSM6", 7: "Goddard", 8: "Thompson", 9: "Milbrandt-Yau", 10: "Morrison",
              11: "CAM 5.1", 13: "SBU-YLin", 14: "WDM5", 16: "WDM6", 17: "NSSL 2-moment",
              18: "NSSL 2-moment + CCN", 19: "NSSL 1-moment (7 class)", 21: "NSSL 1-moment (6 class)",
              22: "NSSL 2-moment (no hail)", 24: "WSM7", 26: "WDM7", 28: "Thompson aerosol-aware",
              30: "HUJI SBM fast", 32: "HUJI SBM full", 38: "Thompson hail-aware", 40: "Morrison+CESM aerosol",
              50: "P3 1-ice", 51: "P3 1-ice + nc", 52: "P3 2-ice", 53: "P3 1-ice 3-moment", 55: "Jensen ISHMAEL",
              56: "NTU"}

_ALL_FIVE = ("QCLOUD", "QRAIN", "QICE", "QSNOW", "QGRAUP")
SCHEME_VARS = {1: ("QCLOUD", "QRAIN"), 2: _ALL_FIVE, 3: ("QCLOUD", "QRAIN"), 4: ("QCLOUD", "QRAIN", "QICE", "QSNOW"),
               6: _ALL_FIVE, 7: _ALL_FIVE, 8: _ALL_FIVE, 10: _ALL_FIVE, 14: ("QCLOUD", "QRAIN", "QICE", "QSNOW"),
               9: _ALL_FIVE + ("QHAIL",), 16: _ALL_FIVE, 17: _ALL_FIVE, 18: _ALL_FIVE, 22: _ALL_FIVE, 24: _ALL_FIVE, 26: _ALL_FIVE, 28: _ALL_FIVE, 38: _ALL_FIVE,
               50: ("QCLOUD", "QRAIN", "QICE"), 51: ("QCLOUD", "QRAIN", "QICE"), 52: ("QCLOUD", "QRAIN", "QICE"),
               53: ("QCLOUD", "QRAIN", "QICE")}
