"""The scores observer (alias ``value``): a numeric field of a topic's messages (thesis 6.2.5).

Configuration::

    - type: scores
      main_loop_rate: 1.0
      topics:
        - name: battery
          field: charge.percent          # dotted path into the JSON payload (default: data)
          callerid: [battery_driver]     # optional: only these publishers
          filter: {type: mean, window_size: 5}
          states:
            - {state: charged, number: 1, score: {type: greater_than, greater_than: 20}}

The thesis' observer read a bare float message; here ``field`` names a number
anywhere in the payload (``data`` fits a ported ``std_msgs/Float*`` topic). A loop in
which messages came but none had a number there reports ``GENERAL_ERROR``; before the
first value nothing is reported.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from executive.bus.keys import topic
from executive.bus.payloads import GENERAL_ERROR
from executive.bus.session import Message
from knowledge.errors import BusError
from monitoring.caller_groups import topic_name
from monitoring.config_entry import Entry
from monitoring.field_path import read_number
from monitoring.filter import Filter, FilterConfig, read_filter
from monitoring.observer import Environment, Handler, Observer, ObserverConfig, ObserverResult
from monitoring.state import ObserverState, Verdict, classify, read_states


@dataclass(frozen=True)
class ScoredTopic:
    name: str
    field: str
    callerids: tuple[str, ...]
    filter: FilterConfig
    states: tuple[ObserverState, ...]


@dataclass(frozen=True, kw_only=True)
class ScoresConfig(ObserverConfig):
    topics: tuple[ScoredTopic, ...]


def read_topic(entry: Entry, owner: str) -> ScoredTopic | None:
    name = topic_name(entry, "name")
    if name is not None:
        entry.what = f"topic '{name}' of the {owner}"
    field = entry.text("field", "data") or "data"
    callerids = entry.names("callerid")
    filter_config = read_filter(entry.entry("filter", f"the filter of {entry.what}", required=True))
    states = read_states(entry, ("score",), every=True)
    entry.close()
    if name is None or filter_config is None or not states:
        return None
    return ScoredTopic(name, field, callerids, filter_config, states)


class ScoresObserver(Observer):
    type = "scores"
    config: ScoresConfig

    def __init__(self, config: ScoresConfig, environment: Environment | None = None) -> None:
        super().__init__(config, environment)
        self._queues: list[deque[Message]] = [deque() for _ in config.topics]
        self._filters: list[Filter] = [t.filter.make() for t in config.topics]

    @classmethod
    def read(cls, entry: Entry, common: ObserverConfig) -> ScoresConfig | None:
        what = f"topic {{n}} of the {entry.what}"
        topics = [read_topic(e, entry.what) for e in entry.entries("topics", what, required=True)]
        return ScoresConfig(**common.common(), topics=tuple(t for t in topics if t is not None))

    def inputs(self) -> list[tuple[str, Handler]]:
        return [
            (topic(t.name), q.append) for t, q in zip(self.config.topics, self._queues, strict=True)
        ]

    def _reset(self, now: float) -> None:
        for queue, scores in zip(self._queues, self._filters, strict=True):
            queue.clear()
            scores.reset()

    def _observe(self, now: float) -> list[ObserverResult]:
        results: list[ObserverResult] = []
        for config, queue, scores in zip(
            self.config.topics, self._queues, self._filters, strict=True
        ):
            missing = 0
            for _ in range(len(queue)):
                message = queue.popleft()
                if config.callerids and message.caller_id not in config.callerids:
                    continue
                try:
                    value = read_number(message.payload, config.field)
                except BusError:
                    value = None
                if value is None:
                    missing += 1
                else:
                    scores.update(value)
            score = scores.state()
            values = {"score": score.value} if score is not None else {}
            if score is not None:
                note = f" ('{config.field}' over {score.sample_size} messages)"
                verdict = classify(config.states, {"score": score}, note)
            elif missing:
                detail = f"{missing} messages without a number at '{config.field}'"
                verdict = Verdict(GENERAL_ERROR, "no value", detail)
            else:
                continue
            results.append(
                self.result((config.name,), verdict, now, values=values, callerids=config.callerids)
            )
        return results
