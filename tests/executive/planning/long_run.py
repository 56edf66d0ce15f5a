"""A robot that ran long: the high level's verbs served over a real bus from a knowledge
base filled by the test, and a client of them (the events and goal pages' tests)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from executive.bus.service import Context
from executive.bus.session import Bus
from executive.planning.goal_api import GoalApi
from knowledge.errors import DuraError
from knowledge.knowledge_base import KnowledgeBase
from knowledge.robot import load_robot
from tests.conftest import USECASE


def _nothing() -> None:
    raise DuraError("not needed here")


@contextmanager
def served(kb_path: Path, endpoint: str, fill: Callable[[KnowledgeBase], None]) -> Iterator[Bus]:
    """A client's bus to the use case's high-level verbs on a knowledge base ``fill`` wrote."""
    with (
        KnowledgeBase(kb_path) as kb,
        Bus("usecase", name="executive", endpoint=endpoint, listen=True) as bus,
    ):
        fill(kb)
        context = Context(load_robot(USECASE), bus, kb)
        GoalApi(context, planning=_nothing, current=lambda: None, diagnoses=dict, status={}).serve()
        with Bus("usecase", name="cli", endpoint=endpoint) as cli:
            yield cli
