"""The kinds of event dura logs are known: every ``log_event`` call of dura, read from
its source, logs a kind of :mod:`executive.bus.event_kinds`, and every kind listed there
is logged somewhere."""

from __future__ import annotations

import ast
from collections.abc import Iterator

from executive.bus.event_kinds import FAMILIES, KINDS, NAMED, known
from executive.bus.payloads import GoalStatus, Lifecycle
from executive.tasks.task import TaskPhase
from knowledge.lifecycle import GoalState
from tests.conftest import ROOT

PACKAGES = ("executive", "monitoring", "knowledge")
LOGGERS = {"log_event", "event"}  # the knowledge base's, and the ledger's and plan run's


def logged_kinds() -> Iterator[tuple[str, ast.expr]]:
    """Every kind expression handed to a logger, with where it is (``file:line``)."""
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
            for node in ast.walk(tree):
                if not isinstance(node, ast.Call):
                    continue
                where = f"{path.relative_to(ROOT)}:{node.lineno}"
                func = node.func
                if isinstance(func, ast.Attribute) and func.attr in LOGGERS and node.args:
                    yield where, node.args[0]
                # a logger handed over to be called later: callback(kb.log_event, "KIND")
                for i, arg in enumerate(node.args[:-1]):
                    if isinstance(arg, ast.Attribute) and arg.attr == "log_event":
                        yield where, node.args[i + 1]


def forwarders() -> set[str]:
    """``file:line`` of every call inside a logger that hands its own ``kind`` on."""
    found = set()
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
            for function in ast.walk(tree):
                if isinstance(function, ast.FunctionDef) and function.name in LOGGERS:
                    for node in ast.walk(function):
                        if isinstance(node, ast.Call):
                            found.add(f"{path.relative_to(ROOT)}:{node.lineno}")
    return found


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
    return []  # a variable: only a forwarder's own parameter (checked below)


def test_every_logged_kind_is_a_known_kind_or_family() -> None:
    allowed_variables = forwarders()
    seen: set[str] = set()
    for where, expression in logged_kinds():
        kinds = kinds_of(expression)
        if not kinds:
            assert where in allowed_variables, (
                f"{where}: a kind dura cannot read: {ast.unparse(expression)}"
            )
            continue
        for kind in kinds:
            if kind.endswith("*"):
                assert kind[:-1] in FAMILIES, f"{where}: unknown family {kind}"
            else:
                assert known(kind), f"{where}: {kind} is not in executive/bus/event_kinds.py"
            seen.add(kind)
    assert seen >= NAMED, f"listed but never logged: {sorted(NAMED - seen)}"
    assert {f"{p}*" for p in FAMILIES} <= seen, "a family nobody logs"


def test_each_family_holds_the_states_of_its_enum() -> None:
    assert FAMILIES["COMPONENT_"] == tuple(s.name for s in Lifecycle)
    assert FAMILIES["GOAL_"] == tuple(s.name for s in GoalState)
    assert FAMILIES["GOAL_RESULT_"] == tuple(s.name for s in GoalStatus)
    assert set(FAMILIES["TASK_"]) == {p.name for p in TaskPhase if p.final}


def test_composed_kinds_are_known_and_others_are_not() -> None:
    assert {"COMPONENT_READY", "GOAL_ACHIEVED", "GOAL_RESULT_CANCELLED", "TASK_FAILED"} <= KINDS
    assert not known("bogus")
    assert not known("TASK_WAITING")  # a phase, but no event ends a task in it
