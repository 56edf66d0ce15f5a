"""The launcher's bus API: the declared verbs answer, and refuse bad requests by their types."""

from __future__ import annotations

from pathlib import Path

import pytest

from executive.bus.api.components import (
    COMPONENT_ACHIEVE,
    COMPONENT_LIST,
    COMPONENT_LOGS,
    COMPONENT_START,
    COMPONENT_STOP,
    Achievement,
    ComponentName,
    LogQuery,
)
from executive.bus.service import Context
from executive.bus.session import Bus
from executive.bus.states import Lifecycle
from executive.runtime.component_api import ComponentApi
from knowledge.errors import BusError
from tests.executive.runtime.rig import rig, robot, usecase


def test_components_are_listed_started_stopped_and_their_logs_read_through_the_verbs(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(usecase("lidar")), endpoint, tmp_path) as r:
        api = ComponentApi(Context(r.robot, r.bus, r.kb), r.launcher)
        api.configure()
        api.activate()
        try:
            started = COMPONENT_START.call(r.bus, ComponentName("lidar"))
            assert started.state is Lifecycle.READY
            (listed,) = COMPONENT_LIST.call(r.bus).components
            assert (listed.component, listed.kind, listed.state) == (
                "lidar",
                "functionality",
                Lifecycle.READY,
            )
            assert listed.log == str(tmp_path / "logs" / "lidar.log")
            assert listed.pid == started.pid
            assert COMPONENT_STOP.call(r.bus, ComponentName("lidar")).state is Lifecycle.STOPPED
            (stopped,) = COMPONENT_LIST.call(r.bus).components
            assert (stopped.state, stopped.pid) == (Lifecycle.STOPPED, None)  # no pid shown
            logs = COMPONENT_LOGS.call(r.bus, LogQuery("lidar", lines=1))
            assert logs.lines[0].startswith("--- dura: stopped: exited with code 0")
        finally:
            api.shutdown()


@pytest.mark.parametrize(
    ("key", "request_", "reason"),
    [
        (
            COMPONENT_LOGS.key,
            {"name": "lidar", "lines": -1},
            "'lines' must be from 0 to 10000, not -1",
        ),
        (
            COMPONENT_LOGS.key,
            {"name": "lidar", "lines": True},
            "'lines' must be an integer, not true",
        ),
        (COMPONENT_START.key, {"name": ""}, "'name' must be a non-empty string, not \"\""),
        (COMPONENT_STOP.key, {}, "'name' must be a non-empty string, not null"),
        (
            COMPONENT_ACHIEVE.key,
            {"component": "lidar", "key": ""},
            "'key' must be a non-empty string, not \"\"",
        ),
    ],
)
def test_a_request_with_a_bad_field_is_refused_by_its_declared_type_with_the_key_and_the_reason(
    endpoint: str, tmp_path: Path, key: str, request_: dict[str, object], reason: str
) -> None:
    with rig(robot(usecase("lidar")), endpoint, tmp_path) as r:
        api = ComponentApi(Context(r.robot, r.bus, r.kb), r.launcher)
        api.configure()
        api.activate()
        try:
            with pytest.raises(BusError) as refused:
                # achievements are asked under the caller's name (the session's)
                r.bus.request(key, request_, as_caller=key == COMPONENT_ACHIEVE.key)
            assert str(refused.value) == f"{key}: {reason}"
            assert r.launcher.state("lidar").state is Lifecycle.STOPPED  # nothing was done
        finally:
            api.shutdown()


def test_achievements_are_stored_by_the_launcher_for_known_components_only(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(usecase("lidar")), endpoint, tmp_path) as r:
        with Bus(r.robot.name, name="lidar", endpoint=endpoint) as lidar:
            COMPONENT_ACHIEVE.call(lidar, Achievement("lidar", "seen", {"scans": 3}))
        assert r.kb.achievements("lidar") == {"seen": {"scans": 3}}
        with (
            Bus(r.robot.name, name="lidr", endpoint=endpoint) as lidr,
            pytest.raises(BusError, match=r"^achievement for unknown component 'lidr'$"),
        ):
            COMPONENT_ACHIEVE.call(lidr, Achievement("lidar", "seen", 1))  # the name asked
