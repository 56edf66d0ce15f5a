"""Read YAML against a schema, keeping the line of every value for error messages.

PyYAML's composer gives nodes with source marks; :class:`Section` reads a mapping
node key by key with typed accessors, reports each type error once with its line,
and at :meth:`Section.close` reports every key that no accessor asked for as
unknown, with a did-you-mean. Readers therefore never list allowed keys twice.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import yaml

from knowledge.finding import Report

MAX_BYTES = 1 << 20  # a robot description, rules or observers file is far smaller
MAX_DEPTH = 64  # levels of nesting: the schemas need about ten
MAX_VALUES = 100_000  # values a document may hold once its aliases are expanded
# libyaml when it is there: it is faster, and refuses pathological nesting by itself
_LOADER: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)

_NUMBER_TAGS = ("tag:yaml.org,2002:int", "tag:yaml.org,2002:float")
_TAG_NAMES = {
    "tag:yaml.org,2002:str": "a string",
    "tag:yaml.org,2002:int": "an integer",
    "tag:yaml.org,2002:float": "a number",
    "tag:yaml.org,2002:bool": "a boolean",
    "tag:yaml.org,2002:null": "empty",
    "tag:yaml.org,2002:map": "a mapping",
    "tag:yaml.org,2002:seq": "a list",
}


def line_of(node: yaml.Node) -> int:
    """The 1-based line a node starts on."""
    return int(node.start_mark.line) + 1


def describe(node: yaml.Node) -> str:
    """How a value reads in an error message: its text for scalars, else its kind."""
    if isinstance(node, yaml.ScalarNode):
        return repr(node.value) if node.value != "" else "empty"
    return _TAG_NAMES.get(node.tag, node.tag)


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
            text = path.read_text(encoding="utf-8")
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


def paths(node: yaml.Node, prefix: str = "") -> dict[str, int]:
    """The line of every key and list item below a node, by dotted path."""
    out: dict[str, int] = {}
    if isinstance(node, yaml.MappingNode):
        for key, value in node.value:
            path = f"{prefix}{key.value}"
            out[path] = line_of(key)
            out.update(paths(value, path + "."))
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            path = f"{prefix}{i}"
            out[path] = line_of(item)
            out.update(paths(item, path + "."))
    return out


def did_you_mean(word: str, choices: object) -> str:
    """`` (did you mean 'x'?)`` for the closest choice, or an empty string."""
    names = [str(c) for c in choices]  # type: ignore[attr-defined]
    close = difflib.get_close_matches(word, names, n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""


class Section:
    """A YAML mapping read against a schema, key by key.

    ``what`` names the mapping in messages, e.g. ``functionality 'lidar'``.
    """

    def __init__(self, node: yaml.Node, what: str, report: Report, line: int | None = None) -> None:
        self.what = what
        self.report = report
        self.line = line or line_of(node)
        self._values: dict[str, yaml.Node] = {}
        self._key_lines: dict[str, int] = {}
        self._read: set[str] = set()
        if isinstance(node, yaml.MappingNode):
            for key, value in node.value:
                name = key.value if isinstance(key, yaml.ScalarNode) else str(key.value)
                self._values.setdefault(str(name), value)
                self._key_lines.setdefault(str(name), line_of(key))
        self.valid = isinstance(node, yaml.MappingNode)
        if not self.valid:
            report.error(self.line, f"{what} must be a mapping, not {describe(node)}")

    # --- access ---------------------------------------------------------------

    def written(self) -> list[str]:
        """The keys as written, in order."""
        return list(self._values)

    def has(self, key: str) -> bool:
        return key in self._values

    def node(self, key: str) -> yaml.Node | None:
        """The raw node of a key (marks it as read)."""
        self._read.add(key)
        return self._values.get(key)

    def key_line(self, key: str) -> int:
        return self._key_lines.get(key, self.line)

    def _missing(self, key: str, required: bool) -> None:
        if required:
            self.report.error(self.line, f"{self.what} has no '{key}'")

    def _wrong(self, key: str, node: yaml.Node, expected: str) -> None:
        self.report.error(
            line_of(node),
            f"'{key}' of {self.what} must be {expected}, not {describe(node)}",
        )

    def text(self, key: str, default: str | None = None, *, required: bool = False) -> str | None:
        node = self.node(key)
        if node is None:
            self._missing(key, required)
            return default
        if not isinstance(node, yaml.ScalarNode) or node.tag == "tag:yaml.org,2002:null":
            self._wrong(key, node, "a string")
            return default
        return str(node.value)

    def number(self, key: str, default: float, *, minimum: float | None = None) -> float:
        node = self.node(key)
        if node is None:
            return default
        if not isinstance(node, yaml.ScalarNode) or node.tag not in _NUMBER_TAGS:
            self._wrong(key, node, "a number")
            return default
        value = float(to_python(node))
        if minimum is not None and value < minimum:
            self.report.error(
                line_of(node),
                f"'{key}' of {self.what} must be at least {minimum:g}, not {value:g}",
            )
            return default
        return value

    def integer(self, key: str, default: int, *, minimum: int | None = None) -> int:
        node = self.node(key)
        if node is None:
            return default
        if not isinstance(node, yaml.ScalarNode) or node.tag != "tag:yaml.org,2002:int":
            self._wrong(key, node, "an integer")
            return default
        value = int(to_python(node))
        if minimum is not None and value < minimum:
            self.report.error(
                line_of(node),
                f"'{key}' of {self.what} must be at least {minimum}, not {value}",
            )
            return default
        return value

    def flag(self, key: str, default: bool) -> bool:
        node = self.node(key)
        if node is None:
            return default
        if not isinstance(node, yaml.ScalarNode) or node.tag != "tag:yaml.org,2002:bool":
            self._wrong(key, node, "true or false")
            return default
        return bool(to_python(node))

    def texts(self, key: str, *, required: bool = False) -> tuple[str, ...]:
        """A list of strings; a single string is accepted as a list of one."""
        node = self.node(key)
        if node is None:
            self._missing(key, required)
            return ()
        if isinstance(node, yaml.ScalarNode) and node.tag == "tag:yaml.org,2002:str":
            return (str(node.value),)
        if isinstance(node, yaml.ScalarNode) and node.tag == "tag:yaml.org,2002:null":
            return ()
        if not isinstance(node, yaml.SequenceNode):
            self._wrong(key, node, "a list of strings")
            return ()
        out: list[str] = []
        for item in node.value:
            if not isinstance(item, yaml.ScalarNode) or item.tag == "tag:yaml.org,2002:null":
                self.report.error(
                    line_of(item),
                    f"'{key}' of {self.what} must list strings, not {describe(item)}",
                )
            else:
                out.append(str(item.value))
        return tuple(out)

    def section(self, key: str, *, required: bool = False) -> Section | None:
        node = self.node(key)
        if node is None:
            self._missing(key, required)
            return None
        return Section(node, f"'{key}' of {self.what}", self.report)

    def named(self, key: str) -> Iterator[tuple[str, yaml.Node, int]]:
        """Entries of a mapping keyed by name: (name, value node, line)."""
        node = self.node(key)
        if node is None or (isinstance(node, yaml.ScalarNode) and node.value in ("", "~", "null")):
            return
        if not isinstance(node, yaml.MappingNode):
            self._wrong(key, node, "a mapping of names to entries")
            return
        for k, v in node.value:
            yield str(k.value), v, line_of(k)

    def sequence(self, key: str) -> list[yaml.Node]:
        node = self.node(key)
        if node is None or (isinstance(node, yaml.ScalarNode) and node.value in ("", "~", "null")):
            return []
        if not isinstance(node, yaml.SequenceNode):
            self._wrong(key, node, "a list")
            return []
        return list(node.value)

    def plain(self, key: str) -> dict[str, Any]:
        """A mapping of free-form values (e.g. component parameters)."""
        node = self.node(key)
        if node is None:
            return {}
        if not isinstance(node, yaml.MappingNode):
            self._wrong(key, node, "a mapping")
            return {}
        value = to_python(node)
        return dict(value) if isinstance(value, dict) else {}

    # --- end ------------------------------------------------------------------

    def close(self) -> None:
        """Report every key no accessor read as unknown, with a did-you-mean."""
        known = self._read
        for key in self._values:
            if key not in known:
                hint = did_you_mean(key, sorted(known))
                self.report.error(self.key_line(key), f"unknown key '{key}' in {self.what}{hint}")
