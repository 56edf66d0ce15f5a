"""Sensing rules: facts and values kept in step with a topic, on a real bus and KB."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from executive.bus.clock import Clock
from executive.bus.keys import topic
from executive.bus.session import Bus
from executive.planning.sensing import Sensing, read_field, verdict
from knowledge.domain import read_domain
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact
from knowledge.sensing_spec import SensingRuleSpec
from tests.conftest import wait_for
from tests.executive.planning.planning_cases import TRANSPORT_DOMAIN, USECASE_DOMAIN

LOW = SensingRuleSpec("battery_low", "battery", "level", fact="(battery_low)", below=20.0,
                      clear_above=30.0)  # fmt: skip


def test_a_fact_follows_its_field_with_hysteresis() -> None:
    readings = [25, 19, 22, 29, 31, 25, 18]
    held: bool | None = False
    seen = []
    for level in readings:
        held = verdict(LOW, level, held)
        seen.append(held)
    assert seen == [False, True, True, True, False, False, True]


def test_above_equals_and_values_that_do_not_fit() -> None:
    hot = SensingRuleSpec("hot", "t", "c", fact="(hot)", above=60.0, clear_below=50.0)
    assert [verdict(hot, c, True) for c in (55, 49)] == [True, False]
    docked = SensingRuleSpec("docked", "dock", "state", fact="(docked)", equals="docked")
    assert verdict(docked, "docked", None) is True
    assert verdict(docked, "away", True) is False
    assert verdict(LOW, "empty", False) is None  # not a number: no verdict


def test_a_field_is_read_by_its_dotted_path() -> None:
    message = {"pose": {"position": {"x": 1.5}}, "ranges": [3.0, 4.0]}
    assert read_field(message, "pose.position.x") == 1.5
    assert read_field(message, "ranges.-1") == 4.0
    assert read_field(message, "pose.orientation.w") is None


class Rig:
    """A bus, a knowledge base with the transport world's objects, and a publisher."""

    def __init__(
        self, tmp_path: Path, endpoint: str, rules: list[SensingRuleSpec], domain: Path
    ) -> None:
        self.executive = Bus("transport", name="executive", endpoint=endpoint, listen=True)
        self.base = Bus("transport", name="base", endpoint=endpoint)
        self.kb = KnowledgeBase(tmp_path / "kb.db")
        self.kb.add_object("dock", "place")
        self.kb.add_object("lab", "place")
        self.changes: list[tuple[list[Fact], str]] = []
        self.changed = threading.Event()
        self.sensing = Sensing(
            self.kb,
            read_domain(domain),
            rules,
            subscribe=self.executive.subscribe,
            changed=self._changed,
            clock=Clock(10.0),  # hold times of robot seconds pass ten times faster
        )
        self.sensing.start()

    def _changed(self, facts: list[Fact], reason: str) -> None:
        self.changes.append((facts, reason))

    def publish(self, **payload: Any) -> None:
        self.base.publish(topic("battery"), payload)

    def facts(self) -> list[str]:
        return [str(f) for f in self.kb.facts()]

    def close(self) -> None:
        self.sensing.stop()
        self.kb.close()
        self.base.close()
        self.executive.close()


@pytest.fixture
def rig(tmp_path: Path, endpoint: str) -> Iterator[Rig]:
    made: list[Rig] = []

    def make(*rules: SensingRuleSpec, domain: Path = TRANSPORT_DOMAIN) -> Rig:
        made.append(Rig(tmp_path, endpoint, list(rules), domain))
        return made[-1]

    yield make  # type: ignore[misc]
    for r in made:
        r.close()


def test_a_low_reading_sets_the_fact_with_the_rule_as_its_source(rig: Any) -> None:
    r = rig(LOW)
    r.publish(level=25.0)
    r.publish(level=15.0)
    assert wait_for(lambda: "(battery_low)" in r.facts(), 5.0)
    (event,) = r.kb.events(kind="STATE_SET")
    assert event.subject == "(battery_low)"
    assert event.data == {"source": "sensing", "rule": "battery_low", "topic": "battery",
                          "field": "level", "value": 15.0}  # fmt: skip
    assert r.changes[0][0] == [Fact("battery_low", ())]
    r.publish(level=25.0)  # above 20, not above 30: still low
    r.publish(level=31.0)
    assert wait_for(lambda: "(battery_low)" not in r.facts(), 5.0)
    assert [e.kind for e in r.kb.events(kind="STATE_UNSET")] == ["STATE_UNSET"]


def test_a_verdict_counts_only_once_it_lasted_its_hold_time(rig: Any) -> None:
    held = SensingRuleSpec(
        "battery_low", "battery", "level", fact="(battery_low)", below=20.0, hold=5.0
    )  # fmt: skip  (0.5 s of wall time)
    r = rig(held)
    r.publish(level=15.0)
    r.publish(level=25.0)  # a blip: gone before the hold time
    r.publish(level=15.0)
    assert wait_for(lambda: "(battery_low)" in r.facts(), 5.0)  # no message needed: a timer
    assert len(r.kb.events(kind="STATE_SET")) == 1


def test_a_value_is_written_when_it_moved_enough(rig: Any) -> None:
    rule = SensingRuleSpec("travel", "battery", "minutes", value="(travel_time dock lab)",
                           min_change=1.0)  # fmt: skip
    r = rig(rule, domain=USECASE_DOMAIN)
    for minutes in (4.0, 4.5, 6.0):
        r.publish(minutes=minutes)
    assert wait_for(lambda: "(= (travel_time dock lab) 6)" in r.facts(), 5.0)
    assert [e.subject for e in r.kb.events(kind="STATE_SET")] == [
        "(= (travel_time dock lab) 4)",  # 4.5 moved less than 1
        "(= (travel_time dock lab) 6)",
    ]


def test_a_rule_that_does_not_fit_the_domain_is_left_out_with_a_warning(
    rig: Any, caplog: pytest.LogCaptureFixture
) -> None:
    r = rig(SensingRuleSpec("level", "battery", "level", value="(battery_low)"))
    r.publish(level=3.0)
    assert "sensing rule 'level' left out" in caplog.text
    assert r.facts() == []
