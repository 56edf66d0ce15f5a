"""The events verb on a robot that ran long: every reply stays under the bus's payload
limit, says when it left events out, and a client pages through them all."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.bus.api import planning as api
from executive.bus.message import MAX_PAYLOAD, encode
from executive.bus.session import Bus
from knowledge.knowledge_base import KnowledgeBase
from tests.executive.planning.long_run import served

LOGGED = 2500  # of about 1 KB each: 2.5 MB, more than two replies hold


def _logged(kb: KnowledgeBase) -> None:
    with kb.transaction():
        for n in range(LOGGED):
            kb.log_event("COMPONENT_READY", f"lidar {n}", {"note": "x" * 1000, "n": n})


@pytest.fixture
def client(tmp_path: Path, endpoint: str) -> Iterator[Bus]:
    with served(tmp_path / "kb.db", endpoint, _logged) as cli:
        yield cli


def test_a_reply_stays_under_the_payload_limit_and_says_there_is_more(client: Bus) -> None:
    newest = api.EVENTS.call(client, api.EventQuery(limit=10_000))
    assert newest.more
    assert len(encode(newest.to_payload())) < MAX_PAYLOAD
    assert newest.events[-1].data["n"] == LOGGED - 1  # the newest of them, in order
    numbers = [e.data["n"] for e in newest.events]
    assert numbers == list(range(LOGGED - len(numbers), LOGGED))
    oldest = api.EVENTS.call(client, api.EventQuery(limit=10_000, oldest=True))
    assert oldest.more
    assert [e.data["n"] for e in oldest.events] == list(range(len(oldest.events)))
    few = api.EVENTS.call(client, api.EventQuery(limit=5))
    assert not few.more
    assert [e.data["n"] for e in few.events] == list(range(LOGGED - 5, LOGGED))


def test_a_client_pages_back_through_the_newest_events(client: Bus) -> None:
    events = api.newest_events(client, 2000)
    assert [e.data["n"] for e in events] == list(range(LOGGED - 2000, LOGGED))
    every = api.newest_events(client, 10_000, kind="COMPONENT_READY")
    assert [e.data["n"] for e in every] == list(range(LOGGED))
    assert api.newest_events(client, 10_000, kind="FAULT") == []


def test_one_event_too_large_for_a_reply_is_not_sent(tmp_path: Path) -> None:
    from executive.planning.goal_api import fitting

    with KnowledgeBase(tmp_path / "kb.db") as kb:
        kb.log_event("NOTE", "small", {})
        kb.log_event("NOTE", "huge", {"text": "x" * MAX_PAYLOAD})
        events = kb.events()
    assert fitting(events, newest=True) == []
    assert [e.subject for e in fitting(events, newest=False)] == ["small"]
