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

from executive.bus.keys import topic
from executive.bus.session import Message
from monitoring.caller_groups import topic_name
from monitoring.config_entry import Entry
from monitoring.filter import FilterConfig, read_filter
from monitoring.observer import Environment, Handler, Observer, ObserverConfig, ObserverResult
from monitoring.state import ObserverState, classify, read_states


@dataclass(frozen=True)
class TopicPair:
    topic_a: str
    callerids_a: tuple[str, ...]
    topic_b: str
    callerids_b: tuple[str, ...]
    single_shot_mode: bool
    filter: FilterConfig
    states: tuple[ObserverState, ...]

    @property
    def callerids(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(self.callerids_a + self.callerids_b))


@dataclass(frozen=True, kw_only=True)
class TimingConfig(ObserverConfig):
    topics: tuple[TopicPair, ...]


def read_pair(entry: Entry, owner: str) -> TopicPair | None:
    a = topic_name(entry, "topicA")
    b = topic_name(entry, "topicB")
    if a is not None and b is not None:
        entry.what = f"topics '{a}' -> '{b}' of the {owner}"
    callerids_a = entry.names("calleridA")
    callerids_b = entry.names("calleridB")
    single_shot = entry.flag("single_shot_mode", False)
    filter_config = read_filter(entry.entry("filter", f"the filter of {entry.what}", required=True))
    states = read_states(entry, ("delay",), every=True)
    entry.close()
    if a is None or b is None or filter_config is None or not states:
        return None
    return TopicPair(a, callerids_a, b, callerids_b, single_shot, filter_config, states)


class _Pairing:
    """Measures the delays of one topic pair from its queued arrivals."""

    def __init__(self, config: TopicPair) -> None:
        self.config = config
        self.arrivals: deque[tuple[float, bool]] = deque()  # (received, is topic B)
        self.delays = config.filter.make()
        self.start: float | None = None  # the A message a measurement started at

    def handler(self, is_b: bool) -> Handler:
        callerids = self.config.callerids_b if is_b else self.config.callerids_a
        append = self.arrivals.append

        def on_message(message: Message) -> None:
            if not callerids or message.caller_id in callerids:
                append((message.received, is_b))

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
                self.delays.update(received - self.start)
                self.start = None


class TimingObserver(Observer):
    type = "timing"
    config: TimingConfig

    def __init__(self, config: TimingConfig, environment: Environment | None = None) -> None:
        super().__init__(config, environment)
        self._pairs = [_Pairing(p) for p in config.topics]

    @classmethod
    def read(cls, entry: Entry, common: ObserverConfig) -> TimingConfig | None:
        entry.flag("use_global_subscriber", False)
        what = f"topic pair {{n}} of the {entry.what}"
        pairs = [read_pair(e, entry.what) for e in entry.entries("topics", what, required=True)]
        return TimingConfig(**common.common(), topics=tuple(p for p in pairs if p is not None))

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
