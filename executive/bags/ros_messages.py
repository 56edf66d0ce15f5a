"""ROS 2 messages of a bag as the plain dicts observers read, decoded only when read.

Message types come from the bag's own definitions (MCAP schemas, rosbag2's message
definitions) and, for types the bag does not define, from ``rosbags``' type store of
the bag's ROS distribution (the newest one if the bag does not say). A message
becomes a dict with the fields of its definition (arrays as lists, nested messages as
dicts); its ``stamp`` is ``header.stamp`` in seconds, as on a live ROS 2 topic.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np
from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from executive.bus.session import Message
from knowledge.errors import BagError, BusError

Decoder = Callable[[bytes], dict[str, Any]]
IDL_SEPARATOR = "=" * 80 + "\n"


def store_of(distro: str | None) -> Stores:
    """Return the type store of a ROS distribution (``humble``); the newest if unknown."""
    if distro:
        for store in Stores:
            if store.name == f"ROS2_{distro.upper()}":
                return store
    return Stores.LATEST


@dataclasses.dataclass(frozen=True)
class Definition:
    """A message definition found in a bag: the type's name, its format and text."""

    type: str
    format: str  # "ros2msg" or "ros2idl"
    text: str


class RosTypes:
    """The message types of one bag: its own definitions over a ``rosbags`` type store.

    Raises:
        BagError: a definition in the bag cannot be read.
    """

    def __init__(self, definitions: Iterable[Definition], distro: str | None, where: str) -> None:
        self.store = store_of(distro)
        fielddefs = dict(get_typestore(self.store).fielddefs)
        for definition in definitions:
            try:
                if definition.format == "ros2idl":
                    parts = definition.text.split(IDL_SEPARATOR)
                    idls = [p.split("\n", 1)[1] for p in parts[1:]] or [definition.text]
                    for idl in idls:
                        fielddefs.update(get_types_from_idl(idl))
                else:
                    fielddefs.update(get_types_from_msg(definition.text, definition.type))
            except Exception as e:  # rosbags' parser fails in many ways on a bad text
                raise BagError(
                    f"{where}: cannot read the definition of message type "
                    f"'{definition.type}' ({type(e).__name__}: {e})"
                ) from e
        self.typestore: Typestore = get_typestore(Stores.EMPTY)
        self.typestore.register(fielddefs)

    def knows(self, msgtype: str) -> bool:
        return msgtype in self.typestore.fielddefs

    def decoder(self, msgtype: str) -> Decoder:
        """Return a function from CDR bytes to the message as a dict."""
        deserialize = self.typestore.deserialize_cdr

        def decode(raw: bytes) -> dict[str, Any]:
            value = plain(deserialize(raw, msgtype))
            if not isinstance(value, dict):
                raise TypeError(f"{msgtype} is not a message")
            return value

        return decode


_FIELDS: dict[type, tuple[str, ...]] = {}


def plain(value: Any) -> Any:
    """Turn a deserialized ROS message (or a part of one) into JSON-like data."""
    kind = type(value)
    names = _FIELDS.get(kind)
    if names is None and dataclasses.is_dataclass(value):
        names = _FIELDS[kind] = tuple(
            f.name for f in dataclasses.fields(value) if not f.name.startswith("__")
        )
    if names is not None:
        return {name: plain(getattr(value, name)) for name in names}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, list):
        return [plain(item) for item in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


@dataclasses.dataclass
class RosMessage(Message):
    """A ROS 2 message of a bag; ``payload`` is decoded from its CDR bytes when read."""

    decoder: Decoder | None = dataclasses.field(default=None, repr=False)

    @property
    def payload(self) -> dict[str, Any]:
        if self._payload is None:
            if self.decoder is None:
                raise BusError(f"{self.key}: a ROS 2 message without its type")
            try:
                self._payload = self.decoder(self.raw)
            except Exception as e:  # a corrupt message fails in the decoder in many ways
                raise BusError(f"{self.key}: malformed ROS 2 message ({e})") from e
        return self._payload

    @property
    def stamp(self) -> float | None:
        """Return ``header.stamp`` in seconds (``stamp`` of a message without a header)."""
        payload = self.payload
        header = payload.get("header")
        stamp = header.get("stamp") if isinstance(header, dict) else payload.get("stamp")
        if isinstance(stamp, dict):
            sec, nanosec = stamp.get("sec"), stamp.get("nanosec")
            if isinstance(sec, int) and isinstance(nanosec, int):
                return sec + nanosec * 1e-9
            return None
        return float(stamp) if isinstance(stamp, (int, float)) else None
