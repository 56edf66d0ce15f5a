"""The component graph: where its nodes stand, and what the picture shows of a robot's
state (component states, diagnoses, fault counters, active configurations)."""

from __future__ import annotations

from pathlib import Path

import pytest

from executive.dashboard import graph
from knowledge.description import RobotDescription
from knowledge.robot import load_robot
from tests.conftest import ROOT, USECASE
from tests.executive.dashboard.pictures import groups, parse, texts, tooltip


@pytest.fixture(scope="module")
def robot() -> RobotDescription:
    return load_robot(USECASE)


TRANSPORT = ROOT / "examples" / "transport" / "robot.yaml"
ROS2 = ROOT / "examples" / "ros2" / "robot.yaml"


def nodes(picture: str) -> dict[str, dict[str, str]]:
    """Each drawn node's attributes, with its tooltip and texts, by name."""
    return {
        g.get("data-node", ""): {**g.attrib, "tooltip": tooltip(g), "texts": " ".join(texts(g))}
        for g in groups(parse(picture), "node")
    }


def test_the_graph_has_every_component_capability_and_topic(robot: RobotDescription) -> None:
    layout = graph.layout(robot)
    kinds = {(n.name, n.kind) for n in layout.nodes.values()}
    assert {("lidar", "functionality"), ("move_to", "behavior"), ("obstacle_scan", "capability"),
            ("scan_filtered", "topic"), ("cmd_vel", "topic")} <= kinds  # fmt: skip
    assert len(layout.nodes) == len(robot.components) + len(robot.topics) + 4
    edges = {(e.source, e.target, e.kind) for e in layout.edges}
    assert ("component:cam_to_lidar", "capability:obstacle_scan", "provides") in edges
    assert ("capability:obstacle_scan", "component:move_to", "requires") in edges
    assert ("topic:scan", "component:lidar_filter", "subscribes") in edges


def test_components_stand_after_the_providers_of_what_they_require(
    robot: RobotDescription,
) -> None:
    at = {n.name: n.x for n in graph.layout(robot).nodes.values()}
    assert at["lidar"] < at["laser_scan"] < at["lidar_filter"] < at["obstacle_scan"] < at["move_to"]
    assert at["cam"] < at["image"] < at["cam_to_lidar"]


def test_nodes_of_a_layer_do_not_overlap(robot: RobotDescription) -> None:
    placed = list(graph.layout(robot).nodes.values())
    for a in placed:
        for b in placed:
            if a.key < b.key and a.x == b.x:
                assert a.y + a.height <= b.y or b.y + b.height <= a.y, (a.name, b.name)


def test_a_plain_picture_shows_the_description_without_states(robot: RobotDescription) -> None:
    drawn = nodes(graph.render(graph.layout(robot)))
    assert "data-state" not in drawn["lidar"]
    assert "provides laser_scan" in drawn["lidar"]["tooltip"]
    assert "functionality" in drawn["lidar"]["texts"]


def test_the_robots_state_colours_the_components_and_marks_the_diagnosis(
    robot: RobotDescription,
) -> None:
    state = graph.GraphState(
        states={"lidar": "faulty", "lidar_filter": "running", "cam": "permanently faulty"},
        diagnosed=frozenset({"lidar"}),
        faults={"lidar": (2, 3), "cam": (3, 3)},
        failed_topics=frozenset({"scan"}),
        tasks={"lidar": ("task 1 move_to(dock, lab)",)},
        used=frozenset({("laser_scan", "lidar")}),
    )
    picture = graph.render(graph.layout(robot), state)
    drawn = nodes(picture)
    assert drawn["lidar"]["data-state"] == "faulty" and drawn["lidar"]["data-diagnosed"] == "yes"
    assert drawn["lidar"]["data-faults"] == "2"
    assert "2/3" in drawn["lidar"]["texts"] and "faults 2 of 3" in drawn["lidar"]["tooltip"]
    assert "serves task 1 move_to(dock, lab)" in drawn["lidar"]["tooltip"]
    assert drawn["cam"]["data-state"] == "permanently faulty"
    assert drawn["move_to"]["data-state"] == "stopped"  # not reported: not running
    assert drawn["scan"]["data-state"] == "failed"
    assert "data-diagnosed" not in drawn["lidar_filter"]
    root = parse(picture)
    used = [p for p in root.iter("{http://www.w3.org/2000/svg}path") if p.get("data-used")]
    assert len(used) == 1 and "provides" in (used[0].get("class") or "")


@pytest.mark.parametrize("description", [USECASE, TRANSPORT, ROS2])
def test_no_edge_passes_through_a_box_it_does_not_join(description: Path) -> None:
    layout = graph.layout(load_robot(description, domain=False))
    bottom = layout.height - graph.LEGEND - 12.0
    crossed = []
    for edge in layout.edges:
        a, b = layout.nodes[edge.source], layout.nodes[edge.target]
        points = graph.sampled(graph.edge_curves(a, b, bottom, layout.nodes.values()))
        for other in layout.nodes.values():
            if other in (a, b):
                continue
            if any(
                other.x < x < other.x + other.width and other.y < y < other.y + other.height
                for x, y in points
            ):
                crossed.append(f"{a.name} -> {b.name} through {other.name}")
    assert crossed == []
