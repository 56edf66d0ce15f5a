"""The timestamp observer: how old messages are when they arrive (thesis 6.2.5).

Configuration, per topic and caller-id group (see :mod:`monitoring.caller_groups`)::

    - type: timestamp
      main_loop_rate: 1.0
      topics:
        - name: scan
          callerids:
            - callerid: []
              filter: {type: mean, window_size: 10}
              states:
                - {state: fresh, number: 1, age: {type: less_than, less_than: 0.2}}

The age of a message is its arrival time minus the ``stamp`` of its payload (seconds;
the publisher's clock). A loop in which messages came but none had a numeric
``stamp`` reports ``GENERAL_ERROR``; before the first age nothing is reported.

Clocks: the age compares the observer's clock with the publisher's, so it assumes they
agree. On a robot that spans computers (host agents), an offset between the
publisher's computer and the observer's adds to every age: keep the computers'
clocks synchronised (chrony, NTP) to well below the smallest ``age`` bound. The other
topic observers measure differences on one clock and do not care.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Annotated

from executive.bus.keys import topic
from executive.bus.message import Message
from executive.bus.payloads import GENERAL_ERROR
from knowledge.conventions import Label
from knowledge.errors import BusError
from knowledge.typed_reader import Entry
from monitoring.caller_groups import TopicGroups, topics_with
from monitoring.filter import Filter, FilterConfig
from monitoring.observer import Environment, Handler, Observer, ObserverConfig, ObserverResult
from monitoring.state import ObserverState, Verdict, classify, states_checking


@dataclass(frozen=True)
class TimestampSettings:
    filter: Annotated[FilterConfig, Label("the filter of {what}")]
    states: Annotated[tuple[ObserverState, ...], states_checking("age", every=True)]

    def after_read(self, entry: Entry) -> TimestampSettings | None:
        return self if self.states else None


@dataclass(frozen=True, kw_only=True)
class TimestampConfig(ObserverConfig):
    topics: Annotated[tuple[TopicGroups[TimestampSettings], ...], topics_with(TimestampSettings)]


class TimestampObserver(Observer):
    type = "timestamp"
    config_type = TimestampConfig
    config: TimestampConfig

    def __init__(self, config: TimestampConfig, environment: Environment | None = None) -> None:
        super().__init__(config, environment)
        self._queues: list[deque[Message]] = [deque() for _ in config.topics]
        self._filters = [[g.settings.filter.make() for g in t.groups] for t in config.topics]

    def inputs(self) -> list[tuple[str, Handler]]:
        return [
            (topic(t.name), q.append) for t, q in zip(self.config.topics, self._queues, strict=True)
        ]

    def _reset(self, now: float) -> None:
        for queue in self._queues:
            queue.clear()
        for filters in self._filters:
            for f in filters:
                f.reset()

    def _observe(self, now: float) -> list[ObserverResult]:
        results: list[ObserverResult] = []
        for config, queue, filters in zip(
            self.config.topics, self._queues, self._filters, strict=True
        ):
            unstamped = self._drain(config, queue, filters)
            for group, ages in zip(config.groups, filters, strict=True):
                age = ages.state()
                values = {"age": age.value} if age is not None else {}
                if age is not None:
                    note = f" s over {age.sample_size} messages"
                    verdict = classify(group.settings.states, {"age": age}, note)
                elif unstamped:
                    detail = f"{unstamped} messages without a numeric 'stamp'"
                    verdict = Verdict(GENERAL_ERROR, "no stamp", detail)
                else:
                    continue
                results.append(
                    self.result(
                        (config.name,), verdict, now, values=values, callerids=group.callerids
                    )
                )
        return results

    @staticmethod
    def _drain(
        config: TopicGroups[TimestampSettings], queue: deque[Message], filters: list[Filter]
    ) -> int:
        """Feed the ages of the queued messages to the filters; returns how many had no stamp."""
        unstamped = 0
        for _ in range(len(queue)):
            message = queue.popleft()
            try:
                stamp = message.stamp_ns
            except BusError:
                stamp = None
            if stamp is None:
                unstamped += 1
                continue
            age = (message.received_ns - stamp) / 1e9
            for group, ages in zip(config.groups, filters, strict=True):
                if group.includes(message.caller_id):
                    ages.update(age)
        return unstamped
