"""The timeout observer: a watchdog on a topic, per caller-id group (thesis 6.2.5).

Configuration (see :mod:`monitoring.caller_groups` for ``topics``)::

    - type: timeout
      start_up_time: 2.0
      topics:
        - name: scan
          callerids:
            - {callerid: [], timeout: 0.5, max_timeouts_in_a_row: 2}

Each loop a group reports ``GENERAL_OK`` while its publishers' last message is at most
``timeout`` seconds old (counted from the start when nothing came yet), else
``TIMEOUT``; its age counts from its arrival, not from when a busy executive got round
to it (see :mod:`monitoring.observer_manager`); a hang is therefore reported at the first loop after ``timeout``. With
``max_timeouts_in_a_row`` it reports a silence only that many timeouts long, then
stays quiet until a message comes (the last report stands); a silence is reported at
least once, also one that began during the start-up time and is longer than that by
the first report. The default loop rate is
``max(1, 4 / shortest timeout)`` Hz, so a hang is seen within ``timeout * 1.25``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

from executive.bus.keys import topic
from executive.bus.message import Message
from executive.bus.payloads import GENERAL_OK, TIMEOUT
from knowledge.conventions import Above, AtLeast
from monitoring.caller_groups import TopicGroups, topics_with
from monitoring.observer import Environment, Handler, Observer, ObserverConfig, ObserverResult
from monitoring.state import Verdict


@dataclass(frozen=True)
class TimeoutSettings:
    timeout: Annotated[float, Above(0.0)]
    max_timeouts_in_a_row: Annotated[int | None, AtLeast(1)] = None


@dataclass(frozen=True, kw_only=True)
class TimeoutConfig(ObserverConfig):
    topics: Annotated[tuple[TopicGroups[TimeoutSettings], ...], topics_with(TimeoutSettings)]


class TimeoutObserver(Observer):
    type = "timeout"
    config_type = TimeoutConfig
    config: TimeoutConfig

    def __init__(self, config: TimeoutConfig, environment: Environment | None = None) -> None:
        super().__init__(config, environment)
        # caller -> the last message's arrival (ns)
        self._last: list[dict[str, int]] = [{} for _ in config.topics]
        # (topic, group) -> the last message before the silence reported as TIMEOUT
        self._reported: dict[tuple[int, int], int | None] = {}

    def default_rate(self) -> float:
        timeouts = [g.settings.timeout for t in self.config.topics for g in t.groups]
        return max(1.0, 4.0 / min(timeouts)) if timeouts else 1.0

    def inputs(self) -> list[tuple[str, Handler]]:
        return [
            (topic(t.name), self._handler(last))
            for t, last in zip(self.config.topics, self._last, strict=True)
        ]

    @staticmethod
    def _handler(last: dict[str, int]) -> Handler:
        def on_message(message: Message) -> None:
            last[message.caller_id] = message.received_ns

        return on_message

    def _reset(self, now: float) -> None:
        for last in self._last:
            last.clear()
        self._reported.clear()

    def _observe(self, now: float) -> list[ObserverResult]:
        results: list[ObserverResult] = []
        for i, (config, last) in enumerate(zip(self.config.topics, self._last, strict=True)):
            heard = list(last.items())
            for j, group in enumerate(config.groups):
                times = [t for caller, t in heard if group.includes(caller)]
                latest = max(times) if times else None
                reported = (i, j) in self._reported and self._reported[i, j] == latest
                verdict = self._verdict(group.settings, now, latest, reported=reported)
                if verdict is None:
                    continue
                if verdict.number == TIMEOUT:
                    self._reported[i, j] = latest
                silence = {"silence": self.since(max(times, default=self.started_ns))}
                results.append(
                    self.result(
                        (config.name,), verdict, now, values=silence, callerids=group.callerids
                    )
                )
        return results

    def _verdict(
        self, settings: TimeoutSettings, now: float, last: int | None, *, reported: bool
    ) -> Verdict | None:
        """OK or TIMEOUT; ``None`` once ``max_timeouts_in_a_row`` timeouts were reported
        (``reported``: this silence was reported already)."""
        silence = max(0.0, self.since(last if last is not None else self.started_ns))
        timeout = settings.timeout
        if silence <= timeout:
            return Verdict(
                GENERAL_OK, "ok", f"last message {silence:.3g} s ago (timeout {timeout:g} s)"
            )
        limit = settings.max_timeouts_in_a_row
        if limit is not None and silence // timeout > limit and reported:
            return None
        what = "no message" if last is not None else "no message since the start"
        return Verdict(TIMEOUT, "timeout", f"{what} for {silence:.3g} s (timeout {timeout:g} s)")
