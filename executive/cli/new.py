"""``dura new NAME``: a robot folder to start from, which runs as it is.

The files come from ``executive/cli/new_robot/`` (package data): a robot description,
a domain with a small type hierarchy, a problem, repair rules, simulated components
and a planner-in-the-loop test, each commented with what to change. ``ROBOT_NAME`` in
them becomes the robot's name; a ``.tmpl`` suffix (which keeps dura's own checks off
the templates) is dropped.
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path
from typing import Any

from knowledge.errors import DuraError

TEMPLATE = Path(__file__).with_name("new_robot")
ROS2_TEMPLATE = Path(__file__).with_name("new_robot_ros2")
ROS2_EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "ros2"
ROS2_PARTS = ("nodes", "msgs")  # of the example: the stand-in nodes, nav2's interface files
NAME = re.compile(r"[a-z][a-z0-9_]*")
PLACEHOLDER = "ROBOT_NAME"


def register(sub: Any) -> None:
    p = sub.add_parser(
        "new",
        help="make a folder with a robot to start from (it runs and passes its test)",
        description="Make the folder NAME with a robot of that name: its description "
        "(robot.yaml), domain and problem (PDDL), repair rules, simulated components and "
        "a test with the planner in the loop (test_robot.py). It validates, runs and "
        "passes its test as it is; the comments in each file say what to change.",
    )
    p.add_argument(
        "name",
        metavar="NAME",
        help="the folder to make; its last part is the robot's name (lowercase letters, "
        "digits and _, starting with a letter)",
    )
    p.add_argument(
        "--ros2",
        action="store_true",
        help="a robot whose drivers are ROS 2 nodes (stand-ins that run without ROS), its "
        "behaviors a ROS 2 action and a ROS 2 service",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    folder = Path(args.name)
    name = folder.name
    if not NAME.fullmatch(name):
        raise DuraError(
            f"'{name}' is not a robot name: use lowercase letters, digits and _, "
            "starting with a letter (it names the robot, its domain and its bus keys)"
        )
    if folder.exists():
        raise DuraError(f"{folder}: already there (dura new makes a new folder)")
    if args.ros2 and not all((ROS2_EXAMPLE / part).is_dir() for part in ROS2_PARTS):
        raise DuraError(
            f"dura new --ros2 copies the ROS 2 stand-in nodes of {ROS2_EXAMPLE}, which is "
            "not here: run it from a dura checkout"
        )
    made = make(folder, name, ros2=args.ros2)
    print(f"made {folder}/ with the robot '{name}': {', '.join(made)}")
    print(f"next: cd {folder} && dura validate robot.yaml && pytest")
    return 0


def make(folder: Path, name: str, *, ros2: bool = False) -> list[str]:
    """Write the template robot named ``name`` into the new ``folder``; the files made,
    relative to it."""
    sources = [(ROS2_TEMPLATE if ros2 else TEMPLATE, "")]
    sources += [(ROS2_EXAMPLE / part, part) for part in ROS2_PARTS] if ros2 else []
    made = []
    for root, into in sources:
        for source in sorted(root.rglob("*")):
            if not source.is_file() or "__pycache__" in source.parts:
                continue
            relative = Path(into) / source.relative_to(root)
            target = folder / relative.with_name(relative.name.removesuffix(".tmpl"))
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(source.read_text().replace(PLACEHOLDER, name))
            made.append(target.relative_to(folder).as_posix())
    return sorted(made)
