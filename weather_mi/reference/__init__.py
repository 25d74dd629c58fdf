"""The ground truth: ``render_reference`` (``render``) path-traces an OpticalVolume in passes (``passes``),
merges them with a standard error (``estimates``), checkpoints and resumes (``checkpoints``), and
spreads passes over Dask (``dask_passes``, ``cluster``, ``worker_probe``)."""
from .estimates import cloud_mask
from .render import render_reference, render_transmittance

__all__ = ["cloud_mask", "render_reference", "render_transmittance"]
