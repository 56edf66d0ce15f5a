"""The goal list of a robot that ran long: every reply stays under the bus's payload
limit, says when it left goals out, and a client pages through them all; ``status``
carries the open goals and the newest others, however many goals there are."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.bus.api import planning as api
from executive.bus.message import MAX_PAYLOAD, encode
from executive.bus.session import Bus
from executive.planning.goal_api import MAX_GOALS
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import GoalState
from tests.executive.planning.long_run import served

TAKEN = 12_000  # more goals than one request reads (MAX_GOALS), in three states


def _taken(kb: KnowledgeBase) -> None:
    with kb.transaction() as db:
        db.executemany(
            "INSERT INTO goals(expression, state, created, updated) VALUES (?, ?, 1, 2)",
            [(f"(picture_taken lab{n})", ("achieved", "failed", "pending")[n % 3])
             for n in range(TAKEN)],
        )  # fmt: skip


@pytest.fixture
def client(tmp_path: Path, endpoint: str) -> Iterator[Bus]:
    with served(tmp_path / "kb.db", endpoint, _taken) as cli:
        yield cli


def test_a_reply_stays_under_the_payload_limit_and_says_there_is_more(client: Bus) -> None:
    raw = client.request(api.GOAL_LIST.key, {})  # as a client before paging asks
    assert raw["more"] is True and len(encode(raw)) < MAX_PAYLOAD
    newest = api.GoalsReply.from_payload(raw).goals
    assert [g.id for g in newest] == list(range(TAKEN + 1 - len(newest), TAKEN + 1))
    few = client.request(api.GOAL_LIST.key, {"limit": 5, "before": 101})
    assert list(few) == ["goals"]  # all of those asked for: no "more" on the wire
    assert [g["id"] for g in few["goals"]] == [96, 97, 98, 99, 100]
    none = api.GOAL_LIST.call(client, api.GoalQuery(limit=0))
    assert (none.goals, none.more) == ([], None)
    past = api.GOAL_LIST.call(client, api.GoalQuery(limit=10**9, before=MAX_GOALS // 2))
    assert past.more and past.goals[-1].id == MAX_GOALS // 2 - 1


def test_a_client_pages_back_through_the_goals(client: Bus) -> None:
    assert [g.id for g in api.newest_goals(client)] == list(range(1, TAKEN + 1))
    assert [g.id for g in api.newest_goals(client, 7_000)] == list(range(TAKEN - 6_999, TAKEN + 1))
    failed = api.newest_goals(client, states=[GoalState.FAILED])
    assert [g.id for g in failed] == list(range(2, TAKEN + 1, 3))
    assert api.newest_goals(client, states=[GoalState.CANCELLED]) == []


def test_status_carries_the_open_goals_and_the_newest_others(client: Bus) -> None:
    raw = client.request(api.STATUS.key, {})
    assert len(encode(raw)) < MAX_PAYLOAD // 2
    status = api.StatusReply.from_payload(raw)
    assert status.goal_counts == {
        "achieved": TAKEN // 3,
        "failed": TAKEN // 3,
        "pending": TAKEN // 3,
    }
    ids = [g.id for g in status.goals]
    assert ids == sorted(ids) and ids[-1] == TAKEN
    opened = [g.id for g in status.goals if g.state.is_open]  # too many for one reply
    assert len(opened) > 100 and opened == list(range(opened[0], TAKEN + 1, 3))
    ended = [g.id for g in status.goals if not g.state.is_open]  # if any fit after them
    assert len(ended) <= api.RECENT_GOALS and all(n > opened[0] for n in ended)


def test_status_carries_the_open_goals_first(tmp_path: Path, endpoint: str) -> None:
    """The ended goals that status carries besides the open ones are the newest, however
    old the open ones are."""
    opened: list[int] = []

    def fill(kb: KnowledgeBase) -> None:
        opened.append(kb.add_goal("(robot_at lab)").id)
        with kb.transaction() as db:
            db.executemany(
                "INSERT INTO goals(expression, state, created, updated) VALUES (?, ?, 1, 2)",
                [("(robot_at dock)", "achieved")] * 5_000,
            )

    with served(tmp_path / "kb.db", endpoint, fill) as cli:
        status = api.STATUS.call(cli)
    assert [g.id for g in status.goals] == [*opened, *range(5_002 - api.RECENT_GOALS, 5_002)]
    assert status.goal_counts == {"pending": 1, "achieved": 5_000}
