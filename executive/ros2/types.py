"""The ROS 2 message types dura speaks: definitions, Cyclone DDS types and decoders.

A :class:`TypeLibrary` holds the definitions of one distribution plus a robot's own
files (see :mod:`knowledge.ros2_messages`). For each message type it builds, once,
the Cyclone DDS IDL class (an ``IdlStruct`` named as ROS 2 names its DDS types, final
and serialised as XCDR1 like ROS 2's) that DDS topics are created with and samples
written as, and the :class:`~executive.ros2.cdr.Decoder` that turns received bytes
into dicts. The ROS ``.msg`` types map onto IDL as rosidl maps them: ``byte`` is an
octet, ``char`` a uint8, ``string<=N`` a bounded string, ``T[N]`` an array, ``T[]``
and ``T[<=N]`` sequences.

Services' requests and replies travel with a header before the message, the way
rmw_cyclonedds writes them: the client's 64-bit id and the request's sequence number
(:meth:`TypeLibrary.wrapped`). Their DDS type is named as the message, with the two
header members ``guid_`` and ``seq_`` first (ROS 2 field names never end in ``_``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from cyclonedds.idl import IdlStruct, make_idl_struct
from cyclonedds.idl import types as idl
from rosbags.interfaces import Nodetype

from executive.ros2.cdr import Decoder
from executive.ros2.names import dds_type, ros_type
from knowledge.errors import ConfigError, did_you_mean
from knowledge.ros2_messages import message_store, normalize_type

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

    from knowledge.ros2_spec import Ros2Spec

_PRIMITIVES: dict[str, Any] = {
    "bool": bool, "byte": idl.byte, "char": idl.uint8, "int8": idl.int8, "uint8": idl.uint8,
    "int16": idl.int16, "uint16": idl.uint16, "int32": idl.int32, "uint32": idl.uint32,
    "int64": idl.int64, "uint64": idl.uint64, "float32": idl.float32, "float64": idl.float64,
}  # fmt: skip
# generic at run time only (their __class_getitem__ builds the IDL type)
_BOUNDED_STR: Any = idl.bounded_str
_ARRAY: Any = idl.array
_SEQUENCE: Any = idl.sequence


class TypeLibrary:
    """The message types of one ROS 2 distribution and a robot's own definitions."""

    def __init__(self, store: Typestore, distribution: str = "") -> None:
        self.store = store
        self.distribution = distribution
        self._classes: dict[str, type[IdlStruct]] = {}
        self._wrapped: dict[str, type[IdlStruct]] = {}
        self._decoders: dict[str, Decoder] = {}

    @classmethod
    def of(cls, spec: Ros2Spec) -> TypeLibrary:
        """Load the library a ``ros2:`` section names (its distribution and message files).

        Raises:
            ConfigError: an invalid message definition.
        """
        return cls(message_store(spec.distribution, spec.messages), spec.distribution)

    def knows(self, name: str) -> bool:
        return normalize_type(name) in self.store.fielddefs

    def check(self, name: str) -> str:
        """Return the normalised name of a known type.

        Raises:
            ConfigError: no such type.
        """
        found = normalize_type(name)
        if found not in self.store.fielddefs:
            raise ConfigError(
                f"unknown ROS 2 message type '{name}'{did_you_mean(found, self.store.fielddefs)}"
            )
        return found

    def of_dds(self, dds_name: str) -> str | None:
        """Return the known ROS 2 type of a DDS type name (``None``: not ROS 2's, or unknown)."""
        found = ros_type(dds_name)
        return found if found is not None and found in self.store.fielddefs else None

    def fields(self, name: str) -> list[tuple[str, tuple[Any, Any]]]:
        """Return a type's fields in rosbags' form: ``(name, (Nodetype, details))``."""
        return list(self.store.fielddefs[self.check(name)][1])

    def definition(self, name: str) -> str:
        """Return a type's full ``ros2msg`` definition, as rosbag2 writes it in a bag."""
        text: str = self.store.generate_msgdef(self.check(name), ros_version=2)[0]
        return text

    def idl(self, name: str) -> type[IdlStruct]:
        """Return the Cyclone DDS class of a type (typename ``pkg::msg::dds_::Name_``)."""
        name = self.check(name)
        found = self._classes.get(name)
        if found is None:
            annotations = {f: self._idl_field(d) for f, d in self.fields(name)}
            found = make_idl_struct(name.rpartition("/")[2] + "_", dds_type(name), annotations)
            self._classes[name] = found
        return found

    def wrapped(self, name: str) -> type[IdlStruct]:
        """Return the Cyclone DDS class of a request or reply with its header members."""
        name = self.check(name)
        found = self._wrapped.get(name)
        if found is None:
            annotations = {"guid_": idl.uint64, "seq_": idl.int64}
            annotations.update({f: self._idl_field(d) for f, d in self.fields(name)})
            found = make_idl_struct(name.rpartition("/")[2] + "_", dds_type(name), annotations)
            self._wrapped[name] = found
        return found

    def _idl_field(self, desc: tuple[Any, Any]) -> Any:
        kind, details = desc
        if kind == Nodetype.BASE:
            base, bound = details
            if base == "string":
                return _BOUNDED_STR[bound] if bound else str
            return _PRIMITIVES[base]
        if kind == Nodetype.NAME:
            return self.idl(details)
        inner, size = details
        if kind == Nodetype.ARRAY:
            return _ARRAY[self._idl_field(inner), size]
        return (
            _SEQUENCE[self._idl_field(inner), size] if size else _SEQUENCE[self._idl_field(inner)]
        )

    def decoder(self, name: str) -> Decoder:
        """Return the decoder of a type's CDR bytes into dicts."""
        name = self.check(name)
        found = self._decoders.get(name)
        if found is None:
            found = self._decoders[name] = Decoder(self.store.fielddefs, name)
        return found

    def create(self, name: str, values: Mapping[str, Any] | None = None) -> IdlStruct:
        """Make a message of a type from a dict of its fields (absent fields: zero, empty).

        Nested messages may be dicts or instances; arrays and sequences lists.

        Raises:
            ConfigError: an unknown type or field.
        """
        name = self.check(name)
        values = values or {}
        fields = self.fields(name)
        unknown = set(values) - {f for f, _ in fields}
        if unknown:
            raise ConfigError(
                f"{name} has no field '{sorted(unknown)[0]}' "
                f"(it has {', '.join(f for f, _ in fields)})"
            )
        return self.idl(name)(**{f: self._value(d, values.get(f)) for f, d in fields})

    def _value(self, desc: tuple[Any, Any], value: Any) -> Any:
        kind, details = desc
        if kind == Nodetype.BASE:
            if value is not None:
                return value
            return {"bool": False, "string": ""}.get(
                details[0], 0.0 if "float" in details[0] else 0
            )
        if kind == Nodetype.NAME:
            return value if isinstance(value, IdlStruct) else self.create(details, value)
        inner, size = details
        items = list(value) if value is not None else []
        if kind == Nodetype.ARRAY and not items:
            items = [None] * size
        return [self._value(inner, item) for item in items]
