"""YAML documents as plain values with the line of every place, for the typed reader.

Every YAML file dura reads goes through here: :func:`load` for a plain value (a bag's
``metadata.yaml``), :func:`read_file` for the typed reader. :func:`compose` parses a file (refusing what no robot needs: too large, too deep, alias
bombs; duplicate keys are problems); :func:`document` turns the nodes into plain values
and the lines of their keys and values; :class:`DocumentSource` lets
:mod:`knowledge.typed_reader` read them against a schema with ``file:line`` messages
that show each scalar as it is written.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from knowledge.errors import ConfigError
from knowledge.field_plan import PathPart, dotted
from knowledge.finding import Report
from knowledge.sources import read_text
from knowledge.value_source import Source

MAX_BYTES = 1 << 20  # a robot description, rules or observers file is far smaller
MAX_DEPTH = 64  # levels of nesting: the schemas need about ten
MAX_VALUES = 100_000  # values a document may hold once its aliases are expanded
# libyaml when it is there: it is faster, and refuses pathological nesting by itself
_LOADER: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def line_of(node: yaml.Node) -> int:
    """The 1-based line a node starts on."""
    return int(node.start_mark.line) + 1


def to_python(node: yaml.Node) -> Any:
    """The plain Python value of a node (dicts, lists, scalars)."""
    return yaml.SafeLoader("").construct_document(node)


def compose(path: Path, report: Report, text: str | None = None) -> yaml.Node | None:
    """Parse one YAML document; report syntax errors, duplicate keys, and documents no
    robot needs and a reader must not choke on: larger than ``MAX_BYTES``, nested deeper
    than ``MAX_DEPTH``, or whose aliases expand to more than ``MAX_VALUES`` values.

    Returns ``None`` when the file cannot be read or parsed, or is refused.
    """
    if text is None:
        try:
            if path.stat().st_size > MAX_BYTES:
                report.error(
                    None, f"too large: {_size(path.stat().st_size)} (at most {_size(MAX_BYTES)})"
                )
                return None
            text = read_text(path)
        except OSError as e:
            report.error(None, f"cannot read: {e.strerror or e}")
            return None
        except UnicodeDecodeError:
            report.error(None, "is not UTF-8 text")
            return None
    if len(text) > MAX_BYTES:
        report.error(None, f"too large: {_size(len(text))} (at most {_size(MAX_BYTES)})")
        return None
    try:
        node = yaml.compose(text, Loader=_LOADER)
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        line = int(mark.line) + 1 if mark is not None else None
        problem = e.problem or e.context or "invalid YAML"
        report.error(line, f"invalid YAML: {problem}")
        return None
    except yaml.YAMLError as e:
        report.error(None, f"invalid YAML: {e}")
        return None
    except RecursionError:
        report.error(None, f"invalid YAML: nested more than {MAX_DEPTH} levels deep")
        return None
    if node is not None:
        if not _within_bounds(node, report):
            return None
        _check_duplicate_keys(node, report)
    return node


def _size(count: int) -> str:
    return f"{count / (1 << 20):.1f} MiB" if count >= 1 << 20 else f"{count // 1024} KiB"


def _within_bounds(root: yaml.Node, report: Report) -> bool:
    """Whether a document is at most ``MAX_DEPTH`` deep and its aliases expand to at most
    ``MAX_VALUES`` values; reports the line where it is not (without recursion, and in
    time linear in the document, however far its aliases would expand)."""
    stack: list[tuple[yaml.Node, int]] = [(root, 1)]
    seen: set[int] = set()
    order: list[yaml.Node] = []
    while stack:
        node, depth = stack.pop()
        if depth > MAX_DEPTH:
            report.error(line_of(node), f"nested more than {MAX_DEPTH} levels deep")
            return False
        if id(node) in seen:
            continue
        seen.add(id(node))
        order.append(node)
        stack.extend((child, depth + 1) for child in _children(node))
    values: dict[int, int] = {}
    for node in reversed(order):  # children before parents: each node counted once
        values[id(node)] = 1 + sum(values.get(id(c), 1) for c in _children(node))
        if values[id(node)] > MAX_VALUES:
            report.error(
                line_of(node), f"its aliases expand to more than {MAX_VALUES} values (a YAML bomb?)"
            )
            return False
    return True


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    return []


def _check_duplicate_keys(node: yaml.Node, report: Report) -> None:
    if isinstance(node, yaml.MappingNode):
        seen: dict[str, int] = {}
        for key, value in node.value:
            if isinstance(key, yaml.ScalarNode):
                if key.value in seen:
                    report.error(
                        line_of(key),
                        f"duplicate key '{key.value}' (first at line {seen[key.value]})",
                    )
                else:
                    seen[key.value] = line_of(key)
            _check_duplicate_keys(value, report)
    elif isinstance(node, yaml.SequenceNode):
        for item in node.value:
            _check_duplicate_keys(item, report)


@dataclass
class Document:
    """A YAML document as plain values, with the line of each key and list item, the
    line where each value starts, and the text of each scalar as written (by dotted
    path: ``functionalities.lidar.observers.0.type``)."""

    value: Any
    key_lines: dict[str, int] = field(default_factory=dict)
    value_lines: dict[str, int] = field(default_factory=dict)
    texts: dict[str, str] = field(default_factory=dict)


def document(root: yaml.Node) -> Document:
    """The plain values of a composed document and the places of its parts (where a key
    is written twice, the last one counts, as in the values)."""
    found = Document(to_python(root))
    stack: list[tuple[str, yaml.Node]] = [("", root)]
    while stack:
        path, node = stack.pop()
        found.value_lines[path] = line_of(node)
        prefix = f"{path}." if path else ""
        children: list[tuple[str, yaml.Node]] = []
        if isinstance(node, yaml.ScalarNode):
            found.texts[path] = str(node.value)
        elif isinstance(node, yaml.MappingNode):
            for key, value in node.value:
                found.key_lines[f"{prefix}{key.value}"] = line_of(key)
                children.append((f"{prefix}{key.value}", value))
        elif isinstance(node, yaml.SequenceNode):
            for i, item in enumerate(node.value):
                found.key_lines[f"{prefix}{i}"] = line_of(item)
                children.append((f"{prefix}{i}", item))
        stack.extend(reversed(children))  # in the document's order: the last one counts
    return found


class DocumentSource(Source):
    """A YAML document read against a schema: problems go to ``report`` with their
    lines; a null is a value (wrong where the field takes none); a scalar reads as the
    text written where a text is expected, and shows so in messages."""

    null_is_absent = False
    strict = False  # a description with problems is still read: later checks run on it

    def __init__(
        self,
        found: Document,
        report: Report,
        *,
        folder: Path | None = None,
        context: Any = None,
    ) -> None:
        super().__init__(report, folder=folder, context=context)
        self.document = found

    def key_line(self, path: Sequence[PathPart]) -> int | None:
        return self.document.key_lines.get(dotted(path))

    def value_line(self, path: Sequence[PathPart]) -> int | None:
        key = dotted(path)
        line = self.document.value_lines.get(key)
        return line if line is not None else self.document.key_lines.get(key)

    def text(self, value: Any, path: Sequence[PathPart]) -> str | None:
        return self.document.texts.get(dotted(path))

    def blank(self, value: Any) -> bool:
        return value is None or value in ("", "~", "null")  # as written, or quoted

    def describe(self, value: Any, path: Sequence[PathPart]) -> str:
        text = self.document.texts.get(dotted(path))
        if text is None:
            return super().describe(value, path)
        return repr(text) if text != "" else "empty"

    def describe_number(self, raw: Any, value: float, path: Sequence[PathPart]) -> str:
        return f"{value:g}" if isinstance(value, float) else str(value)


def read_file(path: Path, report: Report, text: str | None = None) -> Document | None:
    """A YAML file as a :class:`Document` (``None`` if it cannot be read, is refused,
    or is empty: reported, but for an empty one)."""
    node = compose(path, report, text)
    return document(node) if node is not None else None


def load(path: Path) -> Any:
    """A YAML file's plain value, read as safely as a robot description (too large, too
    deep and alias bombs refused; ``None`` for an empty file).

    Raises:
        ConfigError: it cannot be read or is refused: one line, ``file:line: reason``.
    """
    report = Report(str(path))
    node = compose(path, report)
    if report.errors:
        raise ConfigError(str(report.errors[0]))
    return None if node is None else to_python(node)
