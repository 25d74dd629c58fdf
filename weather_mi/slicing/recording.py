"""The frame's recorded kernels: ``dr.freeze`` of a renderer's ``_kernels``, with the three pitfalls of
Dr.Jit 1.5 it must steer clear of, each of which aborts the process: a garbage collection that frees
recordings, an exception raised out of a recording, and a collection that runs inside a recording."""
from __future__ import annotations

FREEZE_LIMIT = 8  # recordings kept per renderer (slice counts of the viewer's drafts, rebuilt or not, ...)


def without_gc(func, *args):
    """``func(*args)`` with Python's cyclic garbage collector held off: a collection that ran inside a
    ``dr.freeze`` recording and freed another renderer's recordings (cyclic garbage left by an earlier
    frame or test) would abort the process (Dr.Jit 1.5)."""
    import gc
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        return func(*args)
    finally:
        if was_enabled:
            gc.enable()


def raise_recording_error(renderer):
    """Raise the error the kernels raised while being recorded. Its traceback holds this frame; had the
    frame kept the error in a local, error -> traceback -> frame -> error would be a cycle holding the
    renderer (and its recordings) until a garbage collection, which may come inside another recording."""
    error, renderer._recording_error = renderer._recording_error, None
    try:
        raise error
    finally:
        del error


def freeze_kernels(renderer_ref):
    """The renderer's ``_kernels`` recorded by ``dr.freeze`` (one recording per structure of its inputs,
    the last FREEZE_LIMIT kept). Through a weak reference: a frozen function that held its renderer would
    make a reference cycle, and Dr.Jit aborts when the garbage collector frees recordings. An exception
    raised out of this recording aborts the process too (Dr.Jit 1.5: "enqueue_host_func(): this function
    cannot be recorded"): the kernels' exception is kept on the renderer and the recording returns None
    (``frame`` drops the recordings and raises it)."""
    import drjit as dr

    def kernels(inputs):
        renderer = renderer_ref()
        try:
            return renderer._constants._kernels(inputs)
        except Exception as error:  # (raised out of a recording, it would abort the process: see frame)
            renderer._recording_error = error
            return None
    return dr.freeze(kernels, limit=FREEZE_LIMIT, warn_after=4 * FREEZE_LIMIT)
