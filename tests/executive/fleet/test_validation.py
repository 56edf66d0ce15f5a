"""A fleet description is read with file:line, and checked against its domain and each
of its robots' descriptions (``dura validate fleet.yaml``)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from executive.fleet.description import load_fleet, read_fleet
from executive.fleet.validation import check_fleet
from knowledge.errors import ConfigError
from tests.conftest import ROOT, run_dura

EXAMPLE = ROOT / "examples" / "fleet"


@pytest.fixture(name="depot")
def depot_fixture(tmp_path: Path) -> Path:
    """A copy of the example fleet to change."""
    folder = tmp_path / "depot"
    shutil.copytree(EXAMPLE, folder)  # the components' link copied as a folder
    return folder


def errors(path: Path) -> list[str]:
    return [str(f) for f in check_fleet(path).findings if f.is_error]


def replace(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new))


def test_the_example_fleet_is_valid_and_each_action_names_its_robot() -> None:
    check = check_fleet(EXAMPLE / "fleet.yaml")
    assert check.ok, check.findings
    assert check.actors == {"drive": "r", "pick": "r", "drop": "r"}
    assert sorted(check.robots) == ["r1", "r2", "r3"]
    assert check.fleet is not None
    assert check.fleet.robots["r2"].pddl_object == "r2"
    assert check.fleet.login_file(check.fleet.robots["r2"]) == EXAMPLE / ".dura/r2.fleet.bus.json"


def test_a_robot_without_a_task_for_an_action_it_may_carry_out_is_refused_at_its_line(
    depot: Path,
) -> None:
    replace(depot / "r2.yaml", '  pick:  {behavior: pick, goal: {crate: "?c", place: "?p"}}\n', "")
    assert errors(depot / "fleet.yaml") == [
        f"{depot / 'fleet.yaml'}:15: robot 'r2' may carry out action 'pick' ('r2' is a "
        "'robot'), but r2.yaml has no task for it"
    ]


def test_a_task_goal_naming_a_parameter_the_fleet_action_lacks_is_refused_in_the_robots_file(
    depot: Path,
) -> None:
    # the robot's own domain names the crate ?crate: valid alone, not with the fleet's
    replace(depot / "robot.pddl", "(?c - crate ?p - place)\n    :duration (= ?duration 2)",
            "(?crate - crate ?p - place)\n    :duration (= ?duration 2)")  # fmt: skip
    replace(depot / "robot.pddl", "(at start (holding ?c)))", "(at start (holding ?crate)))")
    replace(depot / "robot.pddl", "(not (holding ?c))) (at end (crate_at ?c ?p))",
            "(not (holding ?crate))) (at end (crate_at ?crate ?p))")  # fmt: skip
    for robot in ("r1", "r2", "r3"):
        replace(depot / f"{robot}.yaml", 'drop, goal: {crate: "?c"', 'drop, goal: {crate: "?crate"')
    found = errors(depot / "fleet.yaml")
    assert len(found) == 3
    assert found[0] == (
        f"{depot / 'r1.yaml'}:31: goal field 'crate' of task 'drop' names '?crate', which "
        "action 'drop' of fleet domain 'depot' lacks (it has ?r, ?c, ?p)"
    )


def test_robots_that_do_not_fit_the_fleet_are_refused_each_at_its_line(depot: Path) -> None:
    (depot / "fleet.yaml").write_text(
        "fleet: f\ndomain: depot.pddl\nproblem: problem.pddl\nrobots:\n"
        "  r1: {description: r2.yaml}\n"  # line 5: named otherwise
        "  r2: {description: r2.yaml, object: parcel1}\n"  # line 6: a crate
        "  r4: {description: r3.yaml}\n"  # line 7: named otherwise
        "actions:\n  drive: {robot: '?x'}\n"  # line 9: no such parameter
        "robot_type: robots\n"  # line 10
    )
    assert errors(depot / "fleet.yaml") == [
        f"{depot / 'fleet.yaml'}:10: robot type 'robots' is no type of domain 'depot' "
        "(types: robot, place, crate)"
    ]
    replace(depot / "fleet.yaml", "robot_type: robots\n", "")
    path = depot / "fleet.yaml"
    assert errors(path) == [
        f"{path}:5: robot 'r1': its description names robot 'r2'",
        f"{path}:6: robot 'r2': object 'parcel1' is a 'crate', not a 'robot'",
        f"{path}:7: robot 'r4': its description names robot 'r3'",
        f"{path}:9: action 'drive' has no parameter '?x' (it has ?r, ?from, ?to)",
    ]


def test_a_fleet_file_with_problems_is_read_with_their_lines(tmp_path: Path) -> None:
    path = tmp_path / "fleet.yaml"
    path.write_text("fleet: a b\nrobots: {}\nmax_failures: 0\n")
    fleet, findings = read_fleet(path)
    assert fleet is None
    assert [str(f) for f in findings if f.is_error] == [
        f"{path}:1: the fleet description has no 'domain'",
        f"{path}:3: 'max_failures' of the fleet description must be at least 1, not 0",
        f"{path}:1: fleet name 'a b' must be a letter, then up to 63 letters, digits, '_' or '-'",
        f"{path}:2: a fleet needs at least one robot",
    ]
    with pytest.raises(ConfigError, match="has no 'domain'"):
        load_fleet(path)


def test_dura_validate_checks_a_fleet_and_says_where_it_does_not_fit(depot: Path) -> None:
    valid = run_dura("validate", "fleet.yaml", cwd=depot)
    assert valid.returncode == 0, valid.stderr
    assert valid.stdout.startswith("fleet.yaml: valid: fleet 'depot', 3 robots (r1, r2, r3)")
    replace(
        depot / "fleet.yaml",
        "r3: {description: r3.yaml}",
        "r3: {description: r3.yaml, object: dock3}",
    )
    refused = run_dura("validate", "fleet.yaml", "--json", cwd=depot)
    assert refused.returncode == 1
    report = json.loads(refused.stdout)
    assert report["valid"] is False
    assert [(f["line"], f["message"]) for f in report["findings"]] == [
        (13, "object 'r3' of type 'robot' is no robot of the fleet: no plan gives it a step"),
        (16, "robot 'r3': object 'dock3' is a 'place', not a 'robot'"),
    ]
