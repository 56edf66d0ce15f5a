"""How counts, numbers, durations and values read in dura's output, the same in every
view: ``1 fault`` and ``2 faults``, ``0.06 s`` (never ``0.05962``), ``yes``, a list as
``lidar, lidar_filter``, a mapping as ``target lab, reached yes``, a stamp as a clock."""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

DECIMALS = 2  # a measured number or a duration keeps at most this many decimals


def plural(count: int, word: str, many: str = "") -> str:
    """``1 fault``, ``2 faults``; ``many`` for words that do not take an s."""
    return f"{count} {word if count == 1 else (many or word + 's')}"


def goals_named(ids: Any) -> str:
    """Goals by their ids: ``goal 4``, ``goals 1, 3``, ``no goal``."""
    ids = list(ids or [])
    if not ids:
        return "no goal"
    return f"goal {ids[0]}" if len(ids) == 1 else f"goals {listed(ids)}"


def number(value: float) -> str:
    """A number as a person reads it: whole numbers as they are, others rounded to
    ``DECIMALS`` decimals without trailing zeros (``0.05962`` → ``0.06``)."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int) or float(value).is_integer():
        return str(int(value))
    text = f"{value:.{DECIMALS}f}".rstrip("0").rstrip(".")
    return "0" if text == "-0" else text


def seconds(value: float) -> str:
    """A duration: ``4 s``, ``0.06 s``."""
    return f"{number(value)} s"


def clock(stamp: float, *, millis: bool = False) -> str:
    """A stamp (epoch seconds) as the local time of day: ``17:52:14`` (``.463`` with
    ``millis``)."""
    text = time.strftime("%H:%M:%S", time.localtime(stamp))
    return text + f".{int(stamp % 1 * 1000):03d}" if millis else text


def listed(items: Any) -> str:
    """Names one after the other: ``lidar, lidar_filter``."""
    return ", ".join(value(i) for i in items)


def value(item: Any, key: str = "") -> str:
    """Any JSON value readably: numbers rounded, ``yes``/``no``, lists and mappings
    flat; a value whose key names a stamp (``stamp``, ``image_stamp``) as a clock."""
    if item is None:
        return "-"
    if isinstance(item, bool):
        return "yes" if item else "no"
    if isinstance(item, (int, float)):
        if key == "stamp" or key.endswith("_stamp"):
            return clock(float(item), millis=True)
        return number(item)
    if isinstance(item, Mapping):
        return pairs(item)
    if isinstance(item, (list, tuple)):
        return ", ".join(_inner(i) for i in item)
    return str(item)


def _inner(item: Any) -> str:
    """An item of a list: a nested list in parentheses, ``(robot_at dock)``."""
    if isinstance(item, (list, tuple)):
        return "(" + " ".join(_inner(i) for i in item) + ")"
    return value(item)


def pairs(data: Mapping[str, Any]) -> str:
    """A mapping on one line: ``target lab, reached yes``, a nested one in parentheses
    (``result (error_code 0)``); empty values left out."""
    shown = [(k, v) for k, v in data.items() if v not in (None, "", [], {})]
    return ", ".join(
        f"{k} ({pairs(v)})" if isinstance(v, Mapping) else f"{k} {value(v, str(k))}"
        for k, v in shown
    )
