"""Fixtures of the observer tests: a robot, its bus, a running observer manager,
publisher processes and the observations (see :mod:`tests.monitoring.harness`)."""

from tests.monitoring.harness import bus, manager, observations, publish, robot

__all__ = ["bus", "manager", "observations", "publish", "robot"]
