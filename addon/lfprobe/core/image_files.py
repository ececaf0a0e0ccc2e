"""Images that `compare` measures, whatever wrote them: lfprobe's own rendered EXRs (through the
native reader, exactly as before), other EXRs (RGB or RGBA, and Blender's multilayer files, of
which the Combined pass is taken) and PNG/JPEG (sRGB, decoded to linear through core/colour.py).

Every image comes back as the dict `_native.read_image` returns, with only the planes the file
has: `rgba` always (linear colour, premultiplied by alpha; alpha 1 where the file has none), and
`depth`, `normal`, `status`, `probe`, `steps`, `metadata` for lfprobe's own renders; `source`
says what the file was. The EXR reader is plain numpy and zlib, so that the command line and
the add-on inside any Blender read the same pixels without a library to install: the native
reader accepts only lfprobe's own layout. It reads scanline files, single- or multi-part, with
the lossless codecs Blender writes by default and by choice (NONE, RLE, ZIPS, ZIP); any other
codec (PIZ, PXR24, B44, DWA) is refused with a message naming the file and the codec.
"""

from __future__ import annotations

import os
import struct
import zlib
from typing import Dict, List, Optional, Tuple

import numpy as np

from . import native
from .colour import srgb_decode
from .errors import InputError

EXR_MAGIC = b"\x76\x2f\x31\x01"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
JPEG_MAGIC = b"\xff\xd8\xff"

# What the native reader demands: a file holding all of these is lfprobe's own render.
LFPROBE_CHANNELS = ("R", "G", "B", "A", "Z", "N.X", "N.Y", "N.Z", "status", "probe", "steps")

_TILED, _LONG_NAMES, _DEEP, _MULTIPART = 0x200, 0x400, 0x800, 0x1000
_PIXEL_TYPES = {0: np.dtype("<u4"), 1: np.dtype("<f2"), 2: np.dtype("<f4")}
_CODECS = {0: "NONE", 1: "RLE", 2: "ZIPS", 3: "ZIP", 4: "PIZ", 5: "PXR24", 6: "B44", 7: "B44A",
           8: "DWAA", 9: "DWAB"}
_LINES_PER_CHUNK = {0: 1, 1: 1, 2: 1, 3: 16}  # the codecs read here


class ImageFileError(InputError):
    """An image `compare` cannot read; the message names the file and why."""


# ---------------------------------------------------------------------------------------- EXR


def _exr_headers(data: bytes, path: str) -> Tuple[List[Dict[str, Tuple[str, bytes]]], int, bool]:
    """(each part's attributes {name: (type, value bytes)}, position after the headers, multi-part)."""
    flags = struct.unpack_from("<I", data, 4)[0]
    if flags & _TILED:
        raise ImageFileError(f"{path}: tiled EXR files are not read (save it as scanlines)")
    if flags & _DEEP:
        raise ImageFileError(f"{path}: deep EXR files are not read")
    multipart = bool(flags & _MULTIPART)
    headers, pos = [], 8
    while True:
        attrs = {}
        while data[pos] != 0:
            end = data.index(b"\0", pos)
            name = data[pos:end].decode("latin-1")
            end_type = data.index(b"\0", end + 1)
            type_name = data[end + 1:end_type].decode("latin-1")
            (size,) = struct.unpack_from("<i", data, end_type + 1)
            start = end_type + 5
            if size < 0 or start + size > len(data):
                raise ImageFileError(f"{path}: EXR header attribute '{name}' runs past the end of the file")
            attrs[name] = (type_name, data[start:start + size])
            pos = start + size
        pos += 1
        headers.append(attrs)
        if not multipart or data[pos] == 0:
            pos += 1 if multipart else 0
            return headers, pos, multipart


def _exr_channels(raw: bytes, path: str) -> List[Tuple[str, np.dtype]]:
    """The channel list (name, little-endian dtype) in file order (sorted by name, as stored)."""
    out, pos = [], 0
    while raw[pos] != 0:
        end = raw.index(b"\0", pos)
        name = raw[pos:end].decode("utf-8", "replace")
        pixel_type, _linear, x_sampling, y_sampling = struct.unpack_from("<iB3xii", raw, end + 1)
        if pixel_type not in _PIXEL_TYPES:
            raise ImageFileError(f"{path}: channel '{name}' has unknown pixel type {pixel_type}")
        if (x_sampling, y_sampling) != (1, 1):
            raise ImageFileError(f"{path}: channel '{name}' is subsampled, which is not read")
        out.append((name, _PIXEL_TYPES[pixel_type]))
        pos = end + 1 + 16
    return out


def _undo_predictor_and_interleave(raw: bytes) -> bytes:
    """ZIP and RLE store each byte as the difference from the one before (+128) after splitting
    the even- and odd-indexed bytes into two halves; this undoes both."""
    d = np.frombuffer(raw, dtype=np.uint8)
    if d.size == 0:
        return raw
    deltas = d.astype(np.int64)
    deltas[1:] -= 128
    t = (np.cumsum(deltas) & 0xFF).astype(np.uint8)
    out = np.empty_like(t)
    half = (t.size + 1) // 2
    out[0::2], out[1::2] = t[:half], t[half:]
    return out.tobytes()


def _rle_decode(raw: bytes, expected: int) -> bytes:
    """OpenEXR's run-length code: a signed count byte, -n: n bytes as they are, n: n+1 copies."""
    out = bytearray()
    pos = 0
    while pos < len(raw) and len(out) < expected:
        count = raw[pos] - 256 if raw[pos] > 127 else raw[pos]
        pos += 1
        if count < 0:
            out += raw[pos:pos - count]
            pos -= count
        else:
            out += raw[pos:pos + 1] * (count + 1)
            pos += 1
    return bytes(out)


def _decode_chunk(payload: bytes, codec: int, expected: int, path: str) -> bytes:
    if len(payload) == expected:  # OpenEXR stores a chunk raw when compressing would not shrink it
        return payload
    try:
        if codec in (2, 3):
            raw = zlib.decompress(payload)
        elif codec == 1:
            raw = _rle_decode(payload, expected)
        else:
            raw = payload
    except zlib.error as error:
        raise ImageFileError(f"{path}: a compressed EXR block is damaged ({error})") from error
    if codec in (1, 2, 3):
        raw = _undo_predictor_and_interleave(raw)
    if len(raw) != expected:
        raise ImageFileError(f"{path}: an EXR block holds {len(raw)} bytes where {expected} were expected")
    return raw


def read_exr_channels(path: str, data: Optional[bytes] = None) -> Tuple[Dict[str, np.ndarray], Tuple[int, int]]:
    """({channel name: (h, w) float32 array over the display window, top row first}, (w, h)) of a
    scanline EXR; pixels of the display window outside the data window are 0."""
    if data is None:
        with open(path, "rb") as stream:
            data = stream.read()
    try:
        return _read_exr_channels(path, data)
    except ImageFileError:
        raise
    except (IndexError, ValueError, struct.error, KeyError) as error:
        raise ImageFileError(f"{path}: not a readable EXR file (truncated or damaged: {error})") from error


def _read_exr_channels(path: str, data: bytes) -> Tuple[Dict[str, np.ndarray], Tuple[int, int]]:
    headers, pos, multipart = _exr_headers(data, path)
    parts = []
    for attrs in headers:
        if attrs.get("type", ("", b""))[1].rstrip(b"\0") not in (b"", b"scanlineimage"):
            raise ImageFileError(f"{path}: EXR part of type {attrs['type'][1]!r} is not read (scanline images only)")
        codec = attrs["compression"][1][0]
        if codec not in _LINES_PER_CHUNK:
            raise ImageFileError(
                f"{path}: EXR compression {_CODECS.get(codec, codec)} is not read; save the image with "
                "codec ZIP, ZIPS, RLE or none (lossless, what Blender writes by default)")
        window = struct.unpack("<iiii", attrs["dataWindow"][1])
        display = struct.unpack("<iiii", attrs["displayWindow"][1])
        parts.append((codec, window, display, _exr_channels(attrs["channels"][1], path)))
    display = parts[0][2]
    full_w, full_h = display[2] - display[0] + 1, display[3] - display[1] + 1
    if full_w < 1 or full_h < 1:
        raise ImageFileError(f"{path}: EXR display window is empty")
    arrays: Dict[str, np.ndarray] = {}
    for index, (codec, (x0, y0, x1, y1), _display, channels) in enumerate(parts):
        width, height = x1 - x0 + 1, y1 - y0 + 1
        lines = _LINES_PER_CHUNK[codec]
        chunks = -(-height // lines) if width > 0 and height > 0 else 0
        offsets = np.frombuffer(data, dtype="<u8", count=chunks, offset=pos)
        pos += 8 * chunks
        planes = {name: np.zeros((max(height, 0), max(width, 0)), dtype=dtype) for name, dtype in channels}
        row_bytes = sum(width * dtype.itemsize for _name, dtype in channels)
        for offset in offsets:
            cursor = int(offset)
            if multipart:
                (part,) = struct.unpack_from("<i", data, cursor)
                if part != index:
                    raise ImageFileError(f"{path}: EXR chunk of part {part} listed under part {index}")
                cursor += 4
            y, size = struct.unpack_from("<ii", data, cursor)
            cursor += 8
            first = y - y0
            count = min(lines, height - first)
            if first < 0 or count < 1 or size < 0 or cursor + size > len(data):
                raise ImageFileError(f"{path}: EXR block at line {y} lies outside the image or the file")
            raw = _decode_chunk(data[cursor:cursor + size], codec, row_bytes * count, path)
            at = 0
            for row in range(first, first + count):
                for name, dtype in channels:
                    n = width * dtype.itemsize
                    planes[name][row] = np.frombuffer(raw, dtype=dtype, count=width, offset=at)
                    at += n
        for name, plane in planes.items():
            canvas = np.zeros((full_h, full_w), dtype=np.float32)
            # The data window's part inside the display window; the rest stays 0.
            dx0, dy0 = x0 - display[0], y0 - display[1]
            sx0, sy0 = max(0, -dx0), max(0, -dy0)
            ex, ey = min(width, full_w - dx0), min(height, full_h - dy0)
            if ex > sx0 and ey > sy0:
                canvas[dy0 + sy0:dy0 + ey, dx0 + sx0:dx0 + ex] = plane[sy0:ey, sx0:ex].astype(np.float32)
            arrays[name] = canvas
    return arrays, (full_w, full_h)


def colour_layer(names: List[str], path: str) -> str:
    """The layer prefix ("" for plain R, G, B) whose R, G and B are the image's colour: plain RGB
    first, else the Combined pass of a Blender multilayer file (`ViewLayer.Combined.R`), else the
    only layer with R, G and B. InputError listing the layers when that does not decide."""
    layers = sorted({name.rsplit(".", 1)[0] if "." in name else "" for name in names
                     if name.rsplit(".", 1)[-1] == "R"})
    with_rgb = [layer for layer in layers
                if all((f"{layer}.{c}" if layer else c) in names for c in ("G", "B"))]
    if "" in with_rgb:
        return ""
    combined = [layer for layer in with_rgb if layer.rsplit(".", 1)[-1] == "Combined"]
    if len(combined) == 1:
        return combined[0]
    if len(with_rgb) == 1:
        return with_rgb[0]
    if not with_rgb:
        raise ImageFileError(f"{path}: the EXR has no R, G, B channels (channels: {', '.join(sorted(names)[:12])})")
    choices = combined or with_rgb
    raise ImageFileError(f"{path}: the EXR has several colour layers ({', '.join(choices)}); "
                         "save the one to compare on its own")


def _read_other_exr(path: str, data: bytes) -> Dict[str, object]:
    channels, (w, h) = read_exr_channels(path, data)
    layer = colour_layer(list(channels), path)
    prefix = f"{layer}." if layer else ""
    rgba = np.empty((h, w, 4), dtype=np.float32)
    for i, c in enumerate("RGB"):
        rgba[..., i] = channels[prefix + c]
    alpha = channels.get(prefix + "A")
    rgba[..., 3] = 1.0 if alpha is None else alpha
    kind = "EXR " + ("RGBA" if alpha is not None else "RGB")
    return {"rgba": rgba, "source": f"{kind}, layer {layer}" if layer else kind}


# ---------------------------------------------------------------------------------- PNG, JPEG


def _png_16bit(data: bytes, path: str) -> Optional[np.ndarray]:
    """(h, w, c) uint16 of a non-interlaced 16-bit grey, grey+alpha, RGB or RGBA PNG, or None for
    any other PNG (Pillow reads those; it would cut 16-bit colour to 8 bits)."""
    (width, height, depth, colour_type, _cm, _fm, interlace) = struct.unpack_from(">IIBBBBB", data, 16)
    channels = {0: 1, 4: 2, 2: 3, 6: 4}.get(colour_type)
    if depth != 16 or channels is None or interlace != 0:
        return None
    pos, idat = 8, []
    while pos + 8 <= len(data):
        length, tag = struct.unpack_from(">I4s", data, pos)
        if tag == b"IDAT":
            idat.append(data[pos + 8:pos + 8 + length])
        elif tag == b"IEND":
            break
        pos += 12 + length
    try:
        raw = np.frombuffer(zlib.decompress(b"".join(idat)), dtype=np.uint8)
    except zlib.error as error:
        raise ImageFileError(f"{path}: the PNG's image data is damaged ({error})") from error
    bpp, stride = 2 * channels, 2 * channels * width
    if raw.size != height * (stride + 1):
        raise ImageFileError(f"{path}: the PNG holds {raw.size} bytes of image data, {height * (stride + 1)} expected")
    rows = raw.reshape(height, stride + 1)
    out = np.zeros((height, stride), dtype=np.uint8)
    previous = np.zeros(stride, dtype=np.int64)
    for y in range(height):
        kind, line = rows[y, 0], rows[y, 1:].astype(np.int64)
        if kind == 0:
            cur = line
        elif kind == 2:  # Up
            cur = (line + previous) & 0xFF
        elif kind == 1:  # Sub: a running sum per byte position within the pixel
            cur = (np.cumsum(line.reshape(width, bpp), axis=0) & 0xFF).ravel()
        elif kind in (3, 4):  # Average, Paeth: each byte depends on the one decoded left of it
            cur = np.zeros(stride, dtype=np.int64)
            left, up_left = np.zeros(bpp, np.int64), np.zeros(bpp, np.int64)
            for x in range(0, stride, bpp):
                up = previous[x:x + bpp]
                if kind == 3:
                    value = (line[x:x + bpp] + (left + up) // 2) & 0xFF
                else:
                    p = left + up - up_left
                    pa, pb, pc = np.abs(p - left), np.abs(p - up), np.abs(p - up_left)
                    predictor = np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, up, up_left))
                    value = (line[x:x + bpp] + predictor) & 0xFF
                cur[x:x + bpp] = value
                left, up_left = value, up
        else:
            raise ImageFileError(f"{path}: the PNG uses unknown row filter {kind}")
        out[y] = cur
        previous = cur
    return out.view(">u2").reshape(height, width, channels)


def _read_png_jpeg(path: str, data: bytes) -> Dict[str, object]:
    """Linear premultiplied RGBA of an 8- or 16-bit PNG or a JPEG, read as sRGB: straight alpha
    (PNG's) multiplies the decoded colour, as an EXR's colour is premultiplied."""
    is_png = data.startswith(PNG_MAGIC)
    pixels = _png_16bit(data, path) if is_png else None
    if pixels is not None:
        values, bits = pixels.astype(np.float64) / 65535.0, 16
    else:
        try:
            from PIL import Image  # Debian's python3-pil, which python3-skimage depends on
        except ImportError as error:
            raise ImageFileError(f"{path}: reading 8-bit PNG and JPEG needs Pillow "
                                 "(apt-get install python3-pil)") from error
        try:
            with Image.open(path) as image:
                image.load()
                mode = "RGBA" if ("A" in image.getbands() or "transparency" in image.info) else "RGB"
                values, bits = np.asarray(image.convert(mode), dtype=np.float64) / 255.0, 8
        except (OSError, ValueError, SyntaxError) as error:
            raise ImageFileError(f"{path}: not a readable {'PNG' if is_png else 'JPEG'} ({error})") from error
    if values.ndim == 2:
        values = values[..., None]
    if values.shape[2] in (1, 2):  # grey, grey+alpha
        values = np.concatenate([np.repeat(values[..., :1], 3, axis=2), values[..., 1:]], axis=2)
    h, w = values.shape[:2]
    rgba = np.ones((h, w, 4), dtype=np.float64)
    rgba[..., :3] = srgb_decode(values[..., :3])
    if values.shape[2] == 4:
        rgba[..., 3] = values[..., 3]
        rgba[..., :3] *= rgba[..., 3:4]
    alpha = "A" if values.shape[2] == 4 else ""
    kind = f"{'PNG' if is_png else 'JPEG'} {bits}-bit sRGB{' + alpha' if alpha else ''}"
    # Kept in float64: encoding for the metrics then gives back the file's values to ~1e-16.
    return {"rgba": rgba, "source": kind}


# ------------------------------------------------------------------------------------ any image


def read_any_image(path: str) -> Dict[str, object]:
    """The image at `path` as `_native.read_image`'s dict with the planes the file has, and
    `source` (what it was). lfprobe's own EXRs go through the native reader as before; a missing
    file raises FileNotFoundError, anything unreadable ImageFileError, each naming the file."""
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no such image: {path}")
    with open(path, "rb") as stream:
        data = stream.read()
    if data.startswith(EXR_MAGIC):
        try:
            headers, _pos, _multipart = _exr_headers(data, path)
            names = {n for attrs in headers for n, _t in _exr_channels(attrs["channels"][1], path)}
        except ImageFileError:
            raise
        except (IndexError, ValueError, struct.error, KeyError) as error:
            raise ImageFileError(f"{path}: not a readable EXR file (truncated or damaged header: {error})") from error
        if all(c in names for c in LFPROBE_CHANNELS):
            try:
                image = dict(native.load().read_image(path))
            except native.NativeModuleError:
                raise
            except Exception as error:  # the native reader's own error types
                raise ImageFileError(f"cannot read {path}: {error}") from error
            image["source"] = "lfprobe EXR"
            return image
        return _read_other_exr(path, data)
    if data.startswith(PNG_MAGIC) or data.startswith(JPEG_MAGIC):
        return _read_png_jpeg(path, data)
    raise ImageFileError(f"{path}: not an image compare reads (OpenEXR, PNG or JPEG, known by their "
                         "first bytes)")
