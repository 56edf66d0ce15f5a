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
from typing import Annotated

from executive.bus.keys import topic
from executive.bus.message import Message
from executive.bus.payloads import GENERAL_ERROR
from knowledge.conventions import Key, Label, Titles
from knowledge.errors import BusError
from knowledge.typed_reader import Entry
from monitoring.caller_groups import CallerIds, TopicName
from monitoring.field_path import read_number
from monitoring.filter import Filter, FilterConfig, Text
from monitoring.observer import Environment, Handler, Observer, ObserverConfig, ObserverResult
from monitoring.state import ObserverState, Verdict, classify, states_checking


@dataclass(frozen=True, kw_only=True)
class ScoredTopic:
    name: Annotated[TopicName, Titles("topic '{value}' of the {owner}")]
    field: Text = "data"  # the dotted path of the score in a message
    callerids: Annotated[CallerIds, Key("callerid")] = ()
    filter: Annotated[FilterConfig, Label("the filter of {what}")]
    states: Annotated[tuple[ObserverState, ...], states_checking("score", every=True)]

    def after_read(self, entry: Entry) -> ScoredTopic | None:
        return self if self.states else None


@dataclass(frozen=True, kw_only=True)
class ScoresConfig(ObserverConfig):
    topics: Annotated[tuple[ScoredTopic, ...], Label("topic {n} of the {what}")]


class ScoresObserver(Observer):
    type = "scores"
    config_type = ScoresConfig
    config: ScoresConfig

    def __init__(self, config: ScoresConfig, environment: Environment | None = None) -> None:
        super().__init__(config, environment)
        self._queues: list[deque[Message]] = [deque() for _ in config.topics]
        self._filters: list[Filter] = [t.filter.make() for t in config.topics]

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
