"""slicing.calibrate: the reverse-mode fit recovers a parameter that made its reference, and reports each
iteration's loss with the parameters it was measured at (on_step: a long fit stopped early, or one whose last
step overshot, keeps its iterates)."""
from __future__ import annotations

import numpy as np

import weather_mi as wm
from weather_mi.slicing import MODES, SliceParams, SliceRenderer
from weather_mi.slicing.calibrate import TrainingView, calibrate


def test_the_fit_recovers_the_gain_that_made_the_reference_and_logs_each_step():
    beta = np.full((8, 8, 8), 8.0 / 1000.0, np.float32)  # tau 8, 1 km thick, 40 km wide
    vol = wm.OpticalVolume.from_arrays(beta, 1.0, wm.phase.henyey_greenstein(0.85),
                                       ((-20e3, -20e3, 1000.0), (20e3, 20e3, 2000.0)))
    cam = wm.Camera.orthographic(center=(0.0, 0.0, 2500.0), direction=(0, 0, -1), width=2000.0, height=2000.0)
    spec = wm.SceneSpec(camera=cam, sun=wm.Sun(30.0, 40.0), sky=None, ground=None, width=8, height=6)
    truth = SliceParams(diffusion_gain=1.0)
    ref = SliceRenderer(vol, MODES["per-species/multiple"], slices=16, light_res=16).frame(spec, truth).radiance
    view = TrainingView(vol, spec, ref, np.ones(ref.shape[:2], bool))
    start = truth.updated(diffusion_gain=0.5)
    steps = []
    fitted, history = calibrate([view], start=start, names={"diffusion_gain": "positive"}, iterations=12,
                                learning_rate=0.1, slices=16, light_res=16,
                                on_step=lambda i, loss, p: steps.append((i, loss, p)))
    assert [s[0] for s in steps] == list(range(12)) and [s[1] for s in steps] == history
    assert abs(steps[0][2]["diffusion_gain"] - 0.5) < 1e-6  # step 0: measured at the start, before a step
    assert all(abs(p["diffusion_gain"] - 0.5) > 1e-3 for _, _, p in steps[1:])
    # Adam's momentum carries the last iterate past the truth (1.27 here); the best-loss iterate on_step
    # logged is at it (0.98, its loss 0.1% of the start's)
    best = min(steps, key=lambda s: s[1])
    assert best[1] < 0.01 * history[0] and abs(best[2]["diffusion_gain"] - 1.0) < 0.05, steps
    assert abs(fitted.diffusion_gain - 1.0) < abs(0.5 - 1.0)
