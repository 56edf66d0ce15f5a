"""Diagnostics for domain authors, beyond syntax (``dura domain check DOMAIN [PROBLEM]``).

Every finding is a warning at the line it is about:

- a predicate that actions or the goal need but no action adds: one that some action
  deletes can be used up for good; with a problem, one the initial state does not hold
  either can never hold;
- with a problem, an action that can never be applied from its initial state, and a
  goal atom that can never hold, by relaxed reachability
  (:mod:`executive.planning.reachability`);
- a type, predicate or function that nothing uses.
"""

from __future__ import annotations

import re
from collections import defaultdict
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from executive.planning.expression import And
from executive.planning.problem import BOOKKEEPING, from_fnode
from executive.planning.reachability import (
    GroundAction,
    Reachability,
    closure,
    ground,
    possible,
    problem_facts,
)
from knowledge.domain import parse, parse_problem, read_domain
from knowledge.errors import DomainError, located
from knowledge.finding import Finding, Report
from knowledge.sources import read_text

if TYPE_CHECKING:
    from unified_planning.model import Problem


@dataclass
class _Uses:
    """Which predicates and functions the actions and the goal use, and how."""

    needed: defaultdict[str, set[str]] = field(default_factory=lambda: defaultdict(set))
    added: defaultdict[str, set[str]] = field(default_factory=lambda: defaultdict(set))
    deleted: defaultdict[str, set[str]] = field(default_factory=lambda: defaultdict(set))
    mentioned: set[str] = field(default_factory=set)


def check_domain(domain: Path, problem: Path | None = None) -> list[Finding]:
    """Return every warning about a domain (and a problem of it), in file and line order.

    Raises:
        DomainError: a file cannot be read or is not valid PDDL (``file:line``).
    """
    info = read_domain(domain)
    lifted = parse(domain)
    text = read_text(domain)
    report = Report(str(domain))
    uses = _Uses()
    for action in lifted.actions:
        _action_uses(action, uses)
    ground_problem: Problem | None = None
    problem_report = Report(str(problem)) if problem is not None else None
    init: set[str] = set()
    if problem is not None:
        try:
            problem_text = read_text(problem)
        except (OSError, UnicodeDecodeError) as e:
            raise DomainError(located(problem, None, f"cannot read: {e}")) from e
        ground_problem = parse_problem(domain, problem_text, str(problem))
        for goal in ground_problem.goals:
            _walk(goal, True, "the goal", uses.needed, uses.mentioned)
        for fluent_exp, value in ground_problem.explicit_initial_values.items():
            name = fluent_exp.fluent().name
            uses.mentioned.add(name)
            if not value.is_bool_constant() or value.bool_constant_value():
                init.add(name)
    predicate_lines = _declared_lines(text, ":predicates", [*info.predicates])
    function_lines = _declared_lines(text, ":functions", [*info.functions])
    for name in sorted(info.predicates):
        line = predicate_lines.get(name)
        if name not in uses.mentioned:
            report.warning(line, f"predicate '{name}' is not used by any action or the problem")
            continue
        needers = sorted(uses.needed.get(name, ()))
        if not needers or uses.added.get(name):
            continue
        who = ", ".join(needers)
        if uses.deleted.get(name):
            deleters = ", ".join(sorted(uses.deleted[name]))
            report.warning(
                line,
                f"predicate '{name}' is needed by {who} and deleted by {deleters}, "
                "but no action adds it: once used up it never holds again",
            )
        elif problem is not None and name not in init:
            report.warning(
                line,
                f"predicate '{name}' is needed by {who}, but no action adds it and the "
                f"initial state of {problem.name} has none: it never holds",
            )
    for name in sorted(info.functions):
        if name not in uses.mentioned:
            report.warning(
                function_lines.get(name),
                f"function '{name}' is not used by any action or the problem",
            )
    used_types = _used_types(lifted, ground_problem)
    type_lines = _declared_lines(text, ":types", list(info.types))
    for name in info.types:
        if name not in used_types:
            report.warning(type_lines.get(name), f"type '{name}' is not used")
    if ground_problem is not None and problem_report is not None and problem is not None:
        _reachability(ground_problem, info.actions, report, problem_report, problem)
    findings = report.findings + (problem_report.findings if problem_report else [])
    return sorted(findings, key=lambda f: (f.path != str(domain), f.line or 0, f.message))


def _reachability(
    problem: Problem, actions: Any, report: Report, problem_report: Report, path: Path
) -> None:
    grounded = ground(problem)
    if grounded is None:
        report.warning(None, "the problem is too large to check reachability")
        return
    reach = closure(grounded, problem_facts(problem))
    never: dict[str, list[GroundAction]] = defaultdict(list)
    applied = {grounded[i].name for i in reach.applied}
    for action in reach.never_applied():
        if action.name not in applied and not action.name.startswith(BOOKKEEPING):
            never[action.name].append(action)
    for name, instances in sorted(never.items()):
        info = actions.get(name)
        example = instances[0]
        lacking = _lacking_atoms(reach, example)
        why = f": e.g. {example.label} needs {lacking}" if lacking else ""
        report.warning(
            info.line if info is not None else None,
            f"action '{name}' can never be applied from the initial state of {path.name}{why}",
        )
    goal_line = _goal_line(path)
    for goal in problem.goals:
        for part in reach.missing(from_fnode(goal, problem)):
            problem_report.warning(goal_line, f"goal: {reach.explain(part)}")


def _lacking_atoms(reach: Reachability, action: GroundAction) -> str:
    """Return the conditions that keep a ground action from being applied (two at most)."""
    parts: list[str] = []
    during = reach.reached | action.start_adds
    for condition, known in ((action.before, reach.reached), (action.during, during)):
        items = condition.args if isinstance(condition, And) else (condition,)
        parts.extend(str(p) for p in items if not possible(p, known))
    return " and ".join(parts[:2])


def _action_uses(action: Any, uses: _Uses) -> None:
    name = action.name
    if hasattr(action, "preconditions"):
        conditions = list(action.preconditions)
        effects = list(action.effects)
    else:
        conditions = [c for cs in action.conditions.values() for c in cs]
        effects = [e for es in action.effects.values() for e in es]
    duration = getattr(action, "duration", None)  # durations may name functions
    for bound in (duration.lower, duration.upper) if duration is not None else ():
        _walk(bound, False, name, uses.needed, uses.mentioned)
    for condition in conditions:
        _walk(condition, True, name, uses.needed, uses.mentioned)
    for effect in effects:
        _walk(effect.condition, True, name, uses.needed, uses.mentioned)
        fluent = effect.fluent.fluent().name
        uses.mentioned.add(fluent)
        _walk(effect.value, True, name, uses.needed, uses.mentioned)
        value = effect.value
        if value.is_bool_constant():
            (uses.added if value.bool_constant_value() else uses.deleted)[fluent].add(name)
        else:
            uses.added[fluent].add(name)  # a numeric effect


def _walk(
    node: Any, positive: bool, who: str, needed: defaultdict[str, set[str]], mentioned: set[str]
) -> None:
    """Note every fluent a condition names; those it needs true, under ``needed``."""
    if node.is_fluent_exp():
        name = node.fluent().name
        mentioned.add(name)
        if positive and node.fluent().type.is_bool_type():
            needed[name].add(who)
    flip = node.is_not()
    for arg in node.args:
        _walk(arg, positive != flip, who, needed, mentioned)


def _used_types(domain: Problem, problem: Problem | None) -> set[str]:
    """Return every type a parameter, signature, constant or object names, with their
    ancestors and the subtypes of them all."""
    named: list[Any] = []
    for action in domain.actions:
        named.extend(p.type for p in action.parameters)
    for fluent in domain.fluents:
        named.extend(p.type for p in fluent.signature)
    for obj in (problem or domain).all_objects:
        named.append(obj.type)
    used: set[str] = set()
    for declared in named:
        current = declared
        while current is not None and current.is_user_type():
            used.add(str(current.name))
            current = current.father
    # a subtype of a type in use is there for objects of it: `truck - vehicle` when
    # actions take a vehicle
    for kind in domain.user_types:
        ancestor = kind.father
        while ancestor is not None and str(kind.name) not in used:
            if str(ancestor.name) in used:
                used.add(str(kind.name))
            ancestor = ancestor.father
    return used


def _declared_lines(text: str, section: str, names: Iterable[str]) -> dict[str, int]:
    """Find the line of each name's first mention after a section keyword (``:predicates``)."""
    start = text.lower().find(section)
    if start < 0:
        return {}
    first = text.count("\n", 0, start) + 1
    lines = text[start:].splitlines()
    out: dict[str, int] = {}
    for name in names:
        word = re.compile(rf"(?<![\w?-]){re.escape(name)}(?![\w-])", re.IGNORECASE)
        for offset, line in enumerate(lines):
            if word.search(line.split(";", 1)[0]):
                out[name] = first + offset
                break
    return out


def _goal_line(path: Path) -> int | None:
    text = read_text(path)
    at = text.lower().find("(:goal")
    return None if at < 0 else text.count("\n", 0, at) + 1
