"""The documentation's table of the PDDL features each engine supports, computed from the
engines' own declarations (unified-planning's ``supported_kind()``).

Run ``.venv/bin/python -m tests.engine_features`` to print the table (with every engine
installed, ``pip install -e '.[tamer]'``, to have them all); the test beside the planner
tests checks the table in docs/explanation/planning.md against the engines installed where it runs.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

# A PDDL feature → the features of unified-planning's problem kind it needs (a problem
# that uses it has them). Constants and types need none: every engine has them.
FEATURES = {
    "durative actions": ("CONTINUOUS_TIME",),
    "durations from functions": ("STATIC_FLUENTS_IN_DURATIONS",),
    "duration inequalities": ("DURATION_INEQUALITIES",),
    "numeric fluents (real)": ("SIMPLE_NUMERIC_PLANNING", "REAL_FLUENTS"),
    "negative conditions": ("NEGATIVE_CONDITIONS",),
    "disjunctive conditions": ("DISJUNCTIVE_CONDITIONS",),
    "quantified conditions": ("EXISTENTIAL_CONDITIONS", "UNIVERSAL_CONDITIONS"),
    "conditional effects": ("CONDITIONAL_EFFECTS",),
    "timed initial literals": ("TIMED_EFFECTS",),
    "type hierarchies": ("HIERARCHICAL_TYPING",),
    "`:metric` makespan (optimised)": ("MAKESPAN",),
    "`:metric` action costs (optimised)": ("ACTIONS_COST",),
    "`:metric` final value (optimised)": ("FINAL_VALUE",),
}
PAGE = Path(__file__).resolve().parents[1] / "docs" / "explanation" / "planning.md"


def installed() -> dict[str, Any]:
    """The installed engines dura may choose, by name → their class, in dura's order."""
    from executive import fast_start

    fast_start.import_unified_planning()
    from executive.planning.planner_jobs import PlannerJobs

    return PlannerJobs(Path("/dev/null")).available()


def rows(engines: dict[str, Any]) -> list[list[str]]:
    """One row per PDDL feature: yes or no for each engine."""
    out = []
    for name, needs in FEATURES.items():
        cells = [
            "yes" if set(needs) <= set(e.supported_kind().features) else "no"
            for e in engines.values()
        ]
        out.append([name, *cells])
    return out


def table(engines: dict[str, Any]) -> str:
    lines = ["| PDDL feature | " + " | ".join(f"`{n}`" for n in engines) + " |"]
    lines.append("|---" * (len(engines) + 1) + "|")
    lines += ["| " + " | ".join(r) + " |" for r in rows(engines)]
    return "\n".join(lines)


def documented_table() -> tuple[list[str], dict[str, list[str]]]:
    """The documented table: its engine names, and each feature's cells."""
    text = PAGE.read_text(encoding="utf-8").splitlines()
    head = next(i for i, line in enumerate(text) if line.startswith("| PDDL feature |"))
    names = [c.strip().strip("`") for c in text[head].strip("|").split("|")][1:]
    cells = {}
    for line in text[head + 2 :]:
        if not line.startswith("|"):
            break
        parts = [c.strip() for c in line.strip("|").split("|")]
        cells[parts[0]] = parts[1:]
    return names, cells


if __name__ == "__main__":
    print(table(installed()))
