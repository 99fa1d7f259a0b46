"""JSON-safe conversion shared by every result's ``to_dict()``."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["json_safe"]


def json_safe(x) -> Any:
    """Recursively convert to JSON-safe Python types: dicts (keys as str), lists, bool, int,
    float (NaN and inf become None), None and str; an object with ``to_dict()`` becomes that
    dict; anything else its ``str``.
    """
    if isinstance(x, dict):
        return {str(k): json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [json_safe(v) for v in (x.tolist() if isinstance(x, np.ndarray) else x)]
    if hasattr(x, "to_dict"):
        return json_safe(x.to_dict())
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(float(x)) else None
    if x is None or isinstance(x, str):
        return x
    return str(x)
