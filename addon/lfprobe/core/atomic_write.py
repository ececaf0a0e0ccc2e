"""Files that appear whole or not at all: written to a temporary file beside the target and
renamed over it, so that an interrupted run or a reader racing the writer never sees half a
file. Every file lfprobe writes from Python goes through here; a probe set folder is swapped in
with `replace_folder`."""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from typing import IO, Iterator

_UMASK = os.umask(0)
os.umask(_UMASK)


@contextlib.contextmanager
def atomic_open(path: str, mode: str = "w", encoding: str = "utf-8") -> Iterator[IO]:
    """Opens a temporary file in `path`'s folder ("w" text or "wb" bytes); on a clean exit it is
    renamed to `path`, on an exception removed. The folder must exist."""
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_open writes whole files: mode 'w' or 'wb', not {mode!r}")
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{os.path.basename(path)}.", suffix=".tmp")
    try:
        with os.fdopen(fd, mode, encoding=None if "b" in mode else encoding) as stream:
            yield stream
        os.chmod(tmp, 0o666 & ~_UMASK)  # mkstemp makes 0600; the file is as open() would make it
        os.replace(tmp, path)
    except BaseException as error:
        if os.path.exists(tmp):
            os.remove(tmp)
        if isinstance(error, OSError) and error.filename is None and error.errno is not None:
            # A full disk shows up in write() or close() with no file named: name the target.
            raise OSError(error.errno, error.strerror, path) from error
        raise


def write_bytes(path: str, data: bytes) -> None:
    with atomic_open(path, "wb") as stream:
        stream.write(data)


def write_text(path: str, text: str) -> None:
    with atomic_open(path, "w") as stream:
        stream.write(text)


def replace_folder(staging: str, folder: str) -> None:
    """Puts the finished folder `staging` in place of `folder` (two renames, never half a
    folder: the old one is moved aside to `folder`.old first and removed last)."""
    old = folder.rstrip(os.sep) + ".old"
    shutil.rmtree(old, ignore_errors=True)
    if os.path.exists(folder):
        os.rename(folder, old)
    os.rename(staging, folder)
    shutil.rmtree(old, ignore_errors=True)
