"""The component observer: nodes run while the launcher says so, or the resource info lists them."""

from __future__ import annotations

import json

from executive.bus.keys import RESOURCES
from executive.bus.message import Message
from executive.bus.payloads import GENERAL_OK, NOT_AVAILABLE, NodeInfo
from executive.bus.session import Bus
from executive.bus.states import Lifecycle
from monitoring.observer import Environment, make_observer
from monitoring.observer_config import config_of
from monitoring.observer_manager import ObserverManager
from tests.monitoring.harness import Observations, seen, set_state

COMPONENT = {
    "type": "activated",
    "main_loop_rate": 5.0,
    "nodes": [{"name": "lidar"}, "/robot_base"],
}


def test_a_crashed_node_is_not_running_for_the_behavior_that_needs_it(
    manager: ObserverManager, observations: Observations, bus: Bus
) -> None:
    manager.add(COMPONENT, component="move_to")
    for name in ("lidar", "robot_base", "move_to"):
        set_state(bus, name, Lifecycle.READY)
    observations.next(seen("component", ["lidar"], GENERAL_OK))
    observations.next(seen("component", ["robot_base"], GENERAL_OK))
    set_state(bus, "lidar", Lifecycle.EXITED)
    crashed = observations.next(seen("component", ["lidar"], NOT_AVAILABLE))
    assert crashed["verbose_observation_msg"] == "'lidar' is exited"


def test_a_node_the_launcher_does_not_know_runs_while_the_resource_info_lists_it() -> None:
    states = {"lidar": Lifecycle.READY}
    observer = make_observer(config_of(COMPONENT), Environment(component_state=states.get))
    observer.start(0.0)
    [(key, handler)] = observer.inputs()
    assert key == RESOURCES
    [_, unknown] = observer.observe(1.0)
    assert unknown.info.observation == NOT_AVAILABLE
    nodes = [NodeInfo("robot_base", 7, "h", 1.0, 10).to_payload()]
    handler(Message(key, json.dumps({"hostname": "h", "nodes": nodes}).encode(), "rm", None, 1.5))
    results = {r.info.resource: r.info.observation for r in observer.observe(2.0)}
    assert results == {("lidar",): GENERAL_OK, ("robot_base",): GENERAL_OK}
