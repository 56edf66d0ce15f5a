"""The operator's verbs on a running robot: observers and exoneration, removing objects,
the domain, the event log of a knowledge base file, and what the quick commands import.

One use-case robot (a real ``dura run``) serves the whole module; each test puts back
what it changed.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.testing.harness import RobotProcess
from knowledge.knowledge_base import KnowledgeBase
from tests.benchmarks.cli import unlisted
from tests.conftest import ROOT, USECASE, run_dura

# What no quick command may load: solvers, planners, graphs, the web and DDS stacks.
HEAVY = (
    "clingo",
    "unified_planning",
    "up_kairos",
    "up_aries",
    "up_fast_downward",
    "networkx",
    "starlette",
    "uvicorn",
    "cyclonedds",
    "numpy",
    "scipy",
)
QUICK = (("status",), ("goal", "list"), ("component", "list"))
# What else each of them has no use for: the payloads of the components' states (the
# event kinds name the states alone), the wording of events.
UNNEEDED = {
    ("status",): {"executive.bus.payloads"},
    ("goal", "list"): {"executive.bus.payloads", "executive.bus.event_text"},
    ("component", "list"): {"executive.bus.event_text"},
}

OBSERVERS = """\
# two observers of lidar_filter's output
- type: timeout
  topics:
    - name: scan_filtered
      callerids:
        - {callerid: [], timeout: 1.0}
- type: frequency
  topics:
    - name: scan_filtered
      filter: {type: mean, window_size: 5}
      states:
        - {state: ok, number: 1, frequency: {type: in_between, lower_bound: 8, upper_bound: 12}}
"""


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RobotProcess]:
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("PYTHONPATH", str(ROOT))  # the components import the examples
        with RobotProcess(USECASE, tmp_path_factory.mktemp("operator")) as running:
            yield running


def dura(robot: RobotProcess, *args: str) -> subprocess.CompletedProcess[str]:
    """The dura command, run in the robot's folder (it finds the executive there)."""
    return run_dura(*args, cwd=robot.folder)


def observers(robot: RobotProcess) -> dict[str, dict[str, object]]:
    listed = dura(robot, "observer", "list", "--json")
    assert listed.returncode == 0, listed.stderr
    return {o["id"]: o for o in json.loads(listed.stdout)["observers"]}


# --- observers at run time -------------------------------------------------------------


def test_observer_list_shows_the_observers_of_the_robot_description(robot: RobotProcess) -> None:
    listed = dura(robot, "observer", "list")
    assert listed.returncode == 0, listed.stderr
    header, *rows = listed.stdout.splitlines()
    assert header.split() == ["ID", "TYPE", "COMPONENT", "ACTIVATED", "OBSERVING", "RATE",
                              "START-UP"]  # fmt: skip
    assert [row.split()[:5] for row in rows] == [
        ["lidar/0", "frequency", "lidar", "yes", "no"],  # lidar is not running
        ["lidar/1", "timeout", "lidar", "yes", "no"],
    ]


def test_observers_of_a_file_are_added_to_a_component_and_removed(
    robot: RobotProcess, tmp_path: Path
) -> None:
    path = tmp_path / "observers.yaml"
    path.write_text(OBSERVERS)
    added = dura(robot, "observer", "add", str(path), "--component", "lidar_filter")
    assert added.returncode == 0, added.stderr
    assert added.stdout.splitlines() == [
        "lidar_filter/0: timeout observer added (observes once lidar_filter is ready)",
        "lidar_filter/1: frequency observer added (observes once lidar_filter is ready)",
    ]
    listed = observers(robot)
    assert listed["lidar_filter/1"]["component"] == "lidar_filter"
    assert listed["lidar_filter/1"]["active"] is False
    for observer_id in ("lidar_filter/0", "lidar_filter/1"):
        removed = dura(robot, "observer", "remove", observer_id)
        assert (removed.returncode, removed.stdout) == (0, f"{observer_id}: removed\n")
    assert sorted(observers(robot)) == ["lidar/0", "lidar/1"]


def test_an_observer_of_its_own_observes_at_once_and_can_be_changed(
    robot: RobotProcess, tmp_path: Path
) -> None:
    path = tmp_path / "one.yaml"
    path.write_text(OBSERVERS.split("- type: frequency", maxsplit=1)[0])
    added = dura(robot, "observer", "add", str(path), "--name", "watchdog")
    assert (added.returncode, added.stdout) == (0, "watchdog: timeout observer added (observing)\n")
    try:
        changed = dura(robot, "observer", "change", "watchdog", str(path))
        assert changed.returncode == 0, changed.stderr
        assert changed.stdout == "watchdog: changed, starts afresh (observing)\n"
    finally:
        dura(robot, "observer", "remove", "watchdog")


def test_a_file_with_problems_adds_nothing_and_names_each_line(
    robot: RobotProcess, tmp_path: Path
) -> None:
    path = tmp_path / "bad.yaml"
    text = OBSERVERS.replace("timeout: 1.0", "timeoot: 1.0")
    path.write_text(text.replace("- type: frequency", "- type: hz!"))
    refused = dura(robot, "observer", "add", str(path))
    assert refused.returncode == 1
    assert f"{path}:6: unknown key 'timeoot'" in refused.stderr
    assert f"{path}:7: unknown observer type 'hz!'" in refused.stderr
    assert sorted(observers(robot)) == ["lidar/0", "lidar/1"]


def test_an_observer_the_executive_refuses_adds_nothing(
    robot: RobotProcess, tmp_path: Path
) -> None:
    path = tmp_path / "observers.yaml"
    path.write_text(OBSERVERS)
    refused = dura(robot, "observer", "add", str(path), "--component", "lidr")
    assert refused.returncode == 1
    assert refused.stderr.strip().endswith(
        "observers.yaml:2: no component 'lidr' in robot 'usecase' (did you mean 'lidar'?)"
    )
    named = dura(robot, "observer", "add", str(path), "--name", "one")  # but there are two
    assert named.returncode == 2 and "--name names one observer" in named.stderr
    assert sorted(observers(robot)) == ["lidar/0", "lidar/1"]


def test_an_observer_is_deactivated_and_activated_again(robot: RobotProcess) -> None:
    off = dura(robot, "observer", "deactivate", "lidar/0")
    assert (off.returncode, off.stdout) == (0, "lidar/0: deactivated\n")
    assert observers(robot)["lidar/0"]["enabled"] is False
    on = dura(robot, "observer", "activate", "lidar/0")
    assert (on.returncode, on.stdout) == (0, "lidar/0: activated (observes once lidar is ready)\n")
    assert observers(robot)["lidar/0"]["enabled"] is True
    unknown = dura(robot, "observer", "activate", "lidar/7")
    assert (unknown.returncode, unknown.stderr) == (
        1,
        "dura: no observer 'lidar/7' (did you mean 'lidar/1'?)\n",
    )


def test_exoneration_is_switched_on_and_off_at_run_time(robot: RobotProcess) -> None:
    shown = dura(robot, "observer", "exonerate")
    assert shown.stdout.startswith("exoneration off: ")
    on = dura(robot, "observer", "exonerate", "on", "--json")
    assert (on.returncode, json.loads(on.stdout)) == (0, {"on": True})
    assert dura(robot, "observer", "exonerate").stdout.startswith("exoneration on: ")
    off = dura(robot, "observer", "exonerate", "off")
    assert off.stdout.startswith("exoneration off: ")
    assert [e.data["on"] for e in robot.events("EXONERATION")] == [True, False]
    wrong = dura(robot, "observer", "exonerate", "maybe")
    assert wrong.returncode == 2


# --- objects and the domain ------------------------------------------------------------


def test_an_object_is_removed_with_every_fact_that_names_it(robot: RobotProcess) -> None:
    assert dura(robot, "object", "add", "garage", "place").returncode == 0
    robot.set_fact("(connected garage lab)")
    robot.set_fact("(= (travel_time garage lab) 4)")
    removed = dura(robot, "object", "remove", "garage")
    assert removed.returncode == 0, removed.stderr
    assert removed.stdout == (
        "object garage - place removed, and 2 facts: (connected garage lab), "
        "(= (travel_time garage lab) 4)\n"
    )
    assert "garage" not in " ".join(robot.facts())
    event = robot.events("OBJECT_REMOVED")[-1]
    assert (event.subject, event.data["type"]) == ("garage", "place")


def test_an_object_an_open_goal_or_an_integrity_rule_names_is_kept_with_the_reason(
    robot: RobotProcess,
) -> None:
    goal_id = robot.submit_goal("(picture_taken office)")  # seconds of work: open meanwhile
    try:
        refused = dura(robot, "object", "remove", "office")
        assert refused.returncode == 1
        assert refused.stderr.startswith(
            f"dura: object 'office' is in use: goal {goal_id} (picture_taken office) is "
        )
    finally:
        robot.cancel_goal(goal_id)
    dock = dura(robot, "object", "remove", "dock")
    assert dock.returncode == 1
    assert "integrity rule 'lidar_maintenance' (" in dock.stderr
    typo = dura(robot, "object", "remove", "offize")
    assert typo.stderr == "dura: no object 'offize' (did you mean 'office'?)\n"
    objects = json.loads(dura(robot, "state", "get", "--json").stdout)["objects"]
    assert {"dock", "lab", "office"} <= set(objects)


def test_the_domain_is_shown_from_the_running_robot_and_offline_alike(
    robot: RobotProcess,
) -> None:
    running = dura(robot, "domain", "show", "--json")
    assert running.returncode == 0, running.stderr
    domain = json.loads(running.stdout)
    actions = {a["name"]: a for a in domain["actions"]}
    assert actions["take_picture"]["duration"] == "(= ?duration 2)"
    assert (actions["take_picture"]["behavior"], actions["take_picture"]["blocked"]) == (
        "take_picture",
        None,
    )
    offline = run_dura("domain", "show", "--offline", "--robot", str(USECASE), "--json")
    assert offline.returncode == 0, offline.stderr
    assert {**json.loads(offline.stdout), "actions": None} == {**domain, "actions": None}
    table = dura(robot, "domain", "show").stdout
    assert re.search(
        r"move_to +\?from \?to - place +\(= \?duration \(travel_time \?from \?to\)\) +"
        r"move_to\(start=\?from, target=\?to\) +yes",
        table,
    )


# --- the event log of a knowledge base file --------------------------------------------


def test_events_are_read_from_a_knowledge_base_file(tmp_path: Path) -> None:
    path = tmp_path / "stopped.db"
    with KnowledgeBase(path) as kb:
        kb.log_event("GOAL_ADDED", "goal 1", {"expression": "(robot_at lab)"})
        kb.log_event("FAULT", "lidar", {"count": 1, "permanent": False, "reason": "exited"})
        kb.log_event("GOAL_ACHIEVED", "goal 1")
    shown = run_dura("events", "--db", str(path))
    assert shown.returncode == 0, shown.stderr
    assert [line.split(maxsplit=1)[1] for line in shown.stdout.splitlines()] == [
        "GOAL_ADDED             goal 1: (robot_at lab)",
        "FAULT                  lidar: fault 1: exited",
        "GOAL_ACHIEVED          goal 1",
    ]
    faults = run_dura("events", "--db", str(path), "--kind", "FAULT", "--json")
    assert [e["subject"] for e in json.loads(faults.stdout)["events"]] == ["lidar"]
    last = run_dura("events", "--db", str(path), "-n", "1", "--json")
    assert [e["kind"] for e in json.loads(last.stdout)["events"]] == ["GOAL_ACHIEVED"]


def test_events_of_a_missing_file_or_with_a_robot_too_are_refused(tmp_path: Path) -> None:
    missing = run_dura("events", "--db", str(tmp_path / "none.db"))
    assert (missing.returncode, missing.stderr) == (
        1,
        f"dura: {tmp_path / 'none.db'}: no knowledge base here\n",
    )
    both = run_dura("events", "--db", "x.db", "--robot", str(USECASE))
    assert both.returncode == 2


def test_the_log_of_a_running_robot_can_be_read_from_its_file(robot: RobotProcess) -> None:
    shown = run_dura("events", "--db", str(robot.kb_path), "--kind", "EXECUTIVE_STARTED")
    assert shown.returncode == 0, shown.stderr
    assert "EXECUTIVE_STARTED" in shown.stdout


# --- what the quick commands load ------------------------------------------------------


def imported(folder: Path, *args: str) -> set[str]:
    """The modules a dura command imports (``python -X importtime``), after it ran."""
    return python_imports(folder, "-m", "executive.cli", *args)


def python_imports(folder: Path, *argv: str) -> set[str]:
    """The modules ``python -X importtime ARGV`` imports, after it ran."""
    done = subprocess.run(
        [sys.executable, "-X", "importtime", *argv],
        capture_output=True,
        text=True,
        cwd=folder,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
        timeout=60,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    found = re.findall(r"^import time: +\d+ \| +\d+ \| +(\S+)$", done.stderr, re.MULTILINE)
    assert found, done.stderr[-2000:]
    return set(found)


@pytest.mark.parametrize("command", QUICK, ids=" ".join)
def test_a_quick_command_imports_no_solver_planner_or_graph_library(
    robot: RobotProcess, command: tuple[str, ...]
) -> None:
    modules = imported(robot.folder, *command)
    assert sorted(m for m in modules if m.split(".")[0] in HEAVY) == []
    # nor what it does not need: the robot description, logging, and inspect with its
    # parsers, copy (dataclasses names them: executive.fast_start defers them); the
    # replies it reads are records (knowledge.records, executive.bus.reports)
    unneeded = {"knowledge.description", "logging", "yaml", "inspect"}
    assert not modules & (unneeded | {"ast", "dis", "tokenize", "copy"})
    assert not modules & UNNEEDED[command]
    # nor anything of the standard library or elsewhere it did not need before
    # (tests/benchmarks/cli.py lists what it may)
    assert unlisted(modules, python_imports(robot.folder, "-c", "pass")) == []


def test_validate_reads_the_domain_without_any_planning_engine(tmp_path: Path) -> None:
    modules = imported(tmp_path, "validate", str(USECASE))
    engines = ("up_kairos", "up_aries", "up_fast_downward", "up_tamer", "clingo", "scipy")
    assert sorted(m for m in modules if m.split(".")[0] in engines) == []
    assert "unified_planning.io.pddl_reader" in modules  # it does read the PDDL
