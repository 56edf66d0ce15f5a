"""The observer manager: observers follow their components, change at run time, share
subscriptions, and answer on the bus."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from executive.bus.keys import observers_api
from executive.bus.payloads import NO_STATE_FITS
from executive.bus.session import Bus
from executive.bus.states import Lifecycle
from knowledge.errors import BusError, ConfigError
from knowledge.robot import read_robot
from monitoring.observer_manager import ObserverManager
from tests.monitoring.harness import (
    Observations,
    Publish,
    bus,
    manager,
    observations,
    publish,
    robot,
    running_manager,
    set_state,
    stream,
    wait_until,
    write_robot,
)

__all__ = ["bus", "manager", "observations", "publish", "robot"]


def frequency(low: float = 15.0, high: float = 25.0, window: int = 5) -> dict[str, Any]:
    return {
        "type": "hz",
        "main_loop_rate": 5.0,
        "topics": [
            {
                "name": "scan",
                "filter": {"type": "mean", "window_size": window},
                "states": [
                    {
                        "state": "ok",
                        "number": 1,
                        "frequency": {
                            "type": "in_between",
                            "lower_bound": low,
                            "upper_bound": high,
                        },
                    }
                ],
            }
        ],
    }


TIMEOUT_OBSERVER = {"type": "timeout", "topics": [{"name": "scan", "timeout": 1.0}]}


def of(observer: str) -> Any:
    return lambda o: o["observer"] == observer


def test_a_components_observers_observe_only_while_it_is_ready(
    tmp_path: Path, endpoint: str, observations: Observations, bus: Bus, publish: Publish
) -> None:
    robot, _ = read_robot(write_robot(tmp_path, endpoint, observers=json.dumps([frequency()])))
    assert robot is not None
    publish("lidar", [stream("topic/scan", {"rate": 20})])
    with running_manager(robot, bus, tmp_path) as manager:
        [status] = manager.observers()
        assert (status.id, status.component, status.enabled, status.active) == (
            "lidar/0",
            "lidar",
            True,
            False,
        )
        assert not [o for o in observations.during(0.6) if o["observer"] == "lidar/0"]
        set_state(bus, "lidar", Lifecycle.READY)
        found = observations.next(of("lidar/0"))
        assert found["type"] == "frequency" and found["observation"] == 1
        assert manager.observers()[0].active
        set_state(bus, "lidar", Lifecycle.STOPPED)
        wait_until(lambda: not manager.observers()[0].active)
        observations.during(0.3)  # what was published before
        assert not [o for o in observations.during(1.0) if o["observer"] == "lidar/0"]
        assert manager.latest() == []


def test_observers_are_added_changed_deactivated_and_removed_at_run_time(
    manager: ObserverManager, observations: Observations, publish: Publish
) -> None:
    publish("lidar", [stream("topic/scan", {"rate": 20})])
    observer = manager.add(frequency(), name="scan rate")
    assert observations.next(of(observer))["observation"] == 1
    manager.change(observer, frequency(low=40, high=60))
    assert observations.next(of(observer))["observation"] == NO_STATE_FITS
    manager.deactivate_observer(observer)
    observations.during(0.3)
    assert not [o for o in observations.during(0.8) if o["observer"] == observer]
    assert manager.activate_observer(observer) is True
    observations.next(of(observer))
    manager.remove(observer)
    assert manager.observers() == []
    with pytest.raises(ConfigError, match=r"^no observer 'scan rate'$"):
        manager.remove("scan rate")


def test_a_change_to_an_invalid_configuration_keeps_the_old_one(manager: ObserverManager) -> None:
    observer = manager.add(frequency())
    bad = frequency(window=1)
    with pytest.raises(
        ConfigError, match=r"'window_size' of the filter of topic 'scan'.*at least 2, not 1"
    ):
        manager.change(observer, bad)
    assert [s.type for s in manager.observers()] == ["frequency"]


def test_observers_of_one_topic_share_one_subscription(manager: ObserverManager) -> None:
    first = manager.add(frequency())
    second = manager.add(TIMEOUT_OBSERVER)
    assert manager.subscriptions() == {"topic/scan": 2}
    manager.remove(first)
    assert manager.subscriptions() == {"topic/scan": 1}
    manager.remove(second)
    assert manager.subscriptions() == {}


def test_an_observer_of_an_unknown_component_is_refused(manager: ObserverManager) -> None:
    with pytest.raises(
        ConfigError, match=r"no component 'lidr' in robot 'monitored' \(did you mean 'lidar'\?\)"
    ):
        manager.add(frequency(), component="lidr")


def test_another_process_manages_observers_over_the_bus(
    manager: ObserverManager, observations: Observations, publish: Publish, endpoint: str
) -> None:
    publish("lidar", [stream("topic/scan", {"rate": 20})])
    with Bus("monitored", name="cli", endpoint=endpoint) as client:
        added = client.request(observers_api("add"), {"config": frequency(), "component": "lidar"})
        assert added == {"id": "lidar/0", "active": False}
        assert client.request(observers_api("list"))["observers"][0]["active"] is False
        assert client.request(observers_api("deactivate"), {"id": "lidar/0"})["active"] is False
        assert client.request(observers_api("activate"), {"id": "lidar/0"})["active"] is False
        manager.add(TIMEOUT_OBSERVER, name="watchdog")
        observations.next(of("watchdog"))
        latest = client.request(observers_api("latest"))["observations"]
        assert [o["observer"] for o in latest] == ["watchdog"]
        changed = client.request(
            observers_api("change"),
            {"id": "watchdog", "config": {**TIMEOUT_OBSERVER, "main_loop_rate": 2.0}},
        )
        assert changed == {"id": "watchdog", "active": True}
        assert client.request(observers_api("remove"), {"id": "lidar/0"}) == {"id": "lidar/0"}
        assert [o["id"] for o in client.request(observers_api("list"))["observers"]] == ["watchdog"]


@pytest.mark.parametrize(
    ("verb", "request_", "message"),
    [
        (
            "add",
            {"config": "frequency"},
            "monitoring/observers/add: 'config' must be an observer entry",
        ),
        (
            "add",
            {"config": {"type": "hz", "topics": [{"name": "scan", "filter": {"type": "mean"}}]}},
            "monitoring/observers/add: topic 'scan' of the frequency observer has no 'states' (a list)",
        ),
        ("add", {"config": {"type": "frequenzy"}}, "unknown observer type 'frequenzy'"),
        ("remove", {}, "monitoring/observers/remove: 'id' must be a non-empty string"),
        ("activate", {"id": "nobody"}, "no observer 'nobody'"),
    ],
)
def test_a_bad_request_gets_an_error_reply_that_says_why(
    manager: ObserverManager, endpoint: str, verb: str, request_: dict[str, Any], message: str
) -> None:
    with (
        Bus("monitored", name="cli", endpoint=endpoint) as client,
        pytest.raises(BusError) as raised,
    ):
        client.request(observers_api(verb), request_)
    assert message in str(raised.value)
    assert manager.observers() == []


def test_an_invalid_observer_in_the_description_stops_the_start_with_its_line(
    tmp_path: Path, endpoint: str, bus: Bus
) -> None:
    path = write_robot(tmp_path, endpoint, observers="[{type: timeout, topics: [{name: scan}]}]")
    robot, _ = read_robot(path)
    assert robot is not None
    with pytest.raises(ConfigError) as raised, running_manager(robot, bus, tmp_path):
        pass
    line = (
        path.read_text()
        .splitlines()
        .index("    observers: [{type: timeout, topics: [{name: scan}]}]")
        + 1
    )
    assert str(raised.value) == (
        f"{path}:{line}: topic 'scan' of the timeout observer of functionality 'lidar' has no 'timeout'"
    )
