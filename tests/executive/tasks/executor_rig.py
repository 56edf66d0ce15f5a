"""What the task executor's process tests share: a robot whose camera starts slowly,
and a task executor on a launcher with a real bus and knowledge base."""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Iterator
from pathlib import Path

from executive.bus.clock import Clock
from executive.bus.service import Context
from executive.tasks.executor import TaskExecutor
from knowledge.description import RobotDescription
from tests.executive.runtime.rig import USECASE_ROBOT, Rig, rig, robot, scripted, usecase


def slow_camera_robot(delay: float, picture: float = 1.0) -> RobotDescription:
    """take_picture (``picture`` seconds) on a camera that takes ``delay`` seconds to start."""
    camera = scripted(
        "slow_cam",
        "tests.executive.tasks.slow_start",
        provides=("camera",),
        publishes=("image",),
        params={"delay": delay, "rate": 10.0},
        startup_timeout=delay + 10.0,
    )
    take_picture = usecase("take_picture", params={"duration": picture})
    tasks = {"take_picture": USECASE_ROBOT.tasks["take_picture"]}
    return dataclasses.replace(robot(camera, take_picture), tasks=tasks)


@contextlib.contextmanager
def executor(
    description: RobotDescription,
    endpoint: str,
    folder: Path,
    *,
    linger: float = 0.0,
    sequential: bool = False,
    clock: Clock | None = None,
) -> Iterator[tuple[TaskExecutor, Rig]]:
    """A started task executor (stopped on leaving, with every component)."""
    with rig(description, endpoint, folder) as r:
        context = Context(description, r.bus, r.kb)
        tasks = TaskExecutor(context, r.launcher, linger=linger, sequential=sequential, clock=clock)
        tasks.configure()
        tasks.activate()
        try:
            yield tasks, r
        finally:
            tasks.shutdown()
