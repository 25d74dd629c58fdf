"""``VolumeRecipe``: where the viewer's storm comes from (a file or a demo, its times, the species table
and phase mode), small and picklable, so that a background process (the reference render) can build
the same OpticalVolume as the viewer without receiving hundreds of megabytes of arrays."""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Mapping

from ..io import sources


@dataclass(frozen=True)
class VolumeRecipe:
    """path: a wrfout NetCDF or LES text file (None: the demo); demo: "supercell" or "cumulus";
    time: the WRF time (index or timestamp; None: the last); preset: species table ("physical" or
    "paper"); phase: "per_species" or "paper"; sizes: "scheme", "physical", "paper" or None (the scheme's
    where known, ``optical_volume``); dataset: a Hydrometeors Dataset in memory (a notebook's
    ``wm.view(hyd)``; it travels to a reference process by pickling); periodic: the horizontal boundaries
    (``optical_volume``'s; None: the data's default, periodic for LES)."""

    path: str | None = None
    demo: str | None = None
    time: int | str | None = None
    preset: str = "physical"
    phase: str = "per_species"
    sizes: str | None = None
    dataset: object = field(default=None, compare=False, repr=False)
    periodic: bool | str | None = None

    @property
    def label(self) -> str:
        if self.dataset is not None:
            return str(self.dataset.attrs.get("source", "Hydrometeors in memory"))
        return f"demo {self.demo or 'supercell'}" if self.path is None else Path(self.path).name

    def at(self, time) -> "VolumeRecipe":
        return replace(self, time=time)

    def hydrometeors(self):
        """The Hydrometeors Dataset (mixing ratios in kg/kg on a regular grid in metres). A time index of a
        WRF file with several times: that time of ``series()``, on the grid the viewer shows."""
        if self.dataset is not None:
            return self.dataset
        if isinstance(self.time, int) and self._wrf() and len(self.times()) > 1:
            return self.series()[self.time]
        return sources.open_source(self.path, self.demo, self.time, sizes=self.sizes not in ("physical", "paper"))

    def series(self) -> list:
        """Every time of a WRF file as Hydrometeors on one height grid (``io.open_wrf(time="all")``, the
        reader of ``weather-mi animate``), so that the storm's times and their references share a grid."""
        if not self._wrf():
            return [self.hydrometeors()]
        return sources.open_times(self.path, time="all", sizes=self.sizes not in ("physical", "paper"))

    def _wrf(self) -> bool:
        return sources.kind(self.path, self.demo, self.dataset) == "wrf"

    def volume(self, scale: Mapping[str, float] | None = None, hyd=None, keep: tuple = ("beta_ext", "weights"),
               release: tuple = ()):
        """The OpticalVolume (Eq. 1-6, 8) of the (scaled) storm; ``hyd``: its Hydrometeors if already read;
        ``keep``: its per-species grids (``optical_volume``: the slicer reads no weights); ``release``: the kinds
        of field ("q", "r_eff") dropped from ``hyd`` once used (``optical_volume``)."""
        from ..optics.volume import default_sizes, optical_volume
        hyd = self.hydrometeors() if hyd is None else hyd
        return optical_volume(hyd, species=self.preset, scale=dict(scale or {}) or None, phase=self.phase,
                              sizes=self.sizes or default_sizes(hyd),
                              periodic=self.periodic, keep=keep, release=release)

    def times(self) -> list[str]:
        """The labels of the input's times (one for a demo or an LES file; every time of a WRF file)."""
        return sources.time_labels(self.path, self.demo, self.dataset) or [self.label]
