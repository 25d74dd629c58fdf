"""A usable Dask cluster for weather-mi: connect to a scheduler (or start a LocalCluster), and check the
workers before anything is submitted (weather_mi, Mitsuba and Dr.Jit importable there, in this
process's versions; the Mitsuba variant each worker will render with).

A pass rendered on a worker is bit-identical to the same pass rendered here only with the same
weather_mi, Mitsuba and Dr.Jit and the same variant, hence the checks.
"""
from __future__ import annotations

import contextlib
import time

from . import worker_probe

CONNECT_TIMEOUT_S = 8.0     # an unreachable scheduler is reported within 10 s
WORKER_WAIT_S = 60.0        # a scheduler without workers: how long to wait for the first one
CHECKED_PACKAGES = ("weather_mi", "mitsuba", "drjit")

CHECKPOINT_PASSES = "checkpoint (variant not recorded)"   # passes_by_variant's key for resumed passes


def _probe_variants():
    """On a worker: the Mitsuba variants compiled into its Mitsuba, whether it can run CUDA
    (``variant.cuda_usable``: a tiny kernel ran there) and why, and the variant "auto" gives it."""
    import mitsuba as mi
    from ..kernel.variant import cuda_usable
    ok, why = cuda_usable()
    info = {"variants": sorted(mi.variants()), "cuda": ok, "cuda_reason": why}
    info["default"] = auto_variant(info)
    return info


def auto_variant(info: dict) -> str:
    """The variant ``worker_variant="auto"`` gives a worker whose probe (``_probe_variants``) is ``info``:
    cuda_ad_rgb only where a CUDA test kernel ran and the variant is compiled in, else llvm_ad_rgb."""
    if info.get("cuda") and "cuda_ad_rgb" in info.get("variants", ()):
        return "cuda_ad_rgb"
    return "llvm_ad_rgb"


def pass_variants(passes_by_variant: dict, client_variant: str) -> dict:
    """The metadata of a render whose passes ran with these variants ({variant: number of passes}; resumed
    passes under CHECKPOINT_PASSES): ``variant`` (the one variant, or "mixed"), ``passes_by_variant`` and
    ``agreement`` with the same render in this process: bit for bit only when every pass used
    ``client_variant`` (another variant draws other random numbers with other rounding: within noise)."""
    used = {k: int(v) for k, v in passes_by_variant.items() if v}
    one = next(iter(used)) if len(used) == 1 and CHECKPOINT_PASSES not in used else None
    if set(used) <= {client_variant}:
        agreement = "bit-identical to the in-process render"
    elif CHECKPOINT_PASSES in used and set(used) - {CHECKPOINT_PASSES} <= {client_variant}:
        agreement = "bit-identical to the in-process render if the checkpoint's passes were " + client_variant
    else:
        agreement = (f"within noise of the in-process render ({client_variant}), not bit for bit: passes "
                     f"rendered with other variants")
    return {"variant": one or "mixed", "passes_by_variant": used, "agreement": agreement}


def local_versions() -> dict:
    return worker_probe.versions(list(CHECKED_PACKAGES))["versions"]


def _probe_workers(client) -> dict:
    """{worker address: worker_probe.versions(...) or the exception probing it raised}."""
    import cloudpickle
    cloudpickle.register_pickle_by_value(worker_probe)  # runs where weather_mi cannot be imported
    return client.run(worker_probe.versions, list(CHECKED_PACKAGES), on_error="return")


def connect(client_or_address, timeout_s: float = CONNECT_TIMEOUT_S):
    """(client, owned): a ``dask.distributed.Client`` as given, or a new one connected to the scheduler
    address (owned: the caller closes it). An unreachable address raises ConnectionError within
    ``timeout_s`` seconds."""
    from distributed import Client
    if isinstance(client_or_address, Client):
        return client_or_address, False
    if not isinstance(client_or_address, str):
        raise TypeError(f"client must be a dask.distributed.Client or a scheduler address such as "
                        f"'tcp://host:8786', got {type(client_or_address).__name__}")
    address = client_or_address if "://" in client_or_address else f"tcp://{client_or_address}"
    t0 = time.monotonic()
    try:
        client = Client(address, timeout=timeout_s, set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise ConnectionError(f"no Dask scheduler reachable at {address} (waited {time.monotonic() - t0:.1f} s; "
                              f"start one with `dask scheduler` and give its address, e.g. tcp://host:8786): "
                              f"{exc}") from None
    return client, True


def _drjit_threads_plugin(threads: int):
    """A worker plugin that sets Dr.Jit's CPU thread pool of every worker process, restarted ones too."""
    from distributed import WorkerPlugin

    class DrJitThreads(WorkerPlugin):
        name = "weather-mi-drjit-threads"

        def setup(self, worker):
            import drjit as dr
            dr.set_thread_count(threads)

    return DrJitThreads()


def local_cluster(n_workers: int, threads_per_worker: int = 1):
    """A Client on a new LocalCluster of ``n_workers`` worker processes (closing the client closes the
    cluster), the machine's cores shared among them: each worker's Dr.Jit pool gets cores / n_workers
    threads (by default every process's pool has one per core, so n workers would run n x cores threads
    on the cores). Scripts that call this need ``if __name__ == "__main__":`` (workers are spawned)."""
    import os

    from distributed import Client, LocalCluster
    if not isinstance(n_workers, int) or n_workers < 1:
        raise ValueError(f"the number of workers must be a positive integer, got {n_workers!r}")
    cluster = LocalCluster(n_workers=n_workers, threads_per_worker=threads_per_worker, processes=True,
                           dashboard_address=":0")
    client = Client(cluster, set_as_default=False)
    client._weather_mi_owns_cluster = cluster
    client.register_plugin(_drjit_threads_plugin(max(1, (os.cpu_count() or 1) // n_workers)))
    return client


def close(client) -> None:
    """Close a client from ``connect`` or ``local_cluster`` (and the LocalCluster it started)."""
    cluster = getattr(client, "_weather_mi_owns_cluster", None)
    with contextlib.suppress(Exception):
        client.close(timeout=10)
    if cluster is not None:
        with contextlib.suppress(Exception):
            cluster.close(timeout=10)


@contextlib.contextmanager
def session(scheduler: str | None = None, workers: int | None = None):
    """A client for the duration of a command: connected to ``scheduler``, on a new LocalCluster of
    ``workers`` processes, or None (render in this process); closed at the end."""
    if scheduler is None and workers is None:
        yield None
        return
    client = connect(scheduler)[0] if scheduler is not None else local_cluster(workers)
    try:
        yield client
    finally:
        close(client)


def check_workers(client, worker_variant=None, client_variant: str | None = None,
                  wait_s: float = WORKER_WAIT_S) -> dict:
    """Check every worker of ``client`` before submitting: weather_mi, Mitsuba and Dr.Jit importable in
    this process's versions, and the variant ``worker_variant`` asks for compiled there. Returns
    {worker address: variant}. Raises RuntimeError naming each bad worker and both versions, or
    ValueError for a variant a worker lacks."""
    try:
        client.wait_for_workers(1, timeout=wait_s)
    except (TimeoutError, OSError) as exc:
        raise RuntimeError(f"no Dask worker joined the scheduler {client.scheduler.address} within {wait_s:.0f} s "
                           f"(start workers with `dask worker {client.scheduler.address}`)") from exc
    mine = local_versions()
    found = _probe_workers(client)
    problems = []
    for addr, got in sorted(found.items()):
        if isinstance(got, BaseException):
            problems.append(f"worker {addr}: probing it failed ({type(got).__name__}: {got}); this client has "
                            + ", ".join(f"{k} {v}" for k, v in mine.items()))
            continue
        for name in CHECKED_PACKAGES:
            theirs = got["versions"].get(name)
            if theirs != mine[name]:
                what = (f"cannot be imported ({got['errors'][name]})" if theirs is None
                        else f"has version {theirs}")
                problems.append(f"worker {addr}: {name} {what}, this client has {name} {mine[name]}")
    if problems:
        raise RuntimeError("Dask workers that cannot render this image bit for bit:\n  " + "\n  ".join(problems)
                           + "\ninstall the same weather-mi, mitsuba and drjit on every worker (pip install "
                             "weather-mi==<version>) or start workers from this environment")
    return resolve_variants(client, worker_variant, client_variant)


def resolve_variants(client, worker_variant, client_variant: str | None) -> dict:
    """{worker address: variant} for ``worker_variant`` (see ``variant_for``), each checked against the
    variants compiled on that worker."""
    found = client.run(_probe_variants)
    out, bad = {}, []
    for addr, info in sorted(found.items()):
        v = variant_for(addr, worker_variant, client_variant, info["default"])
        if v not in info["variants"]:
            bad.append(f"worker {addr}: variant {v!r} is not one of its Mitsuba variants {info['variants']}")
        out[addr] = v
    if bad:
        raise ValueError("unknown Mitsuba variant for Dask workers:\n  " + "\n  ".join(bad))
    return out


def variant_for(address: str, worker_variant, client_variant: str | None, worker_default: str) -> str:
    """The variant a worker renders with: ``worker_variant`` None -> the client's variant (bit-identical
    images); "auto" -> ``worker_default``, the worker's ``auto_variant`` (cuda_ad_rgb only where a CUDA
    kernel ran there); a variant name; or a dict {worker address: variant} (workers not in it: the
    client's variant)."""
    fallback = client_variant or worker_default
    if worker_variant is None:
        return fallback
    if worker_variant == "auto":
        return worker_default
    if isinstance(worker_variant, str):
        return worker_variant
    if isinstance(worker_variant, dict):
        return worker_variant.get(address, fallback)
    raise TypeError(f"worker_variant must be None, 'auto', a variant name or a dict {{worker address: variant}}, "
                    f"got {type(worker_variant).__name__}")
