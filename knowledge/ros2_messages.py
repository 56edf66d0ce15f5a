"""ROS 2 message definitions: a distribution's standard messages and a robot's own files.

The standard messages of each ROS 2 distribution come from ``rosbags``' type stores,
with the services dura calls itself (lifecycle, action cancellation) and the standard
``std_srvs`` added from the definitions bundled in ``knowledge/ros2_interfaces/``.
A robot may add its own ``.msg``, ``.srv`` and ``.action`` files, laid out as in a ROS
package (``<package>/msg/Name.msg``); they are read here with their lines, so that a
bad definition is a ``file:line:`` error like any other input. A service becomes
``<package>/srv/Name_Request`` and ``_Response``; an action becomes ``_Goal``,
``_Result``, ``_Feedback`` and the messages its services and topics carry
(``_SendGoal_Request`` ... ``_FeedbackMessage``), as ROS 2 generates them.

Definitions use rosbags' field descriptions (``(Nodetype, details)``), so a store with
custom messages serialises them too: that is what tests compare dura's bytes with.

``rosbags`` (a twentieth of a second to import) is imported in the functions that use
it: every robot description is validated through this module, and only one with ROS 2
needs it.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from knowledge.errors import ConfigError, did_you_mean
from knowledge.finding import Finding, Report

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

BUNDLED = Path(__file__).parent / "ros2_interfaces"
DEFAULT_DISTRIBUTION = "jazzy"
DISTRIBUTIONS = ("foxy", "galactic", "humble", "iron", "jazzy", "kilted", "lyrical")
PRIMITIVES = frozenset(
    ("bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
     "int32", "uint32", "int64", "uint64", "string")
)  # fmt: skip
KINDS = {"msg": (), "srv": ("Request", "Response"), "action": ("Goal", "Result", "Feedback")}

# Field descriptions in rosbags' form: (name, (nodetype, details)); nodetypes as numbers
# 1 base, 2 named, 3 array, 4 sequence (rosbags.interfaces.Nodetype).
Definition = tuple[list[tuple[str, str, Any]], list[tuple[str, tuple[int, Any]]]]

_FIELD = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
_CONSTANT = re.compile(r"[A-Z][A-Z0-9_]*")
_TYPE = re.compile(
    r"(?:(?P<package>[a-z][a-z0-9_]*)/(?:msg/)?)?(?P<name>[A-Za-z][A-Za-z0-9_]*)"
    r"(?:<=(?P<strbound>\d+))?(?:\[(?P<le><=)?(?P<size>\d*)\])?$"
)


def normalize_type(name: str) -> str:
    """Normalise a message type name: ``pkg/Name`` -> ``pkg/msg/Name``."""
    parts = name.strip("/").split("/")
    return f"{parts[0]}/msg/{parts[1]}" if len(parts) == 2 else "/".join(parts)


def standard_store(distribution: str) -> Typestore:
    """Load a fresh store of a distribution's standard messages.

    Raises:
        ConfigError: not a ROS 2 distribution rosbags knows.
    """
    from rosbags.typesys import Stores, get_typestore  # here: see the module's docstring

    if distribution not in DISTRIBUTIONS:
        raise ConfigError(
            f"unknown ROS 2 distribution '{distribution}' (choose from "
            f"{', '.join(DISTRIBUTIONS)}){did_you_mean(distribution, DISTRIBUTIONS)}"
        )
    store = get_typestore(Stores(f"ros2_{distribution}"))
    register(store, bundled_definitions())
    return store


@functools.cache
def bundled_definitions() -> dict[str, Definition]:
    """Read the service definitions dura bundles (every distribution has them alike)."""
    from rosbags.typesys import Stores, get_typestore  # here: see the module's docstring

    known = get_typestore(Stores.ROS2_JAZZY).fielddefs
    definitions, findings = read_definitions([BUNDLED], known)
    if findings:  # dura's own files: a broken one is a bug, not the user's input
        raise ConfigError(f"dura's bundled ROS 2 definitions: {findings[0]}")
    return definitions


def message_store(distribution: str, paths: Sequence[Path] = ()) -> Typestore:
    """Load a distribution's messages plus the custom files under ``paths``.

    Raises:
        ConfigError: an unknown distribution or an invalid definition (the first one,
            as ``file:line: reason``).
    """
    store = standard_store(distribution)
    definitions, findings = read_definitions(paths, store.fielddefs)
    if findings:
        raise ConfigError(str(findings[0]))
    register(store, definitions)
    return store


def register(store: Typestore, definitions: Mapping[str, Definition]) -> None:
    """Add definitions to a store (rosbags generates their classes)."""
    from rosbags.interfaces import Nodetype  # here: see the module's docstring

    def typed(desc: tuple[int, Any]) -> tuple[Nodetype, Any]:
        kind, details = desc
        if kind in (3, 4):
            return Nodetype(kind), (typed(details[0]), details[1])
        return Nodetype(kind), details

    if definitions:
        store.register(
            {
                name: (consts, [(f, typed(d)) for f, d in fields])  # type: ignore[misc]
                for name, (consts, fields) in definitions.items()
            }
        )


def message_files(paths: Iterable[Path]) -> list[Path]:
    """List every definition file under the paths (files or folders), sorted, each once."""
    found: dict[Path, None] = {}
    for path in paths:
        candidates = [path] if path.is_file() else sorted(path.rglob("*"))
        for file in candidates:
            if file.suffix[1:] in KINDS and file.parent.name == file.suffix[1:]:
                found[file.resolve()] = None
    return list(found)


def read_definitions(
    paths: Sequence[Path], known: Mapping[str, object]
) -> tuple[dict[str, Definition], list[Finding]]:
    """Read every definition file under ``paths``; problems become findings."""
    definitions: dict[str, Definition] = {}
    reports: list[Report] = []
    lines: dict[str, tuple[Report, dict[str, int]]] = {}
    for path in paths:
        if not path.exists():
            report = Report(str(path))
            report.error(None, "no such file or folder of ROS 2 message definitions")
            reports.append(report)
    for file in message_files(paths):
        report = Report(str(file))
        reports.append(report)
        try:
            text = file.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as e:
            report.error(None, f"cannot read: {e}")
            continue
        for name, definition, field_lines in read_file(file, text, report):
            definitions[name] = definition
            lines[name] = (report, field_lines)
    names = set(known) | set(definitions)
    for name, (_, fields) in definitions.items():
        report, field_lines = lines[name]
        for field, desc in fields:
            for ref in _references(desc):
                if ref not in names:
                    report.error(
                        field_lines.get(field),
                        f"field '{field}' of {name} has unknown type '{ref}'{_hint(ref, names)}",
                    )
    return definitions, [f for r in reports for f in r.findings]


def _hint(ref: str, names: set[str]) -> str:
    """Suggest a known type, preferring one of the same name in another package."""
    same = sorted(n for n in names if n.rpartition("/")[2] == ref.rpartition("/")[2])
    return f" (did you mean '{same[0]}'?)" if same else did_you_mean(ref, sorted(names))


def _references(desc: tuple[int, Any]) -> list[str]:
    kind, details = desc
    if kind == 2:
        return [details]
    if kind in (3, 4):
        return _references(details[0])
    return []


def read_file(
    file: Path, text: str, report: Report
) -> list[tuple[str, Definition, dict[str, int]]]:
    """Read the types one ``.msg``/``.srv``/``.action`` file defines, with each field's line."""
    kind = file.suffix[1:]
    package = file.parent.parent.name
    parts: list[list[tuple[int, str]]] = [[]]
    for number, raw in enumerate(text.splitlines(), start=1):
        if raw.strip() == "---":
            parts.append([])
        else:
            parts[-1].append((number, raw))
    suffixes = KINDS[kind]
    if len(parts) != max(1, len(suffixes)):
        report.error(
            None,
            f"a .{kind} file has {max(1, len(suffixes))} part(s) separated by '---', "
            f"not {len(parts)}",
        )
        return []
    base = f"{package}/{kind}/{file.stem}"
    names = [f"{base}_{s}" for s in suffixes] if suffixes else [base]
    out = []
    for name, lines in zip(names, parts, strict=True):
        definition, field_lines = _read_part(package, lines, report)
        out.append((name, definition, field_lines))
    if kind == "action":
        out.extend((n, d, {}) for n, d in _action_messages(base).items())
    return out


def _action_messages(base: str) -> dict[str, Definition]:
    """Derive the messages of an action's services and feedback topic, as ROS 2 does."""
    uuid = (2, "unique_identifier_msgs/msg/UUID")
    return {
        f"{base}_SendGoal_Request": ([], [("goal_id", uuid), ("goal", (2, f"{base}_Goal"))]),
        f"{base}_SendGoal_Response": (
            [],
            [("accepted", (1, ("bool", 0))), ("stamp", (2, "builtin_interfaces/msg/Time"))],
        ),
        f"{base}_GetResult_Request": ([], [("goal_id", uuid)]),
        f"{base}_GetResult_Response": (
            [],
            [("status", (1, ("int8", 0))), ("result", (2, f"{base}_Result"))],
        ),
        f"{base}_FeedbackMessage": (
            [],
            [("goal_id", uuid), ("feedback", (2, f"{base}_Feedback"))],
        ),
    }


def _read_part(
    package: str, lines: list[tuple[int, str]], report: Report
) -> tuple[Definition, dict[str, int]]:
    consts: list[tuple[str, str, Any]] = []
    fields: list[tuple[str, tuple[int, Any]]] = []
    field_lines: dict[str, int] = {}
    for number, raw in lines:
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        type_text, _, rest = line.partition(" ")
        desc = _type(package, type_text)
        if isinstance(desc, str):
            report.error(number, desc)
            continue
        before, equals, value = rest.partition("=")
        if equals and len(before.split()) == 1:
            name = before.strip()
            if not _CONSTANT.fullmatch(name) or desc[0] != 1:
                report.error(number, f"constant '{name}' must be UPPER_CASE and of a basic type")
                continue
            kind = desc[1][0]
            consts.append((name, kind, _constant(kind, value.strip())))
            continue
        words = rest.split("#", 1)[0].split()
        if not words:
            report.error(number, f"'{line}' is not 'TYPE NAME' (a field) or 'TYPE NAME=VALUE'")
        elif not _FIELD.fullmatch(words[0]):
            report.error(number, f"invalid field name '{words[0]}'")
        elif words[0] in field_lines:
            first = field_lines[words[0]]
            report.error(number, f"field '{words[0]}' is defined twice (first at line {first})")
        else:
            fields.append((words[0], desc))
            field_lines[words[0]] = number
    if not fields:
        # IDL has no empty structures; ROS 2 adds this member to every empty message
        fields.append(("structure_needs_at_least_one_member", (1, ("uint8", 0))))
    return (consts, fields), field_lines


def _type(package: str, text: str) -> tuple[int, Any] | str:
    """Describe a field's type, or say why it is invalid."""
    match = _TYPE.match(text)
    if match is None:
        return f"invalid type '{text}'"
    name, owner = match["name"], match["package"]
    if name == "wstring":
        return "wstring fields are not supported yet"
    if owner is None and name in PRIMITIVES:
        if match["strbound"] and name != "string":
            return f"only strings take a bound (<=N), not '{text}'"
        inner: tuple[int, Any] = (1, (name, int(match["strbound"] or 0)))
    elif match["strbound"]:
        return f"only strings take a bound (<=N), not '{text}'"
    elif owner is None and name == "Header":
        inner = (2, "std_msgs/msg/Header")  # the one type ROS 2 lets a .msg name bare
    else:
        inner = (2, f"{owner or package}/msg/{name}")
    if text.endswith("]"):
        size = int(match["size"]) if match["size"] else 0
        if match["le"] and not size:
            return f"a bounded sequence needs its bound: '{text}'"
        if match["le"] or not size:
            return (4, (inner, size))
        return (3, (inner, size))
    return inner


def _constant(kind: str, value: str) -> Any:
    if kind == "string" and value[:1] in ("'", '"'):
        return value[1 : value.find(value[0], 1)]
    value = value.split("#", 1)[0].strip()
    if kind == "string":
        return value
    if kind == "bool":
        return value.lower() in ("true", "1")
    if kind.startswith("float"):
        return float(value)
    try:
        return int(value, 0)
    except ValueError:
        return value
