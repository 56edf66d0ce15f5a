"""``dura new NAME``: a robot folder that validates, plans and passes its own
planner-in-the-loop test as it is; a bad name or a folder already there is refused in
one line, with nothing made."""

from __future__ import annotations

import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from executive.testing import RobotProcess
from tests.conftest import ROOT

Dura = Callable[..., subprocess.CompletedProcess[str]]


def test_a_new_robot_validates_and_its_domain_has_a_type_hierarchy(
    dura: Dura, tmp_path: Path
) -> None:
    made = dura("new", "rover", cwd=tmp_path)
    assert made.returncode == 0, made.stderr
    assert made.stdout.startswith("made rover/ with the robot 'rover': components/__init__.py, ")
    folder = tmp_path / "rover"
    assert (folder / "components" / "drive.py").is_file()
    assert not list(folder.rglob("*.tmpl"))
    assert "robot: rover\n" in (folder / "robot.yaml").read_text()
    assert "(:types room dock - place" in (folder / "domain.pddl").read_text()
    valid = dura("validate", "robot.yaml", cwd=folder)
    assert valid.returncode == 0, valid.stdout + valid.stderr
    assert valid.stdout.startswith("robot.yaml: valid: robot 'rover', 2 functionalities")


@pytest.mark.parametrize(
    ("name", "said"),
    [
        ("My Robot", "dura: 'My Robot' is not a robot name: use lowercase letters"),
        ("taken", "dura: taken: already there (dura new makes a new folder)"),
    ],
)
def test_a_bad_name_or_a_folder_already_there_is_refused_in_one_line(
    dura: Dura, tmp_path: Path, name: str, said: str
) -> None:
    (tmp_path / "taken").mkdir()
    refused = dura("new", name, cwd=tmp_path)
    assert refused.returncode == 1
    assert refused.stderr.startswith(said) and len(refused.stderr.splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["taken"]
    assert list((tmp_path / "taken").iterdir()) == []


@pytest.mark.slow
def test_a_new_robot_passes_its_own_planner_in_the_loop_test(dura: Dura, tmp_path: Path) -> None:
    assert dura("new", "rover", cwd=tmp_path).returncode == 0
    ran = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider"],
        cwd=tmp_path / "rover",
        capture_output=True,
        text=True,
        timeout=240,
        check=False,
    )
    assert ran.returncode == 0, ran.stdout + ran.stderr
    assert "1 passed" in ran.stdout


def test_a_copied_example_says_exactly_what_to_change_and_then_validates(
    dura: Dura, tmp_path: Path
) -> None:
    copied = tmp_path / "myrobot"
    shutil.copytree(ROOT / "examples" / "usecase", copied)
    refused = dura("validate", "robot.yaml", cwd=copied)
    assert refused.returncode == 1
    assert refused.stderr == (
        "robot.yaml:10: 'domain' names no file: ../../domains/usecase/domain.pddl (that is "
        f"{tmp_path.parent / 'domains' / 'usecase' / 'domain.pddl'}); copied from elsewhere? "
        f"copy domain.pddl into {copied} and write 'domain: domain.pddl'\n"
    )
    # as it says
    shutil.copy(ROOT / "domains" / "usecase" / "domain.pddl", copied)
    description = copied / "robot.yaml"
    description.write_text(
        description.read_text().replace(
            "domain: ../../domains/usecase/domain.pddl", "domain: domain.pddl"
        )
    )
    valid = dura("validate", "robot.yaml", cwd=copied)
    assert valid.returncode == 0, valid.stderr


@pytest.mark.slow
def test_a_new_ros2_robot_validates_and_passes_its_own_test_over_ros2(
    dura: Dura, tmp_path: Path
) -> None:
    made = dura("new", "--ros2", "patroller", cwd=tmp_path)
    assert made.returncode == 0, made.stderr
    folder = tmp_path / "patroller"
    assert (folder / "nodes" / "navigator.py").is_file()
    assert (folder / "msgs" / "nav2_msgs" / "action" / "NavigateToPose.action").is_file()
    assert "(:types room dock - place" in (folder / "domain.pddl").read_text()
    valid = dura("validate", "robot.yaml", cwd=folder)
    assert valid.returncode == 0, valid.stdout + valid.stderr
    ran = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider"],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=240,
        check=False,
    )
    assert ran.returncode == 0, ran.stdout + ran.stderr


@pytest.mark.slow
def test_a_goal_failed_by_a_bug_says_the_exception_and_where_the_traceback_is(
    dura: Dura, tmp_path: Path, dura_robot: Callable[..., RobotProcess]
) -> None:
    assert dura("new", "buggy", cwd=tmp_path).returncode == 0
    drive = tmp_path / "buggy" / "components" / "drive.py"
    code = drive.read_text()
    drive.write_text(
        code.replace('self.latest["odom"]["distance"] - start', 'self.latest["odom"]["celsius"]')
    )
    robot = dura_robot(tmp_path / "buggy" / "robot.yaml", time_scale=10,
                       changes={"behaviors": {"drive": {"max_restarts": 0}}})  # fmt: skip
    goal = robot.submit_goal("(inspected kitchen)")
    failed = robot.wait_for(goal, "failed", timeout=120)
    assert failed.reason.endswith("failed: KeyError: 'celsius' (dura component logs drive)")
    shown = dura("goal", "show", str(goal), cwd=robot.folder)
    assert "KeyError: 'celsius' (dura component logs drive)" in shown.stdout, shown.stdout
    logs = dura("component", "logs", "drive", cwd=robot.folder)
    assert "Traceback (most recent call last):" in logs.stdout
    assert "KeyError: 'celsius'" in logs.stdout
