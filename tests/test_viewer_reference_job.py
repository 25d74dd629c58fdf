"""``weather_mi.viewer.reference_job.ReferenceJob``: the progressive path-traced reference in a background
process. A 32 x 24 view of the demo cumulus (passes of 1 spp, ~0.1 s each): updates arrive in order
and end with the in-process ``render_reference`` image of the same passes; the child exits by itself
after its final update, however slow its interpreter's teardown; cancel ends the process at once; a
child's error arrives as text; the child does not outlive its parent.
"""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.viewer.recipe import VolumeRecipe
from weather_mi.viewer.reference_job import JOIN_TIMEOUT_S, ReferenceJob, ReferenceUpdate

W, H = 32, 24
CUMULUS = VolumeRecipe(demo="cumulus")
ROOT = Path(__file__).resolve().parents[1]


def side_view(seed=5) -> wm.SceneSpec:
    # the cumulus box is 6.4 km x 6.4 km x 5.5 km: from 9 km south, level, at mid-height
    cam = wm.Camera(origin=(3200.0, -9000.0, 2500.0), target=(3200.0, 3200.0, 2500.0), fov=45.0)
    return wm.SceneSpec(camera=cam, width=W, height=H, seed=seed)


WALL_GUARD = 10.0  # a wait's wall-time guard, in multiples of its budget of the child's CPU time: catches a hang


def child_cpu_s(job: ReferenceJob) -> float:
    """CPU seconds (user + system) the job's child has used so far; its last reading once it has exited."""
    try:
        fields = Path(f"/proc/{job.pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (FileNotFoundError, ProcessLookupError):
        return getattr(job, "_cpu_seen", 0.0)
    job._cpu_seen = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    return job._cpu_seen


def wait_for(job: ReferenceJob, cpu_budget_s: float, until=lambda u: u.done) -> list[ReferenceUpdate]:
    """Poll every 20 ms; every update polled, up to the first that satisfies ``until``. The budget counts the
    child's CPU time, not wall time: the child runs at nice 10, and on a busy machine it gets a small share of
    a core, so a wall-clock deadline would fail a render for the machine's load (seen with both cores busy)."""
    seen = []
    t_guard = time.monotonic() + WALL_GUARD * cpu_budget_s
    while child_cpu_s(job) < cpu_budget_s and time.monotonic() < t_guard:
        u = job.poll()
        if u is not None:
            seen.append(u)
            if until(u):
                return seen
            if u.done or u.error:  # the last word, and not the one awaited
                pytest.fail(f"the job ended first: {[(v.passes, v.done, v.error) for v in seen]}")
        time.sleep(0.02)
    pytest.fail(f"no final update within {cpu_budget_s} s of the child's CPU time, {child_cpu_s(job):.1f} s used "
                f"(got {[(u.passes, u.done) for u in seen]})")


class Stop(Exception):
    pass


def test_on_pass_sees_every_estimate_and_can_stop_the_render(tmp_path):
    """``render_reference(on_pass=...)`` in this process: an estimate after every pass, the last the
    returned image; an exception raised by the callback propagates, the checkpoint stays resumable."""
    rng = np.random.default_rng(0)
    vol = wm.OpticalVolume.from_arrays((0.01 * (0.3 + rng.random((6, 6, 6)))).astype(np.float32), 0.99,
                                       wm.phase.henyey_greenstein(0.85), ((0.0, 0.0, 1000.0), (1000.0, 1000.0, 2000.0)))
    cam = wm.Camera.orthographic(center=(500.0, -1000.0, 1500.0), direction=(0.0, 1.0, 0.0), width=800, height=600)
    spec = wm.SceneSpec(camera=cam, sky=wm.Sky("constant"), width=16, height=12, seed=3)
    seen = []
    img = wm.render_reference(spec, vol, spp=12, passes=4, progress=False, on_pass=seen.append)
    assert [e.metadata["passes"] for e in seen] == [1, 2, 3, 4]
    assert [e.metadata["spp"] for e in seen] == [3, 6, 9, 12]
    assert np.all(np.isnan(seen[0].stderr)) and seen[0].metadata["noise"] is None
    assert all(np.all(np.isfinite(e.stderr)) and e.metadata["noise"]["cloud_pixels"] > 0 for e in seen[1:])
    assert np.array_equal(seen[-1].radiance, img.radiance) and np.array_equal(seen[-1].stderr, img.stderr)
    assert seen[-1].metadata == img.metadata
    assert seen[0].radiance is not seen[1].radiance and seen[0].radiance.dtype == np.float32

    def stop_after_two(estimate):
        if estimate.metadata["passes"] == 2:
            raise Stop
    ckpt = tmp_path / "ref.npz"
    with pytest.raises(Stop):
        wm.render_reference(spec, vol, spp=12, passes=4, progress=False, checkpoint=ckpt, on_pass=stop_after_two)
    resumed = wm.render_reference(spec, vol, spp=12, passes=4, progress=False, checkpoint=ckpt, resume=True)
    assert np.array_equal(resumed.radiance, img.radiance)


def test_updates_arrive_progressively_and_end_with_the_in_process_image():
    spec = side_view()
    with ReferenceJob(CUMULUS, spec, target_rse=0.3, max_seconds=20.0) as job:
        assert job.spp == 2 and job.threads == 1
        job.start()
        updates = wait_for(job, 90.0)
        final = updates[-1]
        assert len(updates) >= 2
        passes = [u.passes for u in updates]
        # increasing; the final (done) update may repeat the last pass's count when both were polled
        assert passes[:-1] == sorted(set(passes[:-1])) and passes[-1] >= passes[-2] and passes[0] >= 1
        assert [u.done for u in updates] == [False] * (len(updates) - 1) + [True]
        assert final.error is None and job.done and not job.running and job.error is None
        assert final.rse_mean <= 0.3 or final.seconds >= 20.0
        assert final.spp == final.passes  # 1 spp per pass (spp 2: the plan of two passes of 1)
        for u in updates:
            assert u.image.radiance.shape == (H, W, 3) and u.image.radiance.dtype == np.float32
            assert u.image.metadata["passes"] == u.passes and u.image.metadata["target_rse"] == 0.3
            assert np.all(np.isnan(u.image.stderr)) == (u.passes < 2)
        assert job.poll() is None  # nothing after the final update; the process is reaped
        assert job._proc.exitcode == 0
    # the same passes in this process: the same seeds (pass_seed(5, i)) and samples per pass; the
    # child's single Dr.Jit thread does not change the samples (1 spp per pass: no sum within a pass).
    # Past its two planned passes the job's render to a target renders every pixel (target_pixels="all", issue
    # 38: the sky converges with the cloud), so every pixel is that of the same passes over the whole frame
    vol = CUMULUS.volume()
    ref = wm.render_reference(spec, vol, spp=final.spp, passes=final.passes, progress=False)
    assert np.array_equal(ref.radiance, final.image.radiance)
    np.testing.assert_allclose(ref.stderr, final.image.stderr, rtol=1e-6, atol=0)
    assert ref.metadata["noise"]["rse_mean"] == pytest.approx(final.rse_mean, rel=1e-6)
    assert final.image.metadata["spp_background"] == final.spp and final.image.metadata["target_pixels"] == "all"


def test_a_job_over_the_cloud_pixels_keeps_the_first_estimate_elsewhere():
    """``target_pixels="cloud"``: past its two planned passes the render adds passes over the cloud pixels only;
    the other pixels are those of the two planned passes."""
    spec = side_view()
    with ReferenceJob(CUMULUS, spec, target_rse=1e-3, max_seconds=8.0, target_pixels="cloud") as job:
        job.start()
        final = wait_for(job, 90.0)[-1]
    assert final.error is None and final.passes > 2
    vol = CUMULUS.volume()
    cloud = wm.reference.render.cloud_mask(spec, vol)
    ref = wm.render_reference(spec, vol, spp=final.spp, passes=final.passes, progress=False)
    assert np.array_equal(ref.radiance[cloud], final.image.radiance[cloud])
    planned = wm.render_reference(spec, vol, spp=2, passes=2, progress=False)
    assert np.array_equal(planned.radiance[~cloud], final.image.radiance[~cloud])
    assert final.image.metadata["spp_background"] == 2


class SlowTeardownRecipe(VolumeRecipe):
    """A recipe whose process (the reference's child) would take longer than JOIN_TIMEOUT_S to end its
    interpreter (an atexit handler that sleeps): what Dr.Jit's and Mitsuba's teardown take at nice 10 on a
    busy machine."""

    def volume(self, scale=None, hyd=None):
        import atexit
        atexit.register(time.sleep, JOIN_TIMEOUT_S + 5.0)
        return super().volume(scale, hyd)


def test_the_child_exits_by_itself_after_its_final_update():
    """After its final update the child exits at once (no interpreter teardown), with exit code 0: the
    parent's poll, which reaps it, does not wait past JOIN_TIMEOUT_S and terminate it (exit code -15)."""
    with ReferenceJob(SlowTeardownRecipe(demo="cumulus"), side_view(), target_rse=None) as job:
        job.start()
        (*_, final) = wait_for(job, 90.0)
        assert final.error is None and final.passes == 2
        assert job._proc.exitcode == 0


def test_cancel_ends_the_process_at_once():
    job = ReferenceJob(CUMULUS, side_view(), target_rse=1e-3, max_seconds=120.0).start()
    wait_for(job, 60.0, until=lambda u: u.passes >= 2)
    assert job.running
    proc = job._proc
    t0 = time.monotonic()
    job.cancel()
    assert time.monotonic() - t0 < 3.0
    assert not proc.is_alive() and proc.exitcode is not None  # reaped: no zombie
    assert not job.running and job.cancelled and not job.done
    time.sleep(0.3)
    assert job.poll() is None
    job.cancel()  # idempotent
    # cancelled before the child has even imported Mitsuba
    early = ReferenceJob(CUMULUS, side_view()).start()
    early.cancel()
    assert not early._proc.is_alive() and early._proc.exitcode is not None and early.poll() is None
    with pytest.raises(RuntimeError):
        early.start()


def test_an_error_in_the_child_arrives_as_an_update(tmp_path):
    missing = tmp_path / "wrfout_missing.nc"
    job = ReferenceJob(VolumeRecipe(path=str(missing)), side_view()).start()
    (u,) = wait_for(job, 60.0, until=lambda u: u.error is not None)
    assert str(missing) in u.error and "WeatherDataError" in u.error
    assert u.image is None and u.done
    assert job.error == u.error and not job.running
    assert not job._proc.is_alive()
    job.cancel()


def test_the_child_does_not_outlive_its_parent(tmp_path):
    """A parent that dies without cancelling (os._exit: no atexit, no daemon clean-up) while the child
    renders: the child's watchdog notices within a second and exits."""
    if not Path("/proc/self/stat").is_file():
        pytest.skip("reads process states from /proc")
    script = textwrap.dedent(f"""
        import os, sys, time
        sys.path.insert(0, {str(ROOT)!r})
        import weather_mi as wm
        from weather_mi.viewer.recipe import VolumeRecipe
        from weather_mi.viewer.reference_job import ReferenceJob
        if __name__ == "__main__":
            cam = wm.Camera(origin=(3200.0, -9000.0, 2500.0), target=(3200.0, 3200.0, 2500.0), fov=45.0)
            job = ReferenceJob(VolumeRecipe(demo="cumulus"), wm.SceneSpec(camera=cam, width=32, height=24),
                               target_rse=1e-3, max_seconds=120.0).start()
            while job.poll() is None:  # the child is rendering
                time.sleep(0.02)
            print(job.pid, flush=True)
            os._exit(0)
    """)
    path = tmp_path / "parent.py"
    path.write_text(script)
    # a hang guard, not a speed check: the parent waits for its nice-10 child's first pass
    out = subprocess.run([sys.executable, str(path)], capture_output=True, text=True, timeout=600)
    pid = int(out.stdout.split()[0])

    def alive(pid):  # a zombie waiting for init to reap it counts as gone
        try:
            return Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0] != "Z"
        except FileNotFoundError:
            return False

    t_end = time.monotonic() + 10.0
    while alive(pid) and time.monotonic() < t_end:
        time.sleep(0.1)
    still = alive(pid)
    if still:
        os.kill(pid, 9)
    assert not still, "the reference process outlived its parent"
