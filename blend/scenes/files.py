"""Files written through a temporary name and a rename, and the PNG encoder for textures."""

from __future__ import annotations

import os
import struct
import tempfile
import zlib

import numpy as np


def write_atomic(path: str, data: bytes) -> None:
    """Writes `data` to a temporary file beside `path` and renames it into place, so a reader
    never sees a half-written file."""
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=folder, prefix="." + os.path.basename(path) + "-", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as stream:
            stream.write(data)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes the file private; give it a normal mode
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def png_bytes(rgb8: np.ndarray) -> bytes:
    """An (h, w, 3) uint8 image as an 8-bit RGB PNG; every row uses the 'up' filter, which
    roughly halves the size of the textures here against no filter."""
    if rgb8.dtype != np.uint8 or rgb8.ndim != 3 or rgb8.shape[2] != 3:
        raise ValueError("png: expected an (h, w, 3) uint8 image")
    h, w = rgb8.shape[:2]
    rows = rgb8.reshape(h, w * 3)
    up = rows.copy()
    up[1:] = rows[1:] - rows[:-1]  # uint8 arithmetic wraps modulo 256, as PNG's filter does
    filtered = np.empty((h, w * 3 + 1), np.uint8)
    filtered[:, 0] = 2
    filtered[:, 1:] = up
    filtered[0, 0] = 0  # the first row has no row above: no filter
    filtered[0, 1:] = rows[0]

    def chunk(tag: bytes, data: bytes) -> bytes:
        crc = zlib.crc32(tag + data) & 0xFFFFFFFF
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", crc)

    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
            + chunk(b"IDAT", zlib.compress(filtered.tobytes(), 9)) + chunk(b"IEND", b""))


def write_png(path: str, rgb8: np.ndarray) -> None:
    write_atomic(path, png_bytes(rgb8))
