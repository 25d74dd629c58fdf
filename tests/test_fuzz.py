"""Property-based test (Hypothesis) over the user-facing arguments: ``from_arrays``, ``optical_volume``,
``Camera.orbit``, ``Sun``, ``SceneSpec``. Every input either raises WeatherDataError or ValueError before
rendering, or renders a finite image with both renderers at a tiny size: never another exception, never
NaN. Few examples (the renders dominate the time); Hypothesis keeps the failures it finds in its database."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import weather_mi as wm

SPECIES = ("cloud", "ice", "rain", "snow", "graupel")


def with_one_bad(valid: st.SearchStrategy, bad: dict) -> st.SearchStrategy:
    """A valid argument dict with one entry replaced by one of its bad values (``bad``: key -> values)."""
    pairs = [(k, v) for k, values in bad.items() for v in values]
    return st.tuples(valid, st.sampled_from(pairs)).map(lambda t: {**t[0], t[1][0]: t[1][1]})


@st.composite
def hydrometeor_fields(draw):
    shape = draw(st.tuples(st.integers(1, 3), st.integers(1, 3), st.integers(1, 3)))
    names = draw(st.lists(st.sampled_from(SPECIES), min_size=1, max_size=3, unique=True))
    return {"q": {n: draw(hnp.arrays(np.float64, shape, elements=st.floats(0.0, 3e-3))) for n in names},
            "rho_air": draw(st.floats(0.3, 1.3)),
            "spacing": draw(st.tuples(st.floats(50.0, 2000.0), st.floats(50.0, 2000.0), st.floats(50.0, 2000.0)))}


def _spoilt_q(q: dict, value) -> dict:
    name = next(iter(q))
    a = q[name].copy()
    a.flat[0] = value
    return {**q, name: a}


hyd_valid = hydrometeor_fields()
hyd_bad = st.one_of(
    st.tuples(hyd_valid, st.sampled_from([np.nan, np.inf, -np.inf, -1e-6, 1e30])).map(
        lambda t: {**t[0], "q": _spoilt_q(t[0]["q"], t[1])}),
    with_one_bad(hyd_valid, {"q": [{}, {"hail": np.zeros((1, 1, 1))}, {"cloud": np.zeros((2, 2))}],
                             "rho_air": [0.0, -1.0, np.nan, np.ones(7)],
                             "spacing": [(0.0, 1.0, 1.0), (-5.0, 1.0, 1.0), (np.nan, 1.0, 1.0), (1.0, 1.0)]}))
optics_valid = st.fixed_dictionaries({
    "species": st.sampled_from(["paper", "physical"]),
    "scale": st.one_of(st.none(), st.dictionaries(st.sampled_from(SPECIES), st.floats(0.0, 5.0), max_size=2)),
    "phase": st.sampled_from(["per_species", "paper"])})
optics_bad = with_one_bad(optics_valid, {"species": ["bogus"], "phase": ["none"],
                                         "scale": [{"hail": 2.0}, {"ice": -1.0}, {"ice": np.nan}, {"ice": np.inf}]})
camera_valid = st.fixed_dictionaries({
    "azimuth": st.floats(-720.0, 720.0),
    "elevation": st.one_of(st.floats(-90.0, 90.0), st.sampled_from([89.9, 90.0, -90.0])),
    "distance": st.one_of(st.none(), st.floats(10.0, 1e5)),
    "fov": st.one_of(st.floats(1.0, 170.0), st.sampled_from([1e-3, 179.9]))})
camera_bad = with_one_bad(camera_valid, {"azimuth": [np.nan], "elevation": [-100.0, 100.0, np.inf],
                                         "distance": [0.0, -10.0, np.nan], "fov": [0.0, -10.0, 180.0, np.nan]})
sun_valid = st.fixed_dictionaries({
    "azimuth": st.floats(-360.0, 720.0),
    "elevation": st.one_of(st.floats(1.0, 90.0), st.sampled_from([90.0, 1e-3])),
    "irradiance": st.one_of(st.floats(0.0, 5.0), st.tuples(*[st.floats(0.0, 3.0)] * 3)),
    "angular_diameter_deg": st.one_of(st.floats(0.0, 5.0), st.sampled_from([0.0, 0.53]))})
sun_bad = with_one_bad(sun_valid, {"elevation": [0.0, -10.0, 100.0, np.nan], "irradiance": [-1.0, np.nan, (1.0, 2.0)],
                                   "angular_diameter_deg": [-1.0, 6.0, np.nan]})
spec_valid = st.fixed_dictionaries({
    "width": st.integers(1, 5), "height": st.integers(1, 4), "sky": st.sampled_from(["sunsky", "constant", None]),
    "ground": st.one_of(st.none(), st.tuples(st.floats(0.0, 1.0), st.floats(-2000.0, 3000.0))),
    "seed": st.integers(0, 10)})
spec_bad = with_one_bad(spec_valid, {"width": [0, -1, 2.5, True], "height": [0, 1.5], "seed": [-1, 1.5],
                                     "ground": [(-0.5, 0.0), (1.5, 0.0)]})

GROUPS = ("hyd", "optics", "camera", "sun", "spec")
VALID = dict(zip(GROUPS, (hyd_valid, optics_valid, camera_valid, sun_valid, spec_valid)))
BAD = dict(zip(GROUPS, (hyd_bad, optics_bad, camera_bad, sun_bad, spec_bad)))


@st.composite
def arguments(draw):
    """All five argument groups valid (about half the examples, so that renders are reached) or one of them
    with one bad entry."""
    broken = draw(st.sampled_from((None,) * 4 + GROUPS))
    return {g: draw(BAD[g] if g == broken else VALID[g]) for g in GROUPS}


def build(args):
    """Everything a user constructs before rendering (may raise WeatherDataError / ValueError)."""
    hyd = wm.from_arrays(**args["hyd"])
    optics = args["optics"]
    vol = wm.optical_volume(hyd, species=optics["species"], scale=optics["scale"], phase=optics["phase"],
                            phase_quality="test")
    spec = args["spec"]
    ground = None if spec["ground"] is None else wm.Ground(albedo=spec["ground"][0], height=spec["ground"][1])
    return vol, wm.SceneSpec(camera=wm.Camera.orbit(vol, **args["camera"]), sun=wm.Sun(**args["sun"]),
                             sky=None if spec["sky"] is None else wm.Sky(spec["sky"]), ground=ground,
                             width=spec["width"], height=spec["height"], seed=spec["seed"])


@pytest.mark.filterwarnings("ignore::UserWarning")  # clipped negatives and the like: warnings are allowed
@settings(max_examples=10, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(arguments())
def test_every_input_renders_finite_or_is_refused_before_rendering(args):
    try:
        vol, scene = build(args)
    except (wm.WeatherDataError, ValueError):
        return
    images = []
    for render in (lambda: wm.render_reference(scene, vol, spp=2, progress=False),
                   lambda: wm.render_slices(scene, vol, slices=8, light_res=8)):
        try:  # checks of the volume against the scene (a volume under the ground) come before rendering
            images.append(render())
        except (wm.WeatherDataError, ValueError):
            pass
    for img in images:
        assert img.radiance.shape == (scene.height, scene.width, 3)
        assert np.all(np.isfinite(img.radiance)) and np.all(img.radiance >= 0)
