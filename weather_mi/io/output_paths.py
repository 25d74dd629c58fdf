"""Output files that are never half written nor mixed: the format from the extension, a folder checked
for writing before any work, unique temporary names renamed into place, and a lock that keeps a second
render off a path (and its checkpoint) while the first holds it."""
from __future__ import annotations

import errno
import os
import tempfile
import uuid
from contextlib import contextmanager
from pathlib import Path

from ..errors import OutputWriteError

IMAGE_FORMATS = {".exr": "exr", ".png": "png"}


def image_format(path) -> str:
    """"exr" or "png" from the file name's extension; ValueError for any other."""
    suffix = Path(path).suffix.lower()
    if suffix not in IMAGE_FORMATS:
        raise ValueError(f"{path}: expected an image name ending in .exr (radiance, standard error, metadata) or "
                         f".png (a tone-mapped preview); found {suffix or 'no extension'!r}")
    return IMAGE_FORMATS[suffix]


def render_outputs(output) -> tuple[Path, Path, Path]:
    """(EXR, PNG, checkpoint) of a render's ``-o`` (a .exr or .png name; ValueError for another extension):
    OUT.exr, OUT.png and OUT.exr.ckpt.npz."""
    out = Path(output)
    image_format(out)
    exr = out.with_suffix(".exr")
    return exr, out.with_suffix(".png"), exr.with_name(exr.name + ".ckpt.npz")


def temporary_name(path) -> Path:
    """A unique hidden name beside ``path`` with the same extension (writers of one path never share it)."""
    path = Path(path)
    return path.with_name(f".{path.stem}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp{path.suffix}")


@contextmanager
def written_atomically(path, what: str = "file"):
    """``with written_atomically(path) as tmp:`` write ``tmp`` (a unique name beside ``path``, its folder
    created if needed); on success it is renamed onto ``path`` (atomic on one file system), on failure
    removed, so that a file already at ``path`` (a checkpoint of earlier passes) is never truncated. An
    ``OSError`` (a full disk) comes out as ``OutputWriteError`` naming ``path`` as the ``what``."""
    path = Path(path)
    tmp = temporary_name(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        yield tmp
        os.replace(tmp, path)
    except BaseException as exc:
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError) and not isinstance(exc, OutputWriteError):
            raise write_error(path, what, exc) from exc
        raise


def write_error(path, what: str, exc: BaseException, tmp=None) -> OutputWriteError:
    """``OutputWriteError`` for ``exc`` raised while writing ``path``: an ``OSError``'s errno and reason, or
    the system error a library's message names (OpenEXR raises RuntimeError "... No space left on
    device."), with the temporary name ``tmp`` replaced by ``path``."""
    if isinstance(exc, OSError) and exc.errno is not None:
        return OutputWriteError(path, what, exc.errno, exc.strerror or str(exc))
    text = str(exc) if tmp is None else str(exc).replace(str(tmp), str(path))
    named = [code for code in errno.errorcode if os.strerror(code) in text]
    if named:
        code = max(named, key=lambda c: len(os.strerror(c)))
        return OutputWriteError(path, what, code, os.strerror(code))
    return OutputWriteError(path, what, None, text or type(exc).__name__)


def check_writable_folder(path) -> Path:
    """Create the folder of ``path`` if needed and check that a file can be written there (ValueError
    naming the folder otherwise), before any work is done."""
    folder = Path(path).parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".weather-mi-write-test-"):
            pass
    except OSError as exc:
        raise ValueError(f"{folder}: expected a folder where the output can be written; found "
                         f"{exc.strerror or exc}") from exc
    return folder


class OutputLock:
    """``<path>.lock`` held while one render writes ``path`` (and its checkpoint): created exclusively with
    the holder's process id; a lock whose process is gone is taken over. ValueError when a live process
    holds it."""

    def __init__(self, path):
        self.lock = Path(path).with_name(Path(path).name + ".lock")
        self._held = False

    def __enter__(self) -> "OutputLock":
        for _ in range(2):
            try:
                fd = os.open(self.lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                holder = self._holder()
                if holder is None and self._young():  # being written by its holder right now
                    holder = "unknown"
                if holder == "unknown" or (holder is not None and _alive(holder)):
                    raise ValueError(f"{self.lock}: another render (process {holder}) is writing these outputs; "
                                     "wait for it or choose another -o") from None
                self.lock.unlink(missing_ok=True)  # stale: its process is gone
                continue
            with os.fdopen(fd, "w") as fh:
                fh.write(str(os.getpid()))
            self._held = True
            return self
        raise ValueError(f"{self.lock}: expected to take this lock; another process keeps recreating it")

    def __exit__(self, *exc) -> None:
        if self._held:
            self.lock.unlink(missing_ok=True)
            self._held = False

    def _young(self, seconds: float = 10.0) -> bool:
        import time
        try:
            return time.time() - self.lock.stat().st_mtime < seconds
        except OSError:
            return False

    def _holder(self) -> int | None:
        try:
            return int(self.lock.read_text().strip())
        except (OSError, ValueError):
            return None


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    except (OverflowError, ValueError):
        return False
    return True
