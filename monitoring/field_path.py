"""Numbers inside JSON payloads, named by a dotted path (``pose.position.x``, ``ranges.0``)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any


def read_number(payload: Mapping[str, Any], path: str) -> float | None:
    """The number at a dotted path (list items by index); ``None`` if absent or not a number.

    Booleans count as 0 and 1, so ``exact`` checks work on flags.
    """
    value: Any = payload
    for part in path.split("."):
        if isinstance(value, Mapping):
            value = value.get(part)
        elif isinstance(value, list) and part.lstrip("-").isdigit():
            index = int(part)
            value = value[index] if -len(value) <= index < len(value) else None
        else:
            return None
    if isinstance(value, (int, float)):
        return float(value)
    return None
