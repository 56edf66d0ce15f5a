"""A sensing rule reads a ROS 2 topic through the same topic source as the observers."""

from __future__ import annotations

from executive.bus.clock import Clock
from executive.bus.service import Context
from executive.planning.sensing import Sensing
from executive.ros2.link import Ros2Link
from knowledge.domain import read_domain
from knowledge.records import Fact
from knowledge.sensing_spec import SensingRuleSpec
from tests.conftest import wait_for
from tests.executive.planning.planning_cases import TRANSPORT_DOMAIN
from tests.executive.ros2.messages import Float64
from tests.executive.ros2.peer import RosPeer, streaming


def test_a_ros2_battery_level_sets_the_fact(
    context: Context, link: Ros2Link, peer: RosPeer
) -> None:
    battery = peer.publisher("battery_driver", "/battery", Float64)
    rule = SensingRuleSpec("battery_low", "battery", "data", fact="(battery_low)", below=20.0)
    changed: list[list[Fact]] = []
    sensing = Sensing(
        context.kb,
        read_domain(TRANSPORT_DOMAIN),
        [rule],
        subscribe=link.topics.subscribe,
        changed=lambda facts, reason: changed.append(facts),
        clock=Clock(),
    )
    sensing.start()
    try:
        with streaming(battery, 20, lambda: Float64(data=12.5)):
            assert wait_for(lambda: bool(context.kb.facts("battery_low")), 10.0)
    finally:
        sensing.stop()
    (event,) = context.kb.events(kind="STATE_SET")
    assert (event.subject, event.data["topic"], event.data["value"]) == (
        "(battery_low)",
        "battery",
        12.5,
    )
    assert changed == [[Fact("battery_low", ())]]
