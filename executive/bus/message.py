"""What travels on the bus: JSON objects, encoded and decoded within limits, and the
:class:`Message` a subscriber's handler gets (its payload, key, sender and times)."""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Self

from knowledge.errors import BusError

MAX_PAYLOAD = 1 << 20  # bytes: a larger message is dropped (a robot's messages are far smaller)


def encode(payload: Mapping[str, Any]) -> bytes:
    return json.dumps(payload, separators=(",", ":")).encode()


def decode(raw: bytes, key: str = "") -> dict[str, Any]:
    """A JSON object from bytes.

    Raises:
        BusError: the payload is not a JSON object, is larger than ``MAX_PAYLOAD`` or
            nested too deeply to read.
    """
    if len(raw) > MAX_PAYLOAD:
        raise BusError(f"{key}: payload of {len(raw)} bytes refused (at most {MAX_PAYLOAD})")
    try:
        value = json.loads(raw)
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise BusError(f"{key}: malformed payload (not JSON: {e})") from e
    except RecursionError:
        raise BusError(f"{key}: malformed payload (nested too deeply)") from None
    if not isinstance(value, dict):
        raise BusError(f"{key}: malformed payload (a JSON {type(value).__name__}, not an object)")
    return value


@dataclass
class Message:
    """One received message: what a ``subscribe`` handler gets.

    ``payload`` is the published dict, decoded on first use (hot paths skip it);
    ``message["celsius"]`` and ``message.get("celsius")`` read a field of it. ``key`` is
    the key it came on, ``caller_id`` who sent it, ``stamp`` the payload's ``stamp``;
    ``sent`` and ``received`` are seconds since the epoch, ``sent_ns`` and
    ``received_ns`` the same in integer nanoseconds (exact: compare and subtract those).
    """

    key: str
    raw: bytes
    caller_id: str = ""
    sent: float | None = None
    received: float = 0.0
    _payload: dict[str, Any] | None = field(default=None, repr=False)
    # the times in exact ns where the source had them (see at_ns)
    _sent_ns: int | None = field(default=None, kw_only=True, repr=False, compare=False)
    _received_ns: int | None = field(default=None, kw_only=True, repr=False, compare=False)

    @classmethod
    def at_ns(
        cls,
        key: str,
        raw: bytes,
        caller_id: str,
        sent_ns: int | None,
        received_ns: int,
        **fields: Any,
    ) -> Self:
        """A message whose times are integer nanoseconds since the epoch, kept exact
        (``sent`` and ``received`` are their seconds, rounded to a float)."""
        sent = None if sent_ns is None else sent_ns / 1e9
        return cls(key, raw, caller_id, sent, received_ns / 1e9, _sent_ns=sent_ns,
                   _received_ns=received_ns, **fields)  # fmt: skip

    @property
    def received_ns(self) -> int:
        """When it was received, in integer nanoseconds since the epoch (exact where
        the source had nanoseconds: DDS, a bag, a recording)."""
        found = self._received_ns
        return round(self.received * 1e9) if found is None else found

    @property
    def sent_ns(self) -> int | None:
        """When it was sent, in integer nanoseconds since the epoch (``None``: unknown)."""
        if self._sent_ns is not None:
            return self._sent_ns
        return None if self.sent is None else round(self.sent * 1e9)

    @property
    def payload(self) -> dict[str, Any]:
        if self._payload is None:
            self._payload = decode(self.raw, self.key)
        return self._payload

    def __getitem__(self, field: str) -> Any:
        """A field of the payload (``message["celsius"]``).

        Raises:
            KeyError: the payload has no such field (the message names those it has).
        """
        try:
            return self.payload[field]
        except KeyError:
            has = ", ".join(sorted(self.payload)) or "none"
            raise KeyError(
                f"the message on {self.key} has no field {field!r} (it has: {has})"
            ) from None

    def get(self, field: str, default: Any = None) -> Any:
        """A field of the payload, or ``default``."""
        return self.payload.get(field, default)

    @property
    def stamp(self) -> float | None:
        """The ``stamp`` field of the payload, if it is a number."""
        value = self.payload.get("stamp")
        return float(value) if isinstance(value, (int, float)) else None

    @property
    def stamp_ns(self) -> int | None:
        """``stamp`` in integer nanoseconds since the epoch (exact where the stamp is:
        a ROS 2 header's)."""
        stamp = self.stamp
        return None if stamp is None else round(stamp * 1e9)
