"""The fleet's runner of plan steps: each step to the task executor of the robot it names.

A step's robot is the object bound to its action's robot parameter (the fleet's
``actors``: its position among the action's parameters); it names the robot in the
plan's events and in ``dura plan show``. A step for a robot that cannot act now fails at once with the reason, and
the planner plans again without that robot; so does a step whose robot vanishes while
it runs (:class:`~executive.planning.bus_tasks.BusTasks`). Each outcome counts towards
the robot's availability: failed steps in a row make it unavailable. The steps to come
are told to each robot: its own share of them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from executive.fleet.availability import Availability
from executive.fleet.robot_link import RobotLink
from executive.planning.partial_order import Step
from executive.planning.task_runner import Progress, StepReport, StepTask, TaskRunner, UnrunStep


class FleetTasks(TaskRunner):
    """Runs each plan step on its robot's task executor.

    Args:
        actors: each acting action's robot parameter, by its position.
        robots: the robot's name, by its PDDL object.
        links: each robot's link, by name.
        availability: which robots can act now (told each step's outcome).
    """

    def __init__(
        self,
        actors: Mapping[str, int],
        robots: Mapping[str, str],
        links: Mapping[str, RobotLink],
        availability: Availability,
    ) -> None:
        self.actors = dict(actors)
        self.robots = dict(robots)
        self.links = dict(links)
        self.availability = availability

    def performer(self, action: str, args: Sequence[str]) -> str | None:
        """The robot a step names (``None``: its action names none, or not a robot)."""
        index = self.actors.get(action)
        if index is None or index >= len(args):
            return None
        return self.robots.get(args[index])

    def robot_of(self, step: Step) -> str | None:
        return self.performer(step.action, step.args)

    def run(self, step: Step, plan_id: int, report: StepReport) -> StepTask:
        robot = self.robot_of(step)
        if robot is None:
            report.failed(f"step {step.label} names no robot of the fleet")
            return UnrunStep()
        why = self.availability.reason(robot)
        runner = self.links[robot].runner
        if why is None and runner is None:
            why = "the fleet has not reached its executive"
        if why is not None or runner is None:
            report.failed(f"robot '{robot}' is unavailable: {why}")
            return UnrunStep()
        availability = self.availability

        def relay(_: StepReport, progress: Progress, value: Any) -> None:
            if progress is Progress.STARTED:
                report.started()
            elif progress is Progress.SUCCEEDED:
                availability.step_succeeded(robot)
                report.succeeded(value)
            else:
                availability.step_failed(robot, str(value))
                report.failed(str(value))

        return runner.run(step, plan_id, StepReport(relay))

    def upcoming(self, plan_id: int | None, steps: Sequence[Step]) -> None:
        shares: dict[str, list[Step]] = {name: [] for name in self.links}
        for step in steps:
            robot = self.robot_of(step)
            if robot is not None:
                shares[robot].append(step)
        for name, share in shares.items():
            runner = self.links[name].runner
            if runner is not None and self.availability.reason(name) is None:
                runner.upcoming(plan_id if share else None, share)
