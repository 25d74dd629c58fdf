"""The passes of a reference render as Dask tasks (``render_reference(..., client=...)``).

The scene (a ``PassScene``: SceneSpec, OpticalVolume, estimator options) travels once to each worker:
it is the result of one small task that every pass task depends on, so the scheduler copies it to a
worker the first time that worker needs it, and can compute it again from the graph if every copy is
lost with a killed worker. Each worker process builds its Mitsuba scene once (cached by the render's
fingerprint) and renders pass i with the seed ``pass_seed(seed, i)``, as the in-process loop does. The
client receives the pass images as they finish and hands them over in pass order, so the Welford merge
in ``render_reference`` sees the same sequence as in one process: a bit-identical image whatever the
number of workers, their speed, retries or a worker killed mid-render (its tasks run again elsewhere).
"""
from __future__ import annotations

import time
import uuid

import numpy as np

from . import passes

POLL_S = 0.5            # how often the client wakes up while waiting (Ctrl-C, lost workers)
NO_WORKER_LIMIT_S = 120.0  # all workers gone for this long: give up rather than hang
SCENES_PER_WORKER = 2   # Mitsuba scenes kept per worker process (an animation renders many)

_worker_scenes: dict = {}
_render_thread = None   # created in the worker process on first use


def on_render_thread(fn, *args):
    """Run ``fn(*args)`` on this process's one rendering thread and wait for it: one render at a time
    (Dr.Jit already uses every core), always from the same Python thread, whatever the number of Dask
    threads of the worker (Dr.Jit keeps state per thread: passes alternating between two Dask threads
    of one worker ran 2.8x slower)."""
    global _render_thread
    if _render_thread is None:
        from concurrent.futures import ThreadPoolExecutor
        _render_thread = ThreadPoolExecutor(1, thread_name_prefix="weather-mi-render")
    return _render_thread.submit(fn, *args).result()


def _hold(obj):
    return obj


def held(client, obj, key: str):
    """A future of ``obj`` that workers fetch once each and that survives any worker's death: ``obj``
    travels in the task graph (the scheduler keeps it and can compute it again), not scattered to
    workers that may all die. Dask's warning about a large graph is expected here (one volume)."""
    import warnings
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Sending large graph", category=UserWarning)
        return client.submit(_hold, obj, key=key, pure=False)


def _render_pass_task(job, i: int, spp: int, seed: int, worker_variant, client_variant: str):
    """On a worker: pass ``i`` of ``job`` -> (index, (H, W, 3) float32 image, seconds, worker address,
    the variant it rendered with)."""
    from distributed import get_worker

    from .cluster import variant_for
    from ..kernel.variant import default_variant
    address = get_worker().address
    variant = variant_for(address, worker_variant, client_variant, default_variant())
    raw, seconds = on_render_thread(_render_pass, job, variant, spp, seed, job.pixels_of(i))
    return i, raw, seconds, address, variant


def _render_pass(job, variant: str, spp: int, seed: int, pixels=None):
    from ..kernel.variant import path_tracing_width, set_variant
    set_variant(variant)
    t0 = time.perf_counter()
    with path_tracing_width():  # as in one process: the scene built and rendered at the path tracer's width
        scene = _worker_scenes.get((job.key, variant))
        if scene is None:
            while len(_worker_scenes) >= SCENES_PER_WORKER:
                _worker_scenes.pop(next(iter(_worker_scenes)))
            scene = _worker_scenes[(job.key, variant)] = job.build()
        raw = np.ascontiguousarray(passes.render_pass(scene, spp, seed, pixels=pixels)[..., :3])
    return raw, time.perf_counter() - t0


class RemotePasses:
    """Iterable of (pass index, image, seconds) in pass order, the passes rendered by Dask workers.

    client      : a Client or a scheduler address (connected here, closed at the end).
    job         : the ``PassScene``; ``per_pass(i)``: samples per pixel of pass i; ``more(i)``: whether pass
                  i is wanted (asked in order, after passes < i were handed over: target_rse lives there).
    start       : first pass index (resume); ``planned``: passes certainly wanted (submitted at once);
    open_ended  : more may be wanted (target_rse): keep ``ahead`` passes rendering past the merged ones.
    seconds are wall-clock since the previous pass was handed over.
    ``summary`` (after the loop): workers, passes per worker, bytes per pass, seconds on workers.
    """

    def __init__(self, client, job, per_pass, more, start: int, planned: int, open_ended: bool,
                 worker_variant=None):
        self.client_arg, self.job, self.per_pass, self.more = client, job, per_pass, more
        self.start, self.planned, self.open_ended = start, planned, open_ended
        self.worker_variant = worker_variant
        self.summary: dict | None = None
        self._futures: dict = {}   # pass index -> future, not yet handed over (handed-over ones are released)
        self._scene = None         # the future of the scene, released at the end
        self._client = None
        self._owned = False

    def __iter__(self):
        import mitsuba as mi
        from . import cluster
        self._client, self._owned = cluster.connect(self.client_arg)
        client = self._client
        try:
            variants = cluster.check_workers(client, self.worker_variant, mi.variant())
            threads = sum(client.nthreads().values()) or 1
            ahead = max(4, 2 * threads)
            token = uuid.uuid4().hex[:12]
            scene = self._scene = held(client, self.job, f"weather-mi-scene-{token}")
            summary = {"workers": len(variants), "threads": threads, "variants": sorted(set(variants.values())),
                       "passes_by_worker": {}, "bytes_per_pass": 0, "worker_seconds": 0.0,
                       "passes_by_variant": {cluster.CHECKPOINT_PASSES: self.start} if self.start else {}}
            self.summary = summary
            nxt, i = self.start, self.start   # next pass to submit, next pass to hand over
            last, idle_since = time.perf_counter(), None
            while True:
                if not self.more(i):
                    return
                limit = max(self.planned, i + ahead) if self.open_ended else self.planned
                while nxt < limit:
                    self._futures[nxt] = client.submit(
                        _render_pass_task, scene, nxt, self.per_pass(nxt), passes.pass_seed(self.job.spec.seed, nxt),
                        self.worker_variant, mi.variant(), key=f"weather-mi-pass-{token}-{nxt}", pure=False)
                    nxt += 1
                future = self._futures[i]
                while True:  # pass i, in order (later passes render meanwhile and wait on their workers)
                    try:
                        k, raw, secs, addr, used = future.result(timeout=POLL_S)  # a task error raises here
                        break
                    except TimeoutError:
                        idle_since = self._check_alive(idle_since)
                # released: the workers need not keep the image. Explicitly: a result() that timed out leaves
                # the future in a traceback cycle that only Python's cyclic GC would free, so the pass that
                # waited longest (the first) could stay on the workers for minutes
                del self._futures[i]
                future.release()
                del future
                summary["passes_by_worker"][addr] = summary["passes_by_worker"].get(addr, 0) + 1
                summary["passes_by_variant"][used] = summary["passes_by_variant"].get(used, 0) + 1
                summary["bytes_per_pass"] = int(raw.nbytes)
                summary["worker_seconds"] += secs
                now = time.perf_counter()
                yield i, raw, now - last
                last = now
                i += 1
        finally:
            self.close()

    def _check_alive(self, idle_since):
        """Raise when the scheduler has had no worker for NO_WORKER_LIMIT_S (a hung render otherwise)."""
        if self._client.scheduler_info().get("workers"):
            return None
        now = time.monotonic()
        if idle_since is not None and now - idle_since > NO_WORKER_LIMIT_S:
            raise RuntimeError(f"the Dask scheduler {self._client.scheduler.address} has had no worker for "
                               f"{NO_WORKER_LIMIT_S:.0f} s; passes rendered so far are in the checkpoint")
        return idle_since if idle_since is not None else now

    def close(self) -> None:
        """Cancel the passes still queued or rendering (target met, Ctrl-C, error) and let go of the client."""
        if self._client is None:
            return
        from . import cluster
        futures = list(self._futures.values()) + ([self._scene] if self._scene is not None else [])
        self._futures, self._scene = {}, None
        if futures:
            try:
                self._client.cancel(futures, force=True)
            except Exception:  # the scheduler may be gone already: nothing left to cancel then
                pass
        if self._owned:
            cluster.close(self._client)
        self._client = None
