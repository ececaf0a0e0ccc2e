"""Colour encodings, defined once: the sRGB curve (metrics, PNG previews, the viewport texture
and the scan points drawn in the viewport all encode through `srgb_encode`; compare decodes
PNG and JPEG through `srgb_decode`) and the magma map of error images."""

from __future__ import annotations

import numpy as np


def srgb_encode(linear: np.ndarray, dtype=np.float64) -> np.ndarray:
    """Linear colour → sRGB-encoded colour in [0, 1]: clamp to [0, 1] (NaN → 0), then the sRGB
    curve 12.92·c below 0.0031308 and 1.055·c^(1/2.4) − 0.055 above, computed in `dtype`
    (float32 for what is drawn, float64 for what is measured)."""
    c = np.clip(np.nan_to_num(np.asarray(linear, dtype=dtype), nan=0.0), 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def srgb_decode(encoded: np.ndarray, dtype=np.float64) -> np.ndarray:
    """sRGB-encoded colour in [0, 1] → linear, the inverse of `srgb_encode`: clamp to [0, 1]
    (NaN → 0), then c/12.92 up to 0.04045 and ((c + 0.055)/1.055)^2.4 above (PNG and JPEG
    images that compare reads are sRGB)."""
    c = np.clip(np.nan_to_num(np.asarray(encoded, dtype=dtype), nan=0.0), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, np.power((c + 0.055) / 1.055, 2.4))


def srgb8(linear_rgb: np.ndarray) -> np.ndarray:
    """Linear RGB → 8-bit sRGB (rounded), for PNG previews."""
    return (srgb_encode(linear_rgb) * 255.0 + 0.5).astype(np.uint8)


def srgb_display_rgba(rgba: np.ndarray) -> np.ndarray:
    """Linear premultiplied RGBA → float32 RGBA with sRGB-encoded colour and alpha clamped to
    [0, 1]: what a display texture holds when no view transform is applied to it."""
    out = np.empty(np.shape(rgba), dtype=np.float32)
    out[..., :3] = srgb_encode(rgba[..., :3], dtype=np.float32)
    out[..., 3] = np.clip(rgba[..., 3], 0.0, 1.0)
    return out


def magma8(values: np.ndarray) -> np.ndarray:
    """Values in [0, 1] (NaN → 0, others clamped) → (…, 3) uint8 RGB through matplotlib's magma
    map; a grey ramp when matplotlib is missing."""
    v = np.clip(np.nan_to_num(np.asarray(values, dtype=np.float64), nan=0.0), 0.0, 1.0)
    try:
        import matplotlib

        lut = (matplotlib.colormaps["magma"](np.linspace(0.0, 1.0, 256))[:, :3] * 255.0 + 0.5).astype(np.uint8)
    except (ImportError, KeyError, AttributeError):
        lut = np.repeat(np.arange(256, dtype=np.uint8)[:, None], 3, axis=1)
    return lut[(v * 255.0 + 0.5).astype(np.int64)]
