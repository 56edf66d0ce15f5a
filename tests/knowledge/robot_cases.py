"""A registry of broken robot descriptions and the one finding each must produce.

Each case edits the use-case description (or its domain) and names the line and
message ``dura validate`` must report. Tests and docs share it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from tests.conftest import ROOT

USECASE_YAML = (ROOT / "examples" / "usecase" / "robot.yaml").read_text()
USECASE_DOMAIN = (ROOT / "domains" / "usecase" / "domain.pddl").read_text()


@dataclass(frozen=True)
class BrokenRobot:
    name: str
    old: str  # text of the use case to replace (once)
    new: str
    line_of: str  # the finding's line is the line that contains this text after the edit
    message: str  # a fragment of the finding's message
    in_domain: bool = False  # the edit is in the PDDL domain, and so is the finding

    def write(self, folder: Path) -> Path:
        """Write the broken robot (and its domain) to a folder; returns the robot file."""
        domain = USECASE_DOMAIN
        robot = USECASE_YAML.replace("../../domains/usecase/domain.pddl", "domain.pddl")
        for key, name in (
            ("problem", "problem.pddl"),
            ("integrity", "[integrity.yaml]"),
            ("rules", "[rules.yaml]"),
        ):
            absolute = name.replace(
                name.strip("[]"), str(ROOT / "examples/usecase" / name.strip("[]"))
            )
            robot = robot.replace(f"{key}: {name}", f"{key}: {absolute}")
        if self.in_domain:
            assert self.old in domain, self.name
            domain = domain.replace(self.old, self.new, 1)
        else:
            assert self.old in robot, self.name
            robot = robot.replace(self.old, self.new, 1)
        (folder / "domain.pddl").write_text(domain)
        components = folder / "components"  # the commands start them: they must exist
        if not components.exists():
            components.symlink_to(ROOT / "examples" / "usecase" / "components")
        path = folder / "robot.yaml"
        path.write_text(robot)
        return path

    def expected_line(self, folder: Path) -> int:
        text = (folder / ("domain.pddl" if self.in_domain else "robot.yaml")).read_text()
        return text[: text.index(self.line_of)].count("\n") + 1


BROKEN_ROBOTS = [
    BrokenRobot(
        "bad YAML",
        "    requires: [laser_scan]",
        "    requires: [laser_scan]]",
        "requires: [laser_scan]]",
        "invalid YAML",
    ),
    BrokenRobot(
        "unknown capability",
        "    requires: [laser_scan]",
        "    requires: [laser_scna]",
        "requires: [laser_scna]",
        "functionality 'lidar_filter' requires unknown capability 'laser_scna' (did you mean 'laser_scan'?)",
    ),
    BrokenRobot(
        "requires cycle",
        "    provides: [laser_scan]",
        "    provides: [laser_scan]\n    requires: [obstacle_scan]",
        "requires: [obstacle_scan]",
        "requires cycle: lidar -> lidar_filter -> lidar",
    ),
    BrokenRobot(
        "task for a missing action",
        "tasks:\n  move_to:",
        "tasks:\n  move_too:",
        "move_too:",
        "task 'move_too' names no action of domain 'usecase' (did you mean 'move_to'?)",
    ),
    BrokenRobot(
        "PDDL syntax error",
        "(picture_taken ?p - place)",
        "(picture_taken ?p - place",
        "(picture_taken ?p - place",
        "'(picture_taken' is not closed before '(photographable' at line 12 (a ')' is missing)",
        in_domain=True,
    ),
    BrokenRobot(
        "AB-prefixed name",
        "  cam:\n",
        "  ABcam:\n",
        "ABcam:",
        "functionality name 'ABcam' must not start with 'AB'",
    ),
    BrokenRobot(
        "AB-prefixed topic",
        "publishes: [image]",
        "publishes: [ABimage]",
        "publishes: [ABimage]",
        "topic 'ABimage' of functionality 'cam' must not start with 'AB'",
    ),
    BrokenRobot(
        "bad may_subscribe pattern",
        "publishes: [image]",
        "publishes: [image]\n    may_subscribe: ['**/**']",
        "may_subscribe: ['**/**']",
        "may_subscribe '**/**' of functionality 'cam' must be a topic name or a pattern",
    ),
    BrokenRobot(
        "may_subscribe with a space",
        "publishes: [image]",
        "publishes: [image]\n    may_subscribe: [odom, 'camera info']",
        "may_subscribe: [odom",
        "may_subscribe 'camera info' of functionality 'cam' must be a topic name or a pattern",
    ),
    BrokenRobot(
        "unknown key",
        "    shareable: false",
        "    sharable: false",
        "sharable: false",
        "unknown key 'sharable' in functionality 'robot_base' (did you mean 'shareable'?)",
    ),
    BrokenRobot(
        "wrong type",
        "    max_faults: 3\n    params: {rate: 20.0}",
        "    max_faults: three\n    params: {rate: 20.0}",
        "max_faults: three",
        "'max_faults' of functionality 'robot_base' must be an integer, not 'three'",
    ),
    BrokenRobot(
        "duplicate name",
        "  take_picture:\n    command",
        "  move_to:\n    command",
        "  move_to:\n    command: [python, -m, components.take_picture]",
        "duplicate key 'move_to'",
    ),
    BrokenRobot(
        "unknown goal parameter",
        "      target: ?to",
        "      target: ?destination",
        "target: ?destination",
        "goal field 'target' of task 'move_to' names unknown parameter '?destination'",
    ),
    BrokenRobot(
        "unknown behavior",
        "    behavior: take_picture",
        "    behavior: take_photo",
        "behavior: take_photo",
        "task 'take_picture' names unknown behavior 'take_photo' (did you mean 'take_picture'?)",
    ),
    BrokenRobot(
        "missing command",
        "    command: [python, -m, components.cam]\n",
        "",
        "  cam:",
        "functionality 'cam' has no 'command'",
    ),
    BrokenRobot(
        "unknown predicate in the domain",
        "(at start (photographable ?p))",
        "(at start (photogenic ?p))",
        "(photogenic ?p)",
        "unknown predicate 'photogenic'",
        in_domain=True,
    ),
    BrokenRobot(
        "robot name that is a path",
        "robot: usecase",
        "robot: ../../evil",
        "robot: ../../evil",
        "robot name '../../evil' must be a letter, then up to 63 letters, digits, '_' or '-'",
    ),
    BrokenRobot(
        "component name that is a path",
        "  cam:\n",
        "  ../../x:\n",
        "../../x:",
        "functionality name '../../x' must be a letter, then up to 63 letters",
    ),
    BrokenRobot(
        "topic with key syntax",
        "publishes: [image]",
        "publishes: ['image/**']",
        "publishes: ['image/**']",
        "topic 'image/**' of functionality 'cam' must be names of letters, digits and '_'",
    ),
    BrokenRobot(
        "command as one string",
        "    command: [python, -m, components.cam]",
        "    command: python -m components.cam",
        "command: python -m components.cam",
        "functionality 'cam': command 'python -m components.cam' is one string with spaces: "
        "write it as a list: [python, -m, components.cam]",
    ),
    BrokenRobot(
        "command with a missing module",
        "    command: [python, -m, components.cam]",
        "    command: [python, -m, components.camera]",
        "command: [python, -m, components.camera]",
        "functionality 'cam': no Python module 'components.camera'",
    ),
    BrokenRobot(
        "command with a missing program",
        "    command: [python, -m, components.cam]",
        "    command: [camera-driver, --fast]",
        "command: [camera-driver, --fast]",
        "functionality 'cam': program 'camera-driver' is not on this machine's PATH",
    ),
]
