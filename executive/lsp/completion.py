"""What may be written at the cursor: PDDL names and keywords; robot description keys,
components, capabilities, topics and actions."""

from __future__ import annotations

import re
from pathlib import Path

from lsprotocol import types

from executive.lsp.names import EXPRESSION_WORDS, SECTION_WORDS
from executive.lsp.navigation import Names
from executive.lsp.pddl_syntax import Form, Token, parse
from knowledge.description import BehaviorSpec, FunctionalitySpec, PlannerSpec, TaskSpec
from knowledge.field_plan import fields_of
from knowledge.robot import BusSpec, RobotFile
from knowledge.sensing_spec import SensingRuleSpec

_WORD = re.compile(r"[^\s();\[\],:{}]*$")
_KEY = re.compile(r"([\w-]+)\s*:")
_KIND = {
    "type": types.CompletionItemKind.Class,
    "fluent": types.CompletionItemKind.Function,
    "predicate": types.CompletionItemKind.Function,
    "function": types.CompletionItemKind.Function,
    "object": types.CompletionItemKind.Constant,
    "action": types.CompletionItemKind.Method,
    "component": types.CompletionItemKind.Module,
    "capability": types.CompletionItemKind.Interface,
    "topic": types.CompletionItemKind.Event,
}
_KEYS_OF = {
    (): RobotFile,
    ("functionalities", "*"): FunctionalitySpec,
    ("behaviors", "*"): BehaviorSpec,
    ("tasks", "*"): TaskSpec,
    ("sensing",): SensingRuleSpec,
    ("planner",): PlannerSpec,
    ("bus",): BusSpec,
}
_VALUES = {
    "provides": "capability",
    "requires": "capability",
    "publishes": "topic",
    "subscribes": "topic",
    "may_subscribe": "topic",  # or a pattern: the topics are a start
    "topic": "topic",
    "behavior": "component",
    "component": "component",
}


def complete(names: Names, path: Path, offset: int) -> list[types.CompletionItem]:
    """The completions at ``offset`` of a file of the project."""
    text = names.texts.get(path, "")
    if path.suffix.lower() == ".pddl":
        return _pddl(names, text, offset)
    return _yaml(names, text, offset)


def _items(names: Names, kind: str) -> list[types.CompletionItem]:
    return [
        types.CompletionItem(o.name, kind=_KIND.get(o.kind), detail=o.detail or o.kind)
        for o in names.declared(kind)
    ]


def _words(words: list[str], kind: types.CompletionItemKind) -> list[types.CompletionItem]:
    return [types.CompletionItem(w, kind=kind) for w in words]


def _pddl(names: Names, text: str, offset: int) -> list[types.CompletionItem]:
    before = text[:offset]
    prefix = _WORD.search(before.replace(":", " :")) or _WORD.search("")
    word = prefix.group(0) if prefix else ""
    rest = before[: len(before) - len(word)]
    keyword = types.CompletionItemKind.Keyword
    if word.startswith(":"):
        return _words(SECTION_WORDS, keyword)
    if word.startswith("?"):
        return _words(_variables(text, offset), types.CompletionItemKind.Variable)
    if rest.rstrip().endswith("("):
        return _items(names, "fluent") + _words(sorted(EXPRESSION_WORDS), keyword)
    if rest.rstrip().endswith(" -") or rest.rstrip() == "-":
        return [*_items(names, "type"), types.CompletionItem("object", kind=_KIND["type"])]
    if rest.rstrip().endswith(("(at", "(over")):
        return _words(["start", "end", "all"], keyword)
    return _items(names, "object") + _items(names, "action")


def _variables(text: str, offset: int) -> list[str]:
    """The variables of the top-level part (an action) the cursor is in."""
    for define in parse(text).forms():
        for part in define.forms():
            if part.start <= offset <= part.end:
                return sorted(
                    {w.text for w in _all_words(part) if w.text.startswith("?") and len(w.text) > 1}
                )
    return []


def _all_words(form: Form) -> list[Token]:
    found = form.words()
    for inner in form.forms():
        found += _all_words(inner)
    return found


def _yaml(names: Names, text: str, offset: int) -> list[types.CompletionItem]:
    start = text.rfind("\n", 0, offset) + 1
    line = text[start:offset]
    parents = _parents(text[:start], len(line) - len(line.lstrip(" -")))
    code = line.split(" #", 1)[0]
    if ":" not in code:  # a key, or an item of a block list
        if line.lstrip().startswith("- ") and parents:
            return _values(names, parents[-1])
        if parents in (["tasks"],):
            return _items(names, "action")
        return _keys(parents)
    keys = _KEY.findall(code)  # in a flow mapping, the last key before the cursor
    key = keys[-1] if keys else ""
    if key == "name" and parents[-1:] == ["topics"]:  # an observer's topic
        key = "topic"
    return _values(names, key)


def _values(names: Names, key: str) -> list[types.CompletionItem]:
    kind = _VALUES.get(key)
    items = _items(names, kind) if kind else []
    if key == "behavior":  # a task's: behaviors only
        items = [i for i in items if i.detail == "behavior"]
    return items


def _keys(parents: list[str]) -> list[types.CompletionItem]:
    for pattern, schema in _KEYS_OF.items():
        if len(pattern) == len(parents) and all(
            p in ("*", q) for p, q in zip(pattern, parents, strict=True)
        ):
            keys = [f.key for f in fields_of(schema) if f.fill is None]
            return _words(keys, types.CompletionItemKind.Property)
    return []


def _parents(above: str, indent: int) -> list[str]:
    """The keys of the mappings that hold a line indented by ``indent`` (outermost first)."""
    parents: list[str] = []
    for line in reversed(above.splitlines()):
        code = line.split(" #", 1)[0].rstrip()
        if not code.strip() or code.lstrip().startswith("#"):
            continue
        own = len(code) - len(code.lstrip(" -"))
        if own < indent and ":" in code:
            parents.insert(0, code.split(":", 1)[0].strip(" -"))
            indent = own
            if own == 0:
                break
    return parents
