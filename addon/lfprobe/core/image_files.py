"""Images that `compare` measures, whatever wrote them: lfprobe's own rendered EXRs (through the
native reader, exactly as before), other EXRs (RGB or RGBA, and Blender's multilayer files, of
which the Combined pass is taken) and PNG/JPEG (sRGB, decoded to linear through core/colour.py).

Every image comes back as the dict `_native.read_image` returns, with only the planes the file
has: `rgba` always (linear colour, premultiplied by alpha; alpha 1 where the file has none), and
`depth`, `normal`, `status`, `probe`, `steps`, `metadata` for lfprobe's own renders; `source`
says what the file was. The files are decoded natively, by the libraries made for them
(`_native.read_exr_channels`: OpenEXR, any compression, scanline or tiled, every part;
`_native.read_stored_image`: stb_image, PNG and JPEG at 8 or 16 bits); which layer is the colour
and the sRGB decoding are decided here.
"""

from __future__ import annotations

import os
from typing import Dict, List, Tuple

import numpy as np

from . import native
from .colour import srgb_decode
from .errors import InputError

EXR_MAGIC = b"\x76\x2f\x31\x01"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
JPEG_MAGIC = b"\xff\xd8\xff"

# What the native reader demands: a file holding all of these is lfprobe's own render. The
# analysis channels are written as passes Blender reads (status.X; Blender 3.4 drops a one-token
# name such as status: "unknown channel token"); older files carry those names and read as well.
LFPROBE_CHANNELS = ("R", "G", "B", "A", "Z", "N.X", "N.Y", "N.Z")
LFPROBE_ANALYSIS_CHANNELS = (("status.X", "status"), ("probe.X", "probe"), ("steps.X", "steps"))


def is_lfprobe_render(channel_names) -> bool:
    """Whether an EXR with these channels is lfprobe's own render (under either naming)."""
    names = set(channel_names)
    return (all(c in names for c in LFPROBE_CHANNELS)
            and all(any(c in names for c in either) for either in LFPROBE_ANALYSIS_CHANNELS))


class ImageFileError(InputError):
    """An image `compare` cannot read; the message names the file and why."""


# ---------------------------------------------------------------------------------------- EXR


def read_exr_channels(path: str) -> Tuple[Dict[str, np.ndarray], Tuple[int, int]]:
    """({channel name: (h, w) float32 array over the display window, top row first}, (w, h)) of
    any OpenEXR file; pixels of the display window outside the data window are 0."""
    _native = native.load()
    try:
        channels, size = _native.read_exr_channels(path)
    except _native.InputError as error:
        raise ImageFileError(str(error)) from error
    return dict(channels), tuple(size)


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


def _read_other_exr(path: str, channels: Dict[str, np.ndarray], size: Tuple[int, int]) -> Dict[str, object]:
    w, h = size
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


def _read_png_jpeg(path: str, is_png: bool) -> Dict[str, object]:
    """Linear premultiplied RGBA of an 8- or 16-bit PNG or a JPEG, read as sRGB: straight alpha
    (PNG's) multiplies the decoded colour, as an EXR's colour is premultiplied."""
    _native = native.load()
    try:
        codes, bits = _native.read_stored_image(path)
    except _native.InputError as error:
        raise ImageFileError(str(error)) from error
    # Kept in float64: encoding for the metrics then gives back the file's values to ~1e-16.
    values = codes.astype(np.float64) / float((1 << bits) - 1)
    if values.shape[2] in (1, 2):  # grey, grey+alpha
        values = np.concatenate([np.repeat(values[..., :1], 3, axis=2), values[..., 1:]], axis=2)
    h, w = values.shape[:2]
    rgba = np.ones((h, w, 4), dtype=np.float64)
    rgba[..., :3] = srgb_decode(values[..., :3])
    if values.shape[2] == 4:
        rgba[..., 3] = values[..., 3]
        rgba[..., :3] *= rgba[..., 3:4]
    alpha = " + alpha" if values.shape[2] == 4 else ""
    return {"rgba": rgba, "source": f"{'PNG' if is_png else 'JPEG'} {bits}-bit sRGB{alpha}"}


# ------------------------------------------------------------------------------------ any image


def read_any_image(path: str) -> Dict[str, object]:
    """The image at `path` as `_native.read_image`'s dict with the planes the file has, and
    `source` (what it was). lfprobe's own EXRs go through the native reader as before; a missing
    file raises FileNotFoundError, anything unreadable ImageFileError, each naming the file."""
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no such image: {path}")
    with open(path, "rb") as stream:
        magic = stream.read(8)
    if magic.startswith(EXR_MAGIC):
        channels, size = read_exr_channels(path)
        if is_lfprobe_render(channels):
            try:
                image = dict(native.load().read_image(path))
            except native.NativeModuleError:
                raise
            except Exception as error:  # the native reader's own error types
                raise ImageFileError(f"cannot read {path}: {error}") from error
            image["source"] = "lfprobe EXR"
            return image
        return _read_other_exr(path, channels, size)
    if magic.startswith(PNG_MAGIC) or magic.startswith(JPEG_MAGIC):
        return _read_png_jpeg(path, magic.startswith(PNG_MAGIC))
    raise ImageFileError(f"{path}: not an image compare reads (OpenEXR, PNG or JPEG, known by their "
                         "first bytes)")
