"""Values made fit for strict JSON, which every reader parses: lfprobe writes no NaN or
Infinity (the PSNR of identical images is infinite: it is written as null)."""

from __future__ import annotations

import math


def strict_json(value):
    """Non-finite floats become null (JSON has no inf/NaN); numpy scalars become Python ones."""
    if hasattr(value, "item") and not isinstance(value, (list, dict, str)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {str(k): strict_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [strict_json(v) for v in value]
    return value
