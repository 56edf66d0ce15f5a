"""The kinds of event dura logs are known: every ``log_event`` call of dura, read from
its source, logs a kind of :mod:`executive.bus.event_kinds`, and every kind listed there
is logged somewhere."""

from __future__ import annotations

import ast
from collections.abc import Iterator

from executive.bus.event_kinds import FAMILIES, KINDS, NAMED, known
from executive.bus.states import GoalStatus, Lifecycle
from executive.tasks.task import TaskPhase
from knowledge.transitions import GoalState
from tests.conftest import ROOT

PACKAGES = ("executive", "monitoring", "knowledge")


def sources() -> Iterator[tuple[str, ast.Module]]:
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            text = path.read_text(encoding="utf-8")
            yield str(path.relative_to(ROOT)), ast.parse(text, str(path))


def _called(node: ast.Call) -> str:
    func = node.func
    return func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")


def _parameters(function: ast.FunctionDef) -> list[str]:
    names = [a.arg for a in function.args.posonlyargs + function.args.args]
    return names[1:] if names[:1] in (["self"], ["cls"]) else names


def _kind_argument(node: ast.Call, index: int) -> ast.expr | None:
    for keyword in node.keywords:
        if keyword.arg == "kind":
            return keyword.value
    return node.args[index] if len(node.args) > index else None


def loggers() -> dict[str, int]:
    """``log_event`` and every function that hands its own ``kind`` parameter on to a
    logger (``ledger.event``, a plan run's ``event``, ``_write``), with that parameter's
    place among the arguments."""
    found = {"log_event": 0}
    trees = list(sources())
    while True:
        more = {}
        for _, tree in trees:
            for function in ast.walk(tree):
                if not isinstance(function, ast.FunctionDef) or function.name in found:
                    continue
                parameters = _parameters(function)
                for node in ast.walk(function):
                    if isinstance(node, ast.Call) and _called(node) in found:
                        kind = _kind_argument(node, found[_called(node)])
                        if isinstance(kind, ast.Name) and kind.id in parameters:
                            more[function.name] = parameters.index(kind.id)
        if not more:
            return found
        found.update(more)


def calls(
    tree: ast.AST, within: ast.FunctionDef | None = None
) -> Iterator[tuple[ast.Call, ast.FunctionDef | None]]:
    """Every call with the innermost function it is in (``None``: at module level)."""
    for child in ast.iter_child_nodes(tree):
        inner = child if isinstance(child, ast.FunctionDef) else within
        if isinstance(child, ast.Call):
            yield child, within
        yield from calls(child, inner)


def assigned(scopes: list[ast.AST], name: str) -> list[ast.expr]:
    """The values assigned to a name in the first scope that assigns it (the function,
    then the module: ``kind = "A" if x else "B"``, ``RECOVERED = "RECOVERED"``); the name
    itself if none does (it cannot be read then)."""
    for scope in scopes:
        values = [
            node.value
            for node in ast.walk(scope)
            if isinstance(node, ast.Assign)
            and any(isinstance(t, ast.Name) and t.id == name for t in node.targets)
        ]
        if values:
            return values
    return [ast.Name(name)]


def logged_kinds() -> Iterator[tuple[str, ast.expr, bool]]:
    """Every kind expression handed to a logger, where it is (``file:line``), and whether
    it is the enclosing logger's own parameter, handed on."""
    known_loggers = loggers()
    for path, tree in sources():
        for node, function in calls(tree):
            where = f"{path}:{node.lineno}"
            if _called(node) in known_loggers:
                kind = _kind_argument(node, known_loggers[_called(node)])
                own = (
                    _parameters(function)
                    if function is not None and function.name in known_loggers
                    else []
                )
                if isinstance(kind, ast.Name) and kind.id not in own:
                    # a local name: the values assigned to it in the function
                    scopes = [tree] if function is None else [function, tree]
                    for value in assigned(scopes, kind.id):
                        yield where, value, False
                elif kind is not None:
                    yield where, kind, isinstance(kind, ast.Name)
            # a logger handed over to be called later: callback(kb.log_event, "KIND")
            for i, arg in enumerate(node.args[:-1]):
                if isinstance(arg, ast.Attribute) and arg.attr == "log_event":
                    yield where, node.args[i + 1], False


def kinds_of(expression: ast.expr) -> list[str]:
    """The kinds an expression can be: names, or ``PREFIX*`` for a composed kind."""
    if isinstance(expression, ast.Constant) and isinstance(expression.value, str):
        return [expression.value]
    if isinstance(expression, ast.IfExp):
        return kinds_of(expression.body) + kinds_of(expression.orelse)
    if isinstance(expression, ast.JoinedStr):
        first = expression.values[0]
        assert isinstance(first, ast.Constant), ast.unparse(expression)
        return [f"{first.value!s}*"]
    return []  # a variable: only a logger's own parameter, handed on (checked below)


def test_every_logged_kind_is_a_known_kind_or_family() -> None:
    seen: set[str] = set()
    for where, expression, handed_on in logged_kinds():
        kinds = kinds_of(expression)
        if not kinds:
            assert handed_on, f"{where}: a kind dura cannot read: {ast.unparse(expression)}"
            continue
        for kind in kinds:
            if kind.endswith("*"):
                assert kind[:-1] in FAMILIES, f"{where}: unknown family {kind}"
            else:
                assert known(kind), f"{where}: {kind} is not in executive/bus/event_kinds.py"
            seen.add(kind)
    assert seen >= NAMED, f"listed but never logged: {sorted(NAMED - seen)}"
    assert {f"{p}*" for p in FAMILIES} <= seen, "a family nobody logs"


def test_the_loggers_found_include_those_that_hand_a_kind_on() -> None:
    assert {"log_event", "event"} <= set(loggers())


def test_each_family_holds_the_states_of_its_enum() -> None:
    assert FAMILIES["COMPONENT_"] == tuple(s.name for s in Lifecycle)
    assert FAMILIES["GOAL_"] == tuple(s.name for s in GoalState)
    assert FAMILIES["GOAL_RESULT_"] == tuple(s.name for s in GoalStatus)
    assert set(FAMILIES["TASK_"]) == {p.name for p in TaskPhase if p.final}


def test_composed_kinds_are_known_and_others_are_not() -> None:
    assert {"COMPONENT_READY", "GOAL_ACHIEVED", "GOAL_RESULT_CANCELLED", "TASK_FAILED"} <= KINDS
    assert not known("bogus")
    assert not known("TASK_WAITING")  # a phase, but no event ends a task in it
