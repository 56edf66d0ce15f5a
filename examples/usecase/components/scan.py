"""The laser scan payload of ``scan`` and ``scan_filtered``."""

from __future__ import annotations

import math
from typing import Any

BEAMS = 36
RANGE_MIN = 0.1
RANGE_MAX = 10.0
OUT_OF_RANGE = -1.0  # what a faulty sensor reports: a negative distance


def scan(seq: int, ranges: list[float], stamp: float | None = None) -> dict[str, Any]:
    """A scan over a half circle in front of the robot."""
    payload: dict[str, Any] = {
        "seq": seq,
        "frame": "laser",
        "angle_min": -math.pi / 2,
        "angle_increment": math.pi / (BEAMS - 1),
        "range_min": RANGE_MIN,
        "range_max": RANGE_MAX,
        "ranges": ranges,
    }
    if stamp is not None:
        payload["stamp"] = stamp
    return payload


def clip(value: float) -> float:
    return min(RANGE_MAX, max(RANGE_MIN, value))
