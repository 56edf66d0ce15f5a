"""Component parameters at run time: typed by the robot description, stored in the
knowledge base, taken by a running component through its hook or by a warm restart."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from executive.bus.api.parameters import (
    PARAMETER_GET,
    PARAMETER_LIST,
    ComponentParameters,
    ParameterKey,
)
from executive.bus.states import Lifecycle
from executive.tasks.parameters import checked
from knowledge.errors import BusError, ConfigError
from tests.executive.runtime.rig import robot, usecase
from tests.executive.tasks.executor_rig import executor

LIDAR = usecase("lidar", params={"rate": 10.0, "count": 3, "on": True, "label": "a"})


@pytest.mark.parametrize(
    ("key", "value", "stored"),
    [
        ("rate", 5, 5.0),  # a whole number for a float
        ("rate", 2.5, 2.5),
        ("count", 4.0, 4),  # a whole float for an int
        ("on", False, False),
        ("label", "b", "b"),
        ("window", [1, "x"], [1, "x"]),  # not in the description: any value
    ],
)
def test_a_parameter_takes_values_of_the_type_its_description_gives(
    key: str, value: Any, stored: Any
) -> None:
    result = checked(LIDAR, key, value)
    assert result == stored and type(result) is type(stored)


@pytest.mark.parametrize(
    ("key", "value", "reason"),
    [
        ("rate", "fast", "'rate' of 'lidar' must be a number (the description gives 10.0), not 'fast'"),
        ("rate", True, "must be a number (the description gives 10.0), not True"),
        ("rate", float("inf"), "must be a number (the description gives 10.0), not inf"),
        ("count", 2.5, "'count' of 'lidar' must be a whole number (the description gives 3)"),
        ("on", 1, "'on' of 'lidar' must be true or false (the description gives True), not 1"),
        ("label", 7, "'label' of 'lidar' must be a string (the description gives 'a'), not 7"),
    ],
)  # fmt: skip
def test_a_value_of_another_type_is_refused_with_the_reason(
    key: str, value: Any, reason: str
) -> None:
    with pytest.raises(ConfigError, match=reason.replace("(", r"\(").replace(")", r"\)")):
        checked(LIDAR, key, value)


@pytest.mark.slow
def test_a_running_component_takes_a_parameter_by_its_hook_or_by_a_warm_restart(
    endpoint: str, tmp_path: Path
) -> None:
    with executor(robot(usecase("lidar"), usecase("cam")), endpoint, tmp_path) as (tasks, r):
        lidar = tasks.start_by_hand("lidar")
        cam = tasks.start_by_hand("cam")
        live = tasks.set_parameter("lidar", "rate", 5)
        assert (live.applied, live.value) == ("reconfigured", 5.0)
        assert r.launcher.state("lidar").pid == lidar.pid  # no restart
        restarted = tasks.set_parameter("cam", "rate", 7.5)
        assert restarted.applied == "restarted" and "no on_reconfigure" in restarted.reason
        assert r.launcher.state("cam").state is Lifecycle.READY
        assert r.launcher.state("cam").pid != cam.pid
        assert r.kb.parameters("lidar") == {"rate": 5.0} and r.kb.parameters("cam") == {"rate": 7.5}
        assert not r.kb.events(kind="FAULT")  # a restart for new parameters is no fault
        tasks.stop_by_hand("lidar")
        stored = tasks.set_parameter("lidar", "rate", 4.0)
        assert stored.applied == "stored"
        with pytest.raises(ConfigError, match="must be a number"):
            tasks.set_parameter("lidar", "rate", "fast")
        assert r.kb.parameters("lidar") == {"rate": 4.0}  # the refused value changed nothing
        reply = PARAMETER_GET.call(r.bus, ParameterKey("lidar", "rate"))
        assert (reply.value, reply.source) == (4.0, "knowledge base")
        listed = PARAMETER_LIST.call(r.bus, ComponentParameters("cam"))
        assert listed.parameters == {"rate": 7.5} and listed.sources == {"rate": "knowledge base"}
        with pytest.raises(BusError, match="'cam' has no parameter 'zoom'"):
            PARAMETER_GET.call(r.bus, ParameterKey("cam", "zoom"))
