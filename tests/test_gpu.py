"""The GPU path (``cuda_ad_rgb``).

Here, on any machine: the CUDA probe (``variant.cuda_usable``: a test kernel, not just a driver that
loads), the decision of ``worker_variant="auto"`` (the probe mocked for the GPU branch), the metadata
of passes rendered with several variants, and the guards that keep Dr.Jit's LLVM-only settings (block
size, SIMD width, persistent lanes: ctypes calls into ``libdrjit-core.so``) off CUDA variants, with
``mi.variant()`` mocked to "cuda_ad_rgb" and every such call made to fail.

With a usable GPU only (skipped with the probe's reason otherwise): the Eq. 8 plugin and the majorant
integrator load under cuda_ad_rgb; a reference render and a slicer frame there agree with the LLVM
ones, the reference within combined standard errors (z over cloud pixels), the slicer within 0.2% of
the image's maximum; no LLVM-only call is made under the real CUDA variant.
"""
from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

import mitsuba as mi
import weather_mi as wm
from weather_mi.reference import cluster, passes
from weather_mi.kernel import jit_settings, variant
from weather_mi.kernel.plugins import lanes

from test_reference import cloud_volume, spec

ROOT = Path(__file__).resolve().parents[1]
CUDA_OK, CUDA_WHY = variant.cuda_usable()
LLVM_OK = variant.llvm_usable()
needs_gpu = pytest.mark.skipif(not CUDA_OK, reason=f"no usable CUDA device: {CUDA_WHY}")
needs_llvm = pytest.mark.skipif(not LLVM_OK, reason="Dr.Jit's LLVM backend is absent here (no libLLVM >= 16; "
                                                     "DRJIT_LIBLLVM_PATH): nothing to compare CUDA with")
LLVM_ONLY = ("tune_llvm", "llvm_block_size", "llvm_vector_width", "set_llvm_vector_width")


def forbid_llvm_calls(monkeypatch) -> list:
    """From now on every call into Dr.Jit's LLVM-only core settings fails the test (they all go through
    ``jit_settings._core_function``); returns the list of symbols asked for."""
    asked = []

    def forbidden(name):
        asked.append(name)
        pytest.fail(f"LLVM-only Dr.Jit setting {name} called under {mi.variant()}")
    monkeypatch.setattr(jit_settings, "_core_function", forbidden)
    return asked


@pytest.fixture
def llvm_calls_fail(monkeypatch):
    return forbid_llvm_calls(monkeypatch)


@pytest.fixture
def as_cuda(monkeypatch):
    """``mi.variant()`` reads "cuda_ad_rgb" (nothing is rendered: only the guards are exercised)."""
    monkeypatch.setattr(mi, "variant", lambda: "cuda_ad_rgb")


class _Integrator:
    persistent = True

    def render_passes(self, *a, **k):
        raise AssertionError("persistent lanes chosen")


class _Scene:
    def integrator(self):
        return _Integrator()


# ------------------------------------------------------------------ the probe and "auto"

def test_probe_here_matches_the_default_variant_and_set_variant_says_why():
    assert isinstance(CUDA_WHY, str) and CUDA_WHY
    import drjit as dr
    if dr.has_backend(dr.JitBackend.CUDA):  # a CUDA backend: the probe's kernel decides (tested with mocks below)
        return
    # no CUDA backend at all (a fact independent of the probe under test): LLVM, and the probe says no
    assert variant.default_variant() == "llvm_ad_rgb" and not CUDA_OK
    # no GPU: a clear error naming the reason, before Mitsuba's bare ImportError, the variant kept
    before = mi.variant()
    with pytest.raises(RuntimeError, match=r"'cuda_ad_rgb' cannot run in this process: .*llvm_ad_rgb"):
        wm.set_variant("cuda_ad_rgb")
    assert mi.variant() == before


def test_probe_needs_a_kernel_that_runs_not_only_a_backend(monkeypatch):
    import drjit as dr
    import drjit.llvm
    if LLVM_OK:
        assert variant.probe_kernel(drjit.llvm) == 12.0   # the probe's kernel itself, on a backend that works
    monkeypatch.setattr(dr, "has_backend", lambda backend: True)   # a driver that loads ...

    def broken(backend):
        raise RuntimeError("cuCtxCreate(): CUDA_ERROR_NO_DEVICE")
    monkeypatch.setattr(variant, "probe_kernel", broken)           # ... and a device that cannot run
    ok, why = variant._probe_cuda()
    assert not ok and "test kernel failed" in why and "CUDA_ERROR_NO_DEVICE" in why
    monkeypatch.setattr(variant, "probe_kernel", lambda backend: 11.0)
    assert variant._probe_cuda() == (False, "a CUDA test kernel returned 11.0, expected 12")
    monkeypatch.setattr(variant, "probe_kernel", lambda backend: 12.0)
    assert variant._probe_cuda()[0] is True
    monkeypatch.setattr(dr, "has_backend", lambda backend: False)
    assert variant._probe_cuda()[0] is False
    monkeypatch.setattr(mi, "variants", lambda: ["scalar_rgb", "llvm_ad_rgb"])
    assert variant._probe_cuda() == (False, "this Mitsuba build has no cuda_ad_rgb variant")


class _FakeClient:
    """``client.run(fn)`` answering for two workers: one whose CUDA kernel ran, one without a GPU."""

    def __init__(self, infos):
        self.infos = infos

    def run(self, fn, *args, **kw):
        return self.infos


def test_auto_picks_cuda_only_where_the_probe_ran_a_kernel():
    compiled = ["llvm_ad_rgb", "cuda_ad_rgb"]
    gpu = {"variants": compiled, "cuda": True, "cuda_reason": "a CUDA test kernel ran"}
    cpu = {"variants": compiled, "cuda": False, "cuda_reason": "drjit.has_backend(CUDA) is False"}
    no_variant = {"variants": ["llvm_ad_rgb"], "cuda": True, "cuda_reason": "a CUDA test kernel ran"}
    assert [cluster.auto_variant(i) for i in (gpu, cpu, no_variant)] == ["cuda_ad_rgb", "llvm_ad_rgb", "llvm_ad_rgb"]
    infos = {a: dict(i, default=cluster.auto_variant(i)) for a, i in
             (("tcp://gpu:1", gpu), ("tcp://cpu:1", cpu), ("tcp://old:1", no_variant))}
    got = cluster.resolve_variants(_FakeClient(infos), "auto", "llvm_ad_rgb")
    assert got == {"tcp://gpu:1": "cuda_ad_rgb", "tcp://cpu:1": "llvm_ad_rgb", "tcp://old:1": "llvm_ad_rgb"}
    # None keeps the client's variant everywhere (bit-identical images)
    assert set(cluster.resolve_variants(_FakeClient(infos), None, "llvm_ad_rgb").values()) == {"llvm_ad_rgb"}
    # this machine, probed for real: llvm without a GPU
    import drjit as dr
    here = cluster._probe_variants()
    if not dr.has_backend(dr.JitBackend.CUDA):  # independent of the probe: no backend, no CUDA worker
        assert here["default"] == "llvm_ad_rgb" and here["cuda"] is False


def test_metadata_names_the_variants_of_the_passes():
    one = cluster.pass_variants({"llvm_ad_rgb": 8}, "llvm_ad_rgb")
    assert one == {"variant": "llvm_ad_rgb", "passes_by_variant": {"llvm_ad_rgb": 8},
                   "agreement": "bit-identical to the in-process render"}
    gpu = cluster.pass_variants({"cuda_ad_rgb": 8}, "llvm_ad_rgb")
    assert gpu["variant"] == "cuda_ad_rgb" and gpu["agreement"].startswith("within noise")
    mixed = cluster.pass_variants({"cuda_ad_rgb": 5, "llvm_ad_rgb": 3}, "llvm_ad_rgb")
    assert mixed["variant"] == "mixed" and mixed["passes_by_variant"] == {"cuda_ad_rgb": 5, "llvm_ad_rgb": 3}
    assert "not bit for bit" in mixed["agreement"]
    resumed = cluster.pass_variants({cluster.CHECKPOINT_PASSES: 4, "llvm_ad_rgb": 4}, "llvm_ad_rgb")
    assert resumed["variant"] == "mixed" and "if the checkpoint's passes were llvm_ad_rgb" in resumed["agreement"]


# ------------------------------------------------------------------ LLVM-only settings skipped on CUDA

@needs_llvm
def test_llvm_settings_are_read_on_llvm(monkeypatch):
    """The control for the guard tests below: on LLVM the same code does call the core settings."""
    before = mi.variant()
    wm.set_variant("llvm_ad_rgb")
    asked = []
    real = jit_settings._core_function
    monkeypatch.setattr(jit_settings, "_core_function", lambda name: asked.append(name) or real(name))
    try:
        with variant.path_tracing_width():
            pass
        assert "_Z21jit_llvm_vector_widthv" in asked
        assert lanes.default_lanes() >= 64 and "_Z19jit_llvm_block_sizev" in asked
        assert passes._persistent(_Scene(), None) is True
    finally:
        wm.set_variant(before)


def test_no_llvm_setting_is_touched_under_cuda(as_cuda, llvm_calls_fail, monkeypatch):
    assert not variant.is_llvm() and variant.is_llvm("llvm_ad_rgb")
    with variant.path_tracing_width():   # the path tracer's SIMD width: LLVM only
        pass
    monkeypatch.setattr(variant, "_tuned", False)
    monkeypatch.setattr(variant, "_registered", {"cuda_ad_rgb"})  # registration itself is not under test
    variant._register_current()           # the block size: LLVM only, and not marked as done
    assert variant._tuned is False
    # persistent lanes: never on CUDA, even when asked for; their lane count reads no LLVM setting
    assert passes._persistent(_Scene(), None) is False and passes._persistent(_Scene(), True) is False
    assert lanes.default_lanes() == lanes.CUDA_LANES
    assert llvm_calls_fail == []


def _calls_of(path: Path, names) -> set:
    tree = ast.parse(path.read_text())
    return {n.func.id if isinstance(n.func, ast.Name) else n.func.attr for n in ast.walk(tree)
            if isinstance(n, ast.Call) and isinstance(n.func, (ast.Name, ast.Attribute))
            and (n.func.id if isinstance(n.func, ast.Name) else n.func.attr) in names}


def _uses_drjit_llvm(path: Path) -> bool:
    """Whether the module imports ``drjit.llvm`` or reads ``dr.llvm`` / ``drjit.llvm``."""
    for n in ast.walk(ast.parse(path.read_text())):
        if isinstance(n, ast.Import) and any(a.name.startswith("drjit.llvm") for a in n.names):
            return True
        if isinstance(n, ast.ImportFrom) and ((n.module or "").startswith("drjit.llvm")
                                              or (n.module == "drjit" and any(a.name == "llvm" for a in n.names))):
            return True
        if (isinstance(n, ast.Attribute) and n.attr == "llvm" and isinstance(n.value, ast.Name)
                and n.value.id in ("dr", "drjit")):
            return True
    return False


def test_llvm_only_settings_are_called_only_from_the_guarded_places():
    """A tripwire: the library calls the LLVM-only settings from variant.py (is_llvm) and weather_mi/kernel/plugins/lanes.py
    (default_lanes, LLVM only) and nowhere else, and never imports drjit.llvm: a new call site must get
    a guard (and be added here)."""
    callers = {}
    for path in sorted([*(ROOT / "weather_mi").rglob("*.py"), *(ROOT / "plugins").rglob("*.py")]):
        if path.name == "jit_settings.py" or path.is_relative_to(ROOT / "weather_mi" / "plugins"):
            continue   # (weather_mi/plugins: a link to plugins/ where the package runs uninstalled)
        found = _calls_of(path, LLVM_ONLY)
        if found:
            callers[str(path.relative_to(ROOT))] = found
        assert not _uses_drjit_llvm(path), path
    assert callers == {"weather_mi/kernel/variant.py": {"tune_llvm", "llvm_block_size", "llvm_vector_width",
                                                 "set_llvm_vector_width"},
                       "weather_mi/kernel/plugins/lanes.py": {"llvm_block_size"}}


# ------------------------------------------------------------------ on a GPU

def _z_scores(a: wm.Image, b: wm.Image) -> np.ndarray:
    """(a - b) / sqrt(se_a^2 + se_b^2) over a's cloud pixels, per channel."""
    cloud = a.transmittance < 0.5
    se = np.sqrt(a.stderr ** 2 + b.stderr ** 2)[cloud]
    return ((a.radiance - b.radiance)[cloud] / np.maximum(se, 1e-30)).ravel()


def _phase_values(vol) -> np.ndarray:
    """The Eq. 8 plugin of ``vol`` (current variant): eval_pdf's value (3 channels) and pdf at 64 angles
    and 4 points of the box, and sample's (direction, weight, pdf) for 16 fixed random numbers."""
    import drjit as dr
    from weather_mi.kernel.medium import phase_dict
    phase = mi.load_dict(phase_dict(vol))
    lo, hi = (np.asarray(b, np.float64) for b in vol.bbox)
    pts = lo + (hi - lo) * np.array([[0.1, 0.2, 0.3], [0.5, 0.5, 0.5], [0.9, 0.4, 0.2], [0.3, 0.8, 0.7]])
    ct = np.repeat(np.cos(np.linspace(0.0, np.pi, 64)), len(pts)).astype(np.float32)
    p = np.tile(pts, (64, 1)).astype(np.float32)
    mei = dr.zeros(mi.MediumInteraction3f, ct.size)
    mei.p, mei.wi = mi.Point3f(*(p[:, k] for k in range(3))), mi.Vector3f(0, 0, 1)
    mei.sh_frame = mi.Frame3f(mei.wi)
    ctx = mi.PhaseFunctionContext(None)
    value, pdf = phase.eval_pdf(ctx, mei, mi.Vector3f(np.sqrt(1 - ct ** 2), np.zeros_like(ct), -ct))
    u = np.random.default_rng(0).random((3, ct.size)).astype(np.float32)
    wo, weight, pdf_s = phase.sample(ctx, mei, mi.Float(u[0]), mi.Point2f(u[1], u[2]))
    return np.concatenate([np.array(value).ravel(), np.array(pdf).ravel(), np.array(wo).ravel(),
                           np.array(weight).ravel(), np.array(pdf_s).ravel()]).astype(np.float64)


@needs_gpu
def test_plugins_load_and_render_under_cuda_without_llvm_settings(monkeypatch):
    from weather_mi.kernel.scene_dict import integrator_dict
    vol = cloud_volume()
    before = mi.variant()
    llvm_calls_fail = forbid_llvm_calls(monkeypatch)
    wm.set_variant("cuda_ad_rgb")
    try:
        values = _phase_values(vol)
        integrator = mi.load_dict(integrator_dict(vol, "majorant", -1, None, None))
        assert hasattr(integrator, "render_passes") and mi.variant() == "cuda_ad_rgb"
        img = wm.render_reference(spec(seed=3), vol, spp=16, passes=4, progress=False, variant="cuda_ad_rgb")
    finally:
        if before is not None and (LLVM_OK or not before.startswith("llvm")):
            wm.set_variant(before)
    assert np.isfinite(values).all() and np.isfinite(img.radiance).all() and img.radiance.mean() > 0
    assert img.metadata["variant"] == "cuda_ad_rgb" and llvm_calls_fail == []


@needs_gpu
@needs_llvm
def test_plugin_values_on_cuda_agree_with_llvm():
    vol = cloud_volume()
    before = mi.variant()
    values = {}
    for v in ("llvm_ad_rgb", "cuda_ad_rgb"):
        wm.set_variant(v)
        values[v] = _phase_values(vol)
    wm.set_variant(before)
    # the same float32 code on both backends
    np.testing.assert_allclose(values["cuda_ad_rgb"], values["llvm_ad_rgb"], rtol=1e-4, atol=1e-6)


@needs_gpu
@needs_llvm
def test_reference_on_cuda_agrees_with_llvm_within_combined_standard_error():
    vol, sp, before = cloud_volume(), spec(seed=3), mi.variant()
    llvm = wm.render_reference(sp, vol, spp=256, passes=16, progress=False, variant="llvm_ad_rgb")
    cuda = wm.render_reference(sp, vol, spp=256, passes=16, progress=False, variant="cuda_ad_rgb")
    wm.set_variant(before)
    assert cuda.metadata["variant"] == "cuda_ad_rgb" and llvm.metadata["variant"] == "llvm_ad_rgb"
    assert np.isfinite(cuda.radiance).all() and (cuda.transmittance < 0.5).sum() > 100
    z = _z_scores(cuda, llvm)
    # 16 passes: se from 15 degrees of freedom (t-distributed z: 0.9% beyond 3 for a t15); the mean of
    # ~200 pixels' z (3 correlated channels) has a spread of ~0.07: 0.25 is 3.5 of it. Two LLVM renders
    # of other seeds gave means -0.011, -0.008, +0.003 and fractions 0, 0, 0.005.
    assert abs(z.mean()) < 0.25, z.mean()
    assert (np.abs(z) > 3).mean() < 0.03, (np.abs(z) > 3).mean()
    # the eye-ray optical depth (cloud mask) in software interpolation on both: the same within float32
    np.testing.assert_allclose(cuda.transmittance, llvm.transmittance, rtol=1e-4, atol=1e-6)


@needs_gpu
@needs_llvm
def test_slicer_frame_on_cuda_agrees_with_llvm():
    vol = cloud_volume()
    # a constant sky: Mitsuba's sunsky may read textures in hardware on CUDA (not the slicer's kernels);
    # benchmarks/gpu.py shows the difference with the sunsky
    sp = wm.scene.spec.default_spec(vol, 64, 48, sky=wm.Sky("constant"))
    mode = wm.SliceMode(phase="per_species", light="multiple")
    frames, before = {}, mi.variant()
    for v in ("llvm_ad_rgb", "cuda_ad_rgb"):
        wm.set_variant(v)
        frames[v] = wm.render_slices(sp, vol, mode, slices=64).radiance
    wm.set_variant(before)
    a, b = frames["llvm_ad_rgb"], frames["cuda_ad_rgb"]
    assert np.isfinite(b).all() and a.max() > 0
    # the same algorithm in float32 (textures in software on both: use_accel=False); only rounding differs
    assert np.abs(a - b).max() <= 2e-3 * a.max(), np.abs(a - b).max() / a.max()
