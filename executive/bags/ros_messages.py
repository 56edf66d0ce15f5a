"""ROS 2 messages of a bag as the plain dicts observers read, decoded only when read.

Message types come from the bag's own definitions (MCAP schemas, rosbag2's message
definitions) and, for types the bag does not define, from ``rosbags``' type store of
the bag's ROS distribution (the newest one if the bag does not say). A message
becomes a dict with the fields of its definition (arrays as lists, nested messages as
dicts); its ``stamp`` is ``header.stamp`` in seconds, as on a live ROS 2 topic.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable, Mapping
from typing import Any

from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from executive.ros2.cdr import CdrError
from executive.ros2.cdr import Decoder as CdrDecoder
from executive.ros2.message import Decode
from knowledge.errors import BusError

IDL_SEPARATOR = "=" * 80 + "\n"
EMPTY_MEMBER = "structure_needs_at_least_one_member"  # what ROS 2 puts in an empty message


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
    """The message types of one bag: its own definitions over ``extra`` types (the
    user's ``--types``) over a ``rosbags`` type store.

    A definition that cannot be read makes only its type unknown: each unknown type is
    a one-line reason (:meth:`missing`), and its messages fail only where decoded.
    """

    def __init__(
        self,
        definitions: Iterable[Definition],
        distro: str | None,
        extra: Mapping[str, Any] | None = None,
    ) -> None:
        self.store = store_of(distro)
        fielddefs = dict(get_typestore(self.store).fielddefs)
        fielddefs.update(extra or {})
        self._broken: dict[str, str] = {}
        for definition in definitions:
            try:
                fielddefs.update(_parse(definition))
            except Exception as e:  # rosbags' parser fails in many ways on a bad text
                first = (str(e).strip().splitlines() or [""])[0]
                self._broken[definition.type] = (
                    f"its definition in the bag cannot be read ({type(e).__name__}: {first})"
                )
        self.typestore: Typestore = get_typestore(Stores.EMPTY)
        self.typestore.register(fielddefs)

    def name(self, msgtype: str) -> str:
        """Return the type's name as the store knows it (old bags drop the ``msg/``)."""
        if msgtype not in self.typestore.fielddefs and msgtype.count("/") == 1:
            package, name = msgtype.split("/")
            return f"{package}/msg/{name}"
        return msgtype

    def knows(self, msgtype: str) -> bool:
        return self.missing(msgtype) is None

    def missing(self, msgtype: str) -> str | None:
        """Return why a type cannot be decoded (None: it can)."""
        if msgtype in self._broken:
            return self._broken[msgtype]
        if msgtype in self.typestore.fielddefs:
            return None
        return (
            f"its type '{msgtype or '?'}' is unknown (the bag does not define it, rosbags' "
            f"{self.store.name.lower()} types do not know it; --types DIR reads .msg files)"
        )

    def decoder(self, msgtype: str, on_unknown: Callable[[str], None]) -> Decode:
        """Return a function from CDR bytes to the message as a dict (dura's own CDR
        decoder, as for live ROS 2 topics); for a type that cannot be decoded, one that
        calls ``on_unknown`` with the reason and raises :class:`BusError`."""
        msgtype = self.name(msgtype)
        reason = self.missing(msgtype)
        if reason is None:
            try:
                decoder = CdrDecoder(self.typestore.fielddefs, msgtype)
            except Exception as e:  # a definition naming a type nobody defines
                reason = f"its type '{msgtype}' cannot be decoded ({type(e).__name__}: {e})"
        if reason is not None:
            return self.undecodable(reason, on_unknown)

        def decode(raw: bytes, caller: str) -> dict[str, Any]:
            try:
                return decoder(raw)
            except CdrError as e:
                raise BusError(f"malformed {msgtype} from {caller or '?'} ({e})") from e

        return decode

    @staticmethod
    def undecodable(why: str, on_unknown: Callable[[str], None]) -> Decode:
        """Return a decoder that calls ``on_unknown`` with ``why`` and fails."""

        def unknown(raw: bytes, caller: str) -> dict[str, Any]:
            on_unknown(why)
            raise BusError(f"cannot decode a message from {caller or '?'}: {why}")

        return unknown


def _parse(definition: Definition) -> dict[str, Any]:
    """Return the field definitions of a bag's message definition (and its dependencies)."""
    if definition.format == "ros2idl":
        parts = definition.text.split(IDL_SEPARATOR)
        idls = [p.split("\n", 1)[1] for p in parts[1:]] or [definition.text]
        found: dict[str, Any] = {}
        for idl in idls:
            found.update(get_types_from_idl(idl))
        return found
    found = dict(get_types_from_msg(definition.text, definition.type))
    if found.get(definition.type) == ([], []):  # no fields: ROS 2 serialises one byte
        found[definition.type] = ([], [(EMPTY_MEMBER, (Nodetype.BASE, ("uint8", 0)))])
    return found
