"""The robot harness of the ``dura_robot`` fixture: fault injection as soon as a
component runs, clear errors when it does not, and an executive on a chosen endpoint."""

from __future__ import annotations

import threading
from collections.abc import Callable

import pytest

from executive.testing.harness import RobotProcess
from knowledge.errors import DuraError
from tests.conftest import USECASE, free_endpoint, wait_for

pytestmark = pytest.mark.slow

Start = Callable[..., RobotProcess]


def test_a_fault_injected_before_the_component_runs_strikes_once_it_runs(
    dura_robot: Start,
) -> None:
    endpoint = free_endpoint()
    robot = dura_robot(USECASE, endpoint=endpoint)
    assert robot.endpoint == endpoint
    injected = threading.Thread(target=robot.inject_fault, args=("lidar", "crash"))
    injected.start()  # lidar does not run yet: the injection waits for it
    robot.request("component/start", {"name": "lidar"})
    injected.join(30)
    assert not injected.is_alive()
    assert wait_for(lambda: [e.subject for e in robot.events("FAULT")] == ["lidar"], 10)


def test_a_fault_for_a_component_that_does_not_run_or_a_bad_fault_is_a_clear_error(
    dura_robot: Start,
) -> None:
    robot = dura_robot(USECASE)
    with pytest.raises(DuraError, match=r"cannot inject 'crash' into 'cam': it is stopped, not"):
        robot.inject_fault("cam", "crash", timeout=0.5)
    robot.request("component/start", {"name": "cam"})
    with pytest.raises(DuraError, match=r"unknown fault mode 'melt' \(choose from crash, "):
        robot.inject_fault("cam", "melt")
    with pytest.raises(DuraError, match=r"unknown option 'speed' for fault 'wrong_rate'"):
        robot.inject_fault("cam", "wrong_rate", speed=2)
    robot.inject_fault("cam", "wrong_rate", factor=0.5)
    assert robot.component_state("cam") == "ready"
