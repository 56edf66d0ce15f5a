"""Every name written in a project's files: where it is declared and where it is used.

A PDDL file declares types, predicates, functions, actions, constants and objects and
uses them in its lists; a robot description declares components and, as their
providers, capabilities and topics, and names actions (its tasks), components,
capabilities, topics and predicates; its rule files name components and predicates.
Hover, go to definition, references and completion all read these occurrences.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import yaml

from executive.lsp.pddl_syntax import Form, Token, parse, typed_list

# the words of PDDL's expressions that are no predicate or function
EXPRESSION_WORDS = frozenset(
    [
        "and",
        "or",
        "not",
        "imply",
        "forall",
        "exists",
        "when",
        "at",
        "over",
        "start",
        "end",
        "all",
        "=",
        "<",
        ">",
        "<=",
        ">=",
        "+",
        "-",
        "*",
        "/",
        "increase",
        "decrease",
        "assign",
        "scale-up",
        "scale-down",
        "preference",
        "either",
        "minimize",
        "maximize",
        "sometime",
        "always",
        "within",
        "at-most-once",
        "sometime-after",
        "sometime-before",
        "always-within",
        "hold-during",
        "hold-after",
        "total-time",
        "is-violated",
    ]
)
SECTION_WORDS = [
    ":requirements",
    ":types",
    ":constants",
    ":predicates",
    ":functions",
    ":action",
    ":durative-action",
    ":parameters",
    ":duration",
    ":condition",
    ":precondition",
    ":effect",
    ":domain",
    ":objects",
    ":init",
    ":goal",
    ":metric",
    ":constraints",
]
_FACT = re.compile(r"\(\s*([^\s()]+)([^()]*)\)")


@dataclass(frozen=True)
class Occurrence:
    """A name written at ``start``..``end`` of a file's text; ``declared``: its declaration
    (for a capability or a topic: a provider or publisher)."""

    kind: str  # type, predicate, function, action, object, component, capability, topic
    name: str  # as PDDL compares it: lower-case for PDDL names
    path: Path
    start: int
    end: int
    declared: bool = False
    detail: str = ""  # what the declaration says: a signature, a type, a kind


def pddl_names(path: Path, text: str) -> list[Occurrence]:
    """The names a PDDL domain or problem declares and uses."""
    found: list[Occurrence] = []

    def add(kind: str, token: Token, declared: bool = False, detail: str = "") -> None:
        found.append(
            Occurrence(kind, token.text.lower(), path, token.start, token.end, declared, detail)
        )

    def types_of(pairs: list[tuple[Token, Token | None]]) -> None:
        for _, kind in pairs:
            if kind is not None:
                add("type", kind)

    for define in parse(text).forms():
        for part in define.forms():
            head = part.head
            words = part.words()
            if head in ("domain", "problem", ":domain") and len(words) > 1:
                add("domain" if head != "problem" else "problem", words[1], head != ":domain")
            elif head == ":types":
                for name, parent in typed_list(part.items[1:]):
                    add(
                        "type",
                        name,
                        True,
                        f"type {name.text} - {parent.text if parent else 'object'}",
                    )
                    if parent is not None:
                        add("type", parent)
            elif head in (":constants", ":objects"):
                for name, kind in typed_list(part.items[1:]):
                    add("object", name, True, f"{name.text} - {kind.text if kind else 'object'}")
                    if kind is not None:
                        add("type", kind)
            elif head in (":predicates", ":functions"):
                for signature in part.forms():
                    if signature.items and isinstance(signature.items[0], Token):
                        what = "predicate" if head == ":predicates" else "function"
                        add(what, signature.items[0], True, _flat(text, signature))
                        types_of(typed_list(signature.items[1:]))
            elif head in (":action", ":durative-action") and len(words) > 1:
                add("action", words[1], True, head[1:])
                parameters = part.after(":parameters")
                if isinstance(parameters, Form):
                    types_of(typed_list(parameters.items))
                for form in part.forms():
                    if form is not parameters:
                        _uses(form, add)
            elif head in (":init", ":goal", ":constraints", ":metric"):
                for form in part.forms():
                    _uses(form, add)
    return found


Add = Callable[[str, Token], None]


def _uses(form: Form, add: Add) -> None:
    """The predicates, functions and objects an expression names (a fluent's kind is
    told apart later: PDDL writes both alike)."""
    head = form.head
    if head in ("forall", "exists") and len(form.items) > 1 and isinstance(form.items[1], Form):
        for _, kind in typed_list(form.items[1].items):
            if kind is not None:
                add("type", kind)
        for inner in form.forms()[1:]:
            _uses(inner, add)
        return
    first = form.items[0] if form.items else None
    if (
        isinstance(first, Token)
        and head not in EXPRESSION_WORDS
        and not head.startswith((":", "?"))
    ):
        add("fluent", first)
        for word in form.words()[1:]:
            if not word.text.startswith("?") and not _number(word.text):
                add("object", word)
    for inner in form.forms():
        _uses(inner, add)


def _number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _flat(text: str, form: Form) -> str:
    """A list's text on one line, without comments."""
    code = re.sub(r";[^\n]*", "", text[form.start : form.end])
    return " ".join(code.replace("( ", "(").split())


def yaml_names(path: Path, text: str) -> list[Occurrence]:
    """The names a robot description or one of its rule files declares and uses."""
    try:
        root = yaml.compose(text)
    except (yaml.YAMLError, RecursionError, ValueError):
        return []
    found: list[Occurrence] = []
    if isinstance(root, yaml.MappingNode):
        _walk(path, text, root, (), found)
    return found


_LISTS = {
    "provides": ("capability", True),
    "requires": ("capability", False),
    "publishes": ("topic", True),
    "subscribes": ("topic", False),
}
_SCALARS = {"behavior": "component", "component": "component", "topic": "topic"}


def _walk(
    path: Path, text: str, node: yaml.Node, keys: tuple[str, ...], found: list[Occurrence]
) -> None:
    if isinstance(node, yaml.SequenceNode):
        for item in node.value:
            _walk(path, text, item, keys, found)
        return
    if not isinstance(node, yaml.MappingNode):
        return
    for key, value in node.value:
        if not isinstance(key, yaml.ScalarNode):
            continue
        name = str(key.value)
        where = (key.start_mark.index, key.end_mark.index)
        if keys in (("functionalities",), ("behaviors",)):
            kind = "functionality" if keys[0] == "functionalities" else "behavior"
            found.append(Occurrence("component", name, path, *where, True, kind))
        elif keys == ("tasks",):
            found.append(Occurrence("action", name.lower(), path, *where))
        if name in _LISTS and isinstance(value, yaml.SequenceNode) and len(keys) >= 1:
            kind, declared = _LISTS[name]
            for item in value.value:
                if isinstance(item, yaml.ScalarNode):
                    found.append(
                        Occurrence(
                            kind,
                            str(item.value),
                            path,
                            item.start_mark.index,
                            item.end_mark.index,
                            declared,
                        )
                    )
        elif name in _SCALARS and isinstance(value, yaml.ScalarNode):
            found.append(
                Occurrence(
                    _SCALARS[name],
                    str(value.value),
                    path,
                    value.start_mark.index,
                    value.end_mark.index,
                )
            )
        elif name in ("fact", "goal", "value") and isinstance(value, yaml.ScalarNode):
            found += _facts(path, text, value)
        _walk(path, text, value, (*keys, name), found)


def _facts(path: Path, text: str, node: yaml.ScalarNode) -> list[Occurrence]:
    """The predicates and objects of the atoms a string writes (``"(robot_at dock)"``)."""
    start, end = node.start_mark.index, node.end_mark.index
    written = text[start:end]
    found = []
    for atom in _FACT.finditer(written):
        found.append(
            Occurrence(
                "fluent", atom.group(1).lower(), path, start + atom.start(1), start + atom.end(1)
            )
        )
        for word in re.finditer(r"[^\s()]+", atom.group(2)):
            if not word.group(0).startswith("?") and not _number(word.group(0)):
                offset = start + atom.start(2) + word.start()
                found.append(
                    Occurrence(
                        "object", word.group(0).lower(), path, offset, offset + len(word.group(0))
                    )
                )
    return [o for o in found if o.name not in EXPRESSION_WORDS]
