"""Which engine plans for a problem: from what each installed engine declares it supports
(unified-planning's ``supported_kind()``) and what the problem needs (``problem.kind``).

Nothing here says what an engine can do: every answer is computed from the engines'
own declarations, so a new engine (an extra, a plugin) is chosen as soon as it is
installed. A problem's metric is the one feature an engine may lack and still plan: it
then plans without optimising, and says so. Only the planner's worker process imports
this module (it needs unified-planning's engine classes).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from unified_planning.model.problem_kind import FEATURES

# The features a metric adds to a problem's kind: without them the problem is the same,
# only not optimised.
METRIC_FEATURES = frozenset(
    f
    for group in ("QUALITY_METRICS", "ACTIONS_COST_KIND", "OVERSUBSCRIPTION_KIND")
    for f in FEATURES[group]
)

# How a feature reads in a refusal; the others read as their lower-case names.
_WORDS = {
    "TIMED_EFFECTS": "timed initial literals",
    "TIMED_GOALS": "timed goals",
    "CONDITIONAL_EFFECTS": "conditional effects",
    "NEGATIVE_CONDITIONS": "negative conditions",
    "DISJUNCTIVE_CONDITIONS": "disjunctive conditions",
    "EXISTENTIAL_CONDITIONS": "existential conditions",
    "UNIVERSAL_CONDITIONS": "universal conditions",
    "FORALL_EFFECTS": "forall effects",
    "CONTINUOUS_TIME": "durative actions",
    "DURATION_INEQUALITIES": "duration inequalities",
    "FLUENTS_IN_DURATIONS": "durations computed from functions",
    "STATIC_FLUENTS_IN_DURATIONS": "durations computed from static functions",
    "REAL_FLUENTS": "numeric functions",
    "INT_FLUENTS": "integer functions",
    "INCREASE_EFFECTS": "increase effects",
    "DECREASE_EFFECTS": "decrease effects",
    "SIMPLE_NUMERIC_PLANNING": "numeric fluents",
    "GENERAL_NUMERIC_PLANNING": "general numeric fluents",
    "HIERARCHICAL_TYPING": "type hierarchies",
    "MAKESPAN": "a makespan metric",
    "ACTIONS_COST": "action costs",
    "FINAL_VALUE": "a final-value metric",
    "PLAN_LENGTH": "a plan-length metric",
    "INTERMEDIATE_CONDITIONS_AND_EFFECTS": "conditions or effects in the middle of actions",
}


def feature_words(feature: str) -> str:
    """A feature of UP's problem kind as a refusal names it: ``timed initial literals
    (TIMED_EFFECTS)``."""
    words = _WORDS.get(feature, feature.lower().replace("_", " "))
    return f"{words} ({feature})"


def lacking(engine: Any, features: Iterable[str]) -> list[str]:
    """The features an engine class does not declare it supports, sorted."""
    supported = engine.supported_kind().features
    return sorted(f for f in features if f not in supported)


@dataclass(frozen=True)
class Choice:
    """An engine for a problem: its name, or ``refusal`` (one line) when none fits;
    ``unoptimised``: it plans without the problem's metric (a note for the log)."""

    engine: str = ""
    refusal: str = ""
    unoptimised: str = ""


def choose(wanted: Sequence[str], installed: Mapping[str, Any], features: Iterable[str]) -> Choice:
    """The first of the ``wanted`` engines (in order) that supports every feature, else
    the first that supports all but the metric, else a refusal naming the features and
    the installed engines that support them.

    Args:
        wanted: engine names, in the order of preference (one name: that engine).
        installed: every installed engine name → its UP engine class.
        features: the problem kind's features.
    """
    needed = set(features)
    usable = [n for n in wanted if n in installed]
    for name in usable:
        if not lacking(installed[name], needed):
            return Choice(name)
    for name in usable:
        missing = lacking(installed[name], needed)
        if missing and set(missing) <= METRIC_FEATURES:
            better = _supporters(installed, missing)
            note = (
                f"{name} does not optimise {', '.join(feature_words(f) for f in missing)}: "
                f"the plan is the first it found"
                + (f" (engines that optimise it: {', '.join(better)})" if better else "")
            )
            return Choice(name, unoptimised=note)
    return Choice(refusal=refusal(wanted, installed, needed))


def refusal(wanted: Sequence[str], installed: Mapping[str, Any], needed: set[str]) -> str:
    """One line: what each wanted engine lacks, and which installed engines plan with the
    whole problem (or, if none, which support what the first one lacks)."""
    plain = needed - METRIC_FEATURES
    whole = _supporters(installed, sorted(plain))
    parts = []
    for name in wanted:
        if name not in installed:
            continue
        missing = [f for f in lacking(installed[name], needed) if f not in METRIC_FEATURES]
        parts.append(f"{name} does not support {', '.join(feature_words(f) for f in missing)}")
    absent = [n for n in wanted if n not in installed]
    if absent:
        parts.append(f"not installed: {', '.join(absent)}")
    text = "; ".join(parts) or "no engine is installed"
    if whole:
        return f"{text} (installed engines that do: {', '.join(whole)})"
    return f"{text} (no installed engine supports all of this problem)"


def _supporters(installed: Mapping[str, Any], features: Sequence[str]) -> list[str]:
    return [n for n, engine in installed.items() if not lacking(engine, features)]
