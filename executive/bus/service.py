"""The extension point for the executive's services (launcher, observers, diagnosis, ...).

The executive process composes services; each talks to the others only through the
bus (see :mod:`executive.bus.keys` and :mod:`executive.bus.payloads`), so any of them can also run in a process of its
own. A service gets its collaborators in its constructor and has a small lifecycle.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

from executive.bus.session import Bus
from knowledge.description import RobotDescription
from knowledge.knowledge_base import KnowledgeBase


@dataclass(frozen=True)
class Context:
    """What every service may use: the robot, its bus session and its knowledge base."""

    robot: RobotDescription
    bus: Bus
    kb: KnowledgeBase


class Service(ABC):
    """One long-running part of the executive."""

    name: str = "service"

    def __init__(self, context: Context) -> None:
        self.context = context

    @abstractmethod
    def start(self) -> None:
        """Declare bus entities and start threads; return quickly."""

    @abstractmethod
    def stop(self) -> None:
        """Stop threads and release everything; idempotent."""
