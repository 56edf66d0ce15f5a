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
    made = make(folder, name)
    print(f"made {folder}/ with the robot '{name}': {', '.join(made)}")
    print(f"next: cd {folder} && dura validate robot.yaml && pytest")
    return 0


def make(folder: Path, name: str) -> list[str]:
    """Write the template robot named ``name`` into the new ``folder``; the files made,
    relative to it."""
    made = []
    for source in sorted(TEMPLATE.rglob("*")):
        if not source.is_file() or "__pycache__" in source.parts:
            continue
        relative = source.relative_to(TEMPLATE)
        target = folder / relative.with_name(relative.name.removesuffix(".tmpl"))
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(source.read_text().replace(PLACEHOLDER, name))
        made.append(target.relative_to(folder).as_posix())
    return made
