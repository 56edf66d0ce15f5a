"""The resources observer: resource infos from a scripted resource monitor."""

from __future__ import annotations

from typing import Any

from executive.bus.keys import RESOURCES
from executive.bus.payloads import NOT_AVAILABLE, NodeInfo
from monitoring.observer_manager import ObserverManager
from tests.monitoring.harness import Observations, Publish, seen, stream

RESOURCES_OBSERVER = {
    "type": "resources",
    "main_loop_rate": 5.0,
    "resource_topic": "/diag/node_infos",
    "nodes": [
        {
            "name": "/lidar",
            "cpu_filter": {"type": "mean", "window_size": 3},
            "states": [
                {
                    "state": "normal",
                    "number": 1,
                    "cpu": {"type": "less_than", "less_than": 50},
                    "memory": {"type": "less_than", "less_than": 1e9},
                },
                {
                    "state": "busy",
                    "number": -8,
                    "cpu": {"type": "greater_than", "greater_than": 50},
                },
            ],
        }
    ],
}


def info(*nodes: NodeInfo) -> dict[str, Any]:
    return {"payload": {"hostname": "h", "nodes": [n.to_payload() for n in nodes]}}


def test_cpu_load_and_a_vanished_node_are_reported(
    manager: ObserverManager, observations: Observations, publish: Publish
) -> None:
    base = NodeInfo("robot_base", 2, "h", 1.0, 1000)
    calm = NodeInfo("lidar", 1, "h", 10.0, 5_000_000)
    busy = NodeInfo("lidar", 1, "h", 95.0, 5_000_000)
    publish(
        "resource-monitor",
        [
            stream(
                RESOURCES,
                {"rate": 10, "duration": 1.5, **info(calm, base)},
                {"rate": 10, "duration": 1.5, **info(busy, base)},
                {"rate": 10, **info(base)},
            )
        ],
    )
    manager.add(RESOURCES_OBSERVER)
    normal = observations.next(seen("resources", ["lidar"], 1))
    assert normal["values"] == {"cpu": 10.0, "memory": 5_000_000}
    observations.next(seen("resources", ["lidar"], -8))
    gone = observations.next(seen("resources", ["lidar"], NOT_AVAILABLE))
    assert gone["verbose_observation_msg"] == "'lidar' is not in the resource info"
