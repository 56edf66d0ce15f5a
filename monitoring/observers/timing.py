"""The timing observer: the delay from a message on one topic to the next on another
(thesis 5.2.2, 6.2.5).

Configuration::

    - type: timing
      main_loop_rate: 1.0
      topics:
        - topicA: scan
          calleridA: []                # optional: only these publishers of topicA
          topicB: scan_filtered
          calleridB: []
          single_shot_mode: false      # true for stochastic (not periodic) messages
          filter: {type: mean, window_size: 10}
          states:
            - {state: ok, number: 1, delay: {type: less_than, less_than: 0.05}}

Periodic topics (the default): a measurement starts at the first message on A after
the last message on B and ends at the next message on B. ``single_shot_mode``: the
delay is measured between the closest pair, so every message on A but the last
before a B is ignored, and every B after the first until the next A. The observation
names both topics (``resource: [topicA, topicB]``) and the union of the caller ids.
The tug key ``use_global_subscriber`` is accepted and ignored: dura always shares one
subscription per topic. Before the first delay nothing is reported.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Annotated

from executive.bus.keys import topic
from executive.bus.message import Message
from knowledge.conventions import Key, Label, Titles
from knowledge.typed_reader import Entry
from monitoring.caller_groups import CallerIds, TopicName
from monitoring.filter import FilterConfig
from monitoring.observer import Environment, Handler, Observer, ObserverConfig, ObserverResult
from monitoring.state import ObserverState, classify, states_checking

PAIR = "topics '{topic_a}' -> '{topic_b}' of the {owner}"


@dataclass(frozen=True, kw_only=True)
class TopicPair:
    topic_a: Annotated[TopicName, Key("topicA")]
    topic_b: Annotated[TopicName, Key("topicB"), Titles(PAIR)]
    callerids_a: Annotated[CallerIds, Key("calleridA")] = ()
    callerids_b: Annotated[CallerIds, Key("calleridB")] = ()
    single_shot_mode: bool = False
    filter: Annotated[FilterConfig, Label("the filter of {what}")]
    states: Annotated[tuple[ObserverState, ...], states_checking("delay", every=True)]

    def after_read(self, entry: Entry) -> TopicPair | None:
        return self if self.states else None

    @property
    def callerids(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(self.callerids_a + self.callerids_b))


@dataclass(frozen=True, kw_only=True)
class TimingConfig(ObserverConfig):
    use_global_subscriber: bool = False  # tug's: accepted and ignored
    topics: Annotated[tuple[TopicPair, ...], Label("topic pair {n} of the {what}")]


class _Pairing:
    """Measures the delays of one topic pair from its queued arrivals."""

    def __init__(self, config: TopicPair) -> None:
        self.config = config
        self.arrivals: deque[tuple[int, bool]] = deque()  # (received in ns, is topic B)
        self.delays = config.filter.make()
        self.start: int | None = None  # the A message a measurement started at

    def handler(self, is_b: bool) -> Handler:
        callerids = self.config.callerids_b if is_b else self.config.callerids_a
        append = self.arrivals.append

        def on_message(message: Message) -> None:
            if not callerids or message.caller_id in callerids:
                append((message.received_ns, is_b))

        return on_message

    def reset(self) -> None:
        self.arrivals.clear()
        self.delays.reset()
        self.start = None

    def drain(self) -> None:
        batch = sorted(self.arrivals.popleft() for _ in range(len(self.arrivals)))
        for received, is_b in batch:
            if not is_b:
                if self.start is None or self.config.single_shot_mode:
                    self.start = received
            elif self.start is not None:
                self.delays.update((received - self.start) / 1e9)
                self.start = None


class TimingObserver(Observer):
    type = "timing"
    config_type = TimingConfig
    config: TimingConfig

    def __init__(self, config: TimingConfig, environment: Environment | None = None) -> None:
        super().__init__(config, environment)
        self._pairs = [_Pairing(p) for p in config.topics]

    def inputs(self) -> list[tuple[str, Handler]]:
        out: list[tuple[str, Handler]] = []
        for pair in self._pairs:
            out.append((topic(pair.config.topic_a), pair.handler(False)))
            out.append((topic(pair.config.topic_b), pair.handler(True)))
        return out

    def _reset(self, now: float) -> None:
        for pair in self._pairs:
            pair.reset()

    def _observe(self, now: float) -> list[ObserverResult]:
        results: list[ObserverResult] = []
        for pair in self._pairs:
            pair.drain()
            delay = pair.delays.state()
            if delay is None:
                continue
            config = pair.config
            verdict = classify(
                config.states, {"delay": delay}, f" s over {delay.sample_size} pairs"
            )
            results.append(
                self.result(
                    (config.topic_a, config.topic_b),
                    verdict,
                    now,
                    values={"delay": delay.value},
                    callerids=config.callerids,
                )
            )
        return results
