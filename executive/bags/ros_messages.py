"""ROS 2 messages of a bag as the plain dicts observers read, decoded only when read.

Message types come from the bag's own definitions (MCAP schemas, rosbag2's message
definitions) and, for types the bag does not define, from ``rosbags``' type store of
the bag's ROS distribution (the newest one if the bag does not say). A message
becomes a dict with the fields of its definition (arrays as lists, nested messages as
dicts); its ``stamp`` is ``header.stamp`` in seconds, as on a live ROS 2 topic.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from typing import Any

from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from executive.ros2.cdr import CdrError
from executive.ros2.cdr import Decoder as CdrDecoder
from executive.ros2.message import Decode
from knowledge.errors import BagError, BusError

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

    def decoder(self, msgtype: str) -> Decode:
        """Return a function from CDR bytes to the message as a dict (dura's own CDR
        decoder, as for live ROS 2 topics)."""
        decoder = CdrDecoder(self.typestore.fielddefs, msgtype)

        def decode(raw: bytes, caller: str) -> dict[str, Any]:
            try:
                return decoder(raw)
            except CdrError as e:
                raise BusError(f"malformed {msgtype} from {caller or '?'} ({e})") from e

        return decode
