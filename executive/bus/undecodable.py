"""Messages whose payload does not decode (bad JSON, CDR cut short or of another type,
a payload of the wrong shape), counted per topic with the first reason: a replay
reports them instead of dropping them silently."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from knowledge.errors import excerpt


@dataclass(frozen=True)
class Undecodable:
    """The messages of one topic that did not decode: how many, and why the first did not."""

    topic: str
    count: int
    reason: str  # one line, quoting at most ~200 characters of the message

    def to_payload(self) -> dict[str, Any]:
        return {"topic": self.topic, "count": self.count, "reason": self.reason}


class UndecodableMessages:
    """Count the messages that did not decode, per topic, keeping each topic's first
    reason."""

    def __init__(self) -> None:
        self._counts: dict[str, int] = {}
        self._reasons: dict[str, str] = {}

    def add(self, topic: str, reason: str) -> None:
        """Count one message of ``topic`` that did not decode, and why."""
        self._counts[topic] = self._counts.get(topic, 0) + 1
        self._reasons.setdefault(topic, excerpt(" ".join(reason.split())))  # one line

    def topics(self) -> tuple[Undecodable, ...]:
        """Each topic with undecodable messages, by name."""
        return tuple(
            Undecodable(topic, count, self._reasons[topic])
            for topic, count in sorted(self._counts.items())
        )
