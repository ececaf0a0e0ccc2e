"""Reads the channels of an uncompressed scanline OpenEXR file (what Blender writes with codec
NONE: single-part in 3.4, multi-part in 5.0) into numpy arrays, so that tests can look at
every render pass of a multilayer EXR; writes such a file with any channel names."""

from __future__ import annotations

import struct

import numpy as np

_PIXEL_TYPES = {0: np.uint32, 1: np.float16, 2: np.float32}
_MULTIPART = 0x1000
_TILED = 0x200


def _read_header(data: bytes, pos: int):
    """One header's attributes {name: (type, bytes)} and the position after its end byte."""
    attrs = {}
    while data[pos] != 0:
        end = data.index(b"\0", pos)
        name = data[pos:end].decode()
        end_type = data.index(b"\0", end + 1)
        type_name = data[end + 1:end_type].decode()
        size = struct.unpack_from("<i", data, end_type + 1)[0]
        attrs[name] = (type_name, data[end_type + 5:end_type + 5 + size])
        pos = end_type + 5 + size
    return attrs, pos + 1


def _channels(raw: bytes):
    out, pos = [], 0
    while raw[pos] != 0:
        end = raw.index(b"\0", pos)
        name = raw[pos:end].decode()
        pixel_type, _linear, x_sampling, y_sampling = struct.unpack_from("<iB3xii", raw, end + 1)
        if (x_sampling, y_sampling) != (1, 1):
            raise ValueError(f"channel {name}: subsampled channels are not read here")
        out.append((name, _PIXEL_TYPES[pixel_type]))
        pos = end + 1 + 16
    return out


def read_exr_channels(path: str) -> dict:
    """{channel name: (h, w) array, top row first} of an uncompressed scanline EXR."""
    with open(path, "rb") as stream:
        data = stream.read()
    if data[:4] != b"\x76\x2f\x31\x01":
        raise ValueError(f"{path}: not an OpenEXR file")
    flags = struct.unpack_from("<I", data, 4)[0]
    if flags & _TILED:
        raise ValueError(f"{path}: tiled EXR files are not read here")
    multipart = bool(flags & _MULTIPART)
    headers, pos = [], 8
    while True:
        attrs, pos = _read_header(data, pos)
        headers.append(attrs)
        if not multipart or data[pos] == 0:
            pos += 1 if multipart else 0
            break
    parts = []
    for attrs in headers:
        if attrs["compression"][1][0] != 0:
            raise ValueError(f"{path}: only uncompressed EXR (codec NONE) is read here")
        xmin, ymin, xmax, ymax = struct.unpack("<iiii", attrs["dataWindow"][1])
        parts.append((xmax - xmin + 1, ymax - ymin + 1, ymin, _channels(attrs["channels"][1])))
    arrays = {}
    for width, height, ymin, channels in parts:
        for name, dtype in channels:
            arrays[name] = np.empty((height, width), dtype=dtype)
    for width, height, ymin, channels in parts:
        offsets = np.frombuffer(data, dtype="<u8", count=height, offset=pos)
        pos += 8 * height
        for offset in offsets:
            cursor = int(offset) + (4 if multipart else 0)  # multi-part chunks start with the part number
            y = struct.unpack_from("<i", data, cursor)[0] - ymin
            cursor += 8
            for name, dtype in channels:
                arrays[name][y] = np.frombuffer(data, dtype=np.dtype(dtype).newbyteorder("<"), count=width,
                                                offset=cursor)
                cursor += width * np.dtype(dtype).itemsize
    return arrays


def write_exr_channels(path: str, channels: dict) -> None:
    """Writes {channel name: (h, w) float32 array, top row first} as an uncompressed single-part
    scanline EXR: a file with whatever channel names a test needs (files other writers made,
    or lfprobe wrote before)."""
    names = sorted(channels)  # the channel list and each scanline hold channels by name
    height, width = np.asarray(channels[names[0]]).shape
    planes = [np.ascontiguousarray(channels[name], dtype="<f4") for name in names]

    def attribute(name: str, type_name: str, value: bytes) -> bytes:
        return name.encode() + b"\0" + type_name.encode() + b"\0" + struct.pack("<i", len(value)) + value

    chlist = b"".join(name.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for name in names) + b"\0"
    window = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = b"".join([
        attribute("channels", "chlist", chlist),
        attribute("compression", "compression", b"\0"),
        attribute("dataWindow", "box2i", window),
        attribute("displayWindow", "box2i", window),
        attribute("lineOrder", "lineOrder", b"\0"),
        attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0)),
        attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0)),
        attribute("screenWindowWidth", "float", struct.pack("<f", 1.0)),
    ]) + b"\0"
    start = 8 + len(header) + 8 * height
    line_bytes = 8 + 4 * width * len(names)
    offsets = struct.pack(f"<{height}Q", *(start + y * line_bytes for y in range(height)))
    lines = b"".join(struct.pack("<ii", y, 4 * width * len(names)) + b"".join(p[y].tobytes() for p in planes)
                     for y in range(height))
    with open(path, "wb") as stream:
        stream.write(b"\x76\x2f\x31\x01" + struct.pack("<I", 2) + header + offsets + lines)
