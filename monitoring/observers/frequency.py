"""The frequency observer (alias ``hz``): how often a topic's publishers send (thesis 6.2.5).

Configuration, per topic and caller-id group (see :mod:`monitoring.caller_groups`)::

    - type: frequency
      main_loop_rate: 2.0
      start_up_time: 2.0
      topics:
        - name: scan
          callerids:
            - callerid: []
              filter: {type: mean, window_size: 10}   # filters the periods between messages
              timeout: 1.0                            # optional: silence that means "stopped"
              states:
                - {state: ok, number: 1, frequency: {type: in_between, lower_bound: 8, upper_bound: 12}}

The filter smooths each publisher's periods: the time between two of its messages,
taken from their send stamps (zenoh source timestamps), so that delays of reception
(batching, a busy observer) do not distort them; silences count from arrivals, which
a busy executive does not delay either (see :mod:`monitoring.observer_manager`). A
publisher starved of CPU is slow for everyone, and is reported. The frequency of a group is the sum
of ``1 / filtered period`` over its publishers, and the states check it (for
``student_t`` the period's std ``s`` becomes ``s / p^2``). A slow topic therefore
fits a slow state or none (``NO_STATE_FITS``). A publisher is
*stopped* after ``timeout`` seconds without a message, or by default after
``max(one loop, two filtered periods)``: a low-rate topic is not stopped just because
a loop passed without a message. A group whose publishers all stopped reports
``TIMEOUT``; the gap is not counted as a period when messages come back. Until a
publisher has sent two messages its frequency is unknown and nothing is reported for
it, unless it stays silent past ``timeout`` (or ``max(start_up_time, two loops)``); a
group that hears nothing at all after the start is stopped after ``timeout``, or
``max(start_up_time, two loops)``.
The legacy state key ``frequenzy`` (tug) is accepted.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Annotated

from executive.bus.keys import topic
from executive.bus.message import Message
from executive.bus.payloads import TIMEOUT
from knowledge.conventions import Above, Label
from knowledge.typed_reader import Entry
from monitoring.caller_groups import CallerGroup, TopicGroups, topics_with
from monitoring.filter import Filter, FilterConfig, FilterState
from monitoring.observer import Environment, Handler, Observer, ObserverConfig, ObserverResult
from monitoring.state import ObserverState, Verdict, classify, states_checking

_SHORTEST = 1e-9  # a period of two messages received at once


@dataclass(frozen=True, kw_only=True)
class FrequencySettings:
    filter: Annotated[FilterConfig, Label("the filter of {what}")]
    timeout: Annotated[float | None, Above(0.0)] = None
    states: Annotated[
        tuple[ObserverState, ...],
        states_checking("frequency", aliases={"frequenzy": "frequency"}, every=True),
    ]

    def after_read(self, entry: Entry) -> FrequencySettings | None:
        return self if self.states else None


@dataclass(frozen=True, kw_only=True)
class FrequencyConfig(ObserverConfig):
    topics: Annotated[tuple[TopicGroups[FrequencySettings], ...], topics_with(FrequencySettings)]


@dataclass
class _Track:
    """One publisher as one caller-id group sees it: its filtered periods."""

    filter: Filter
    bound: float  # silence after which the publisher counts as stopped


@dataclass
class _Group:
    config: CallerGroup[FrequencySettings]
    tracks: dict[str, _Track] = field(default_factory=dict)  # caller id -> track


@dataclass
class _Topic:
    config: TopicGroups[FrequencySettings]
    groups: list[_Group]
    # times in integer ns since the epoch
    arrivals: deque[tuple[str, int]] = field(default_factory=deque)  # (caller id, sent)
    heard: dict[str, int] = field(default_factory=dict)  # caller id -> last received
    sent: dict[str, int] = field(default_factory=dict)  # caller id -> last drained sent
    members: dict[str, list[_Group]] = field(default_factory=dict)  # caller id -> its groups


def frequency_of(periods: FilterState) -> FilterState:
    """The frequency state of a period state."""
    period = max(periods.value, _SHORTEST)
    return FilterState(
        1.0 / period,
        periods.sample_size,
        periods.std / period**2 if periods.std is not None else None,
        1.0 / max(periods.maximum, _SHORTEST) if periods.maximum is not None else None,
        1.0 / max(periods.minimum, _SHORTEST) if periods.minimum is not None else None,
    )


def total(states: list[FilterState]) -> FilterState:
    """The frequency of several publishers together: the sum of theirs."""
    if len(states) == 1:
        return states[0]
    stds = [s.std for s in states]
    minima = [s.minimum for s in states]
    maxima = [s.maximum for s in states]
    return FilterState(
        math.fsum(s.value for s in states),
        sum(s.sample_size for s in states),
        math.sqrt(math.fsum(s * s for s in stds if s is not None)) if None not in stds else None,
        math.fsum(m for m in minima if m is not None) if None not in minima else None,
        math.fsum(m for m in maxima if m is not None) if None not in maxima else None,
    )


class FrequencyObserver(Observer):
    type = "frequency"
    config_type = FrequencyConfig
    config: FrequencyConfig

    def __init__(self, config: FrequencyConfig, environment: Environment | None = None) -> None:
        super().__init__(config, environment)
        self._topics = [_Topic(t, [_Group(g) for g in t.groups]) for t in config.topics]

    def _reset(self, now: float) -> None:
        for feed in self._topics:
            feed.arrivals.clear()
            feed.heard.clear()
            feed.sent.clear()
            feed.members.clear()
            for group in feed.groups:
                group.tracks.clear()

    def inputs(self) -> list[tuple[str, Handler]]:
        return [(topic(t.config.name), self._handler(t)) for t in self._topics]

    @staticmethod
    def _handler(feed: _Topic) -> Handler:
        append = feed.arrivals.append
        heard = feed.heard

        def on_message(message: Message) -> None:
            # periods from the publisher's send times: exact, whatever delays reception
            sent, received = message.sent_ns, message.received_ns
            append((message.caller_id, sent if sent is not None else received))
            heard[message.caller_id] = received

        return on_message

    def _drain(self, feed: _Topic) -> None:
        """Turn the queued arrivals into periods, per publisher and caller-id group."""
        arrivals = feed.arrivals
        for _ in range(len(arrivals)):
            caller, sent = arrivals.popleft()
            previous = feed.sent.get(caller)
            feed.sent[caller] = sent
            groups = feed.members.get(caller)
            if groups is None:
                groups = [g for g in feed.groups if g.config.includes(caller)]
                feed.members[caller] = groups
            for group in groups:
                track = group.tracks.get(caller)
                if track is None:
                    settings = group.config.settings
                    bound = settings.timeout or math.inf  # no period known yet
                    group.tracks[caller] = _Track(settings.filter.make(), bound)
                elif previous is not None:
                    period = (sent - previous) / 1e9
                    if period > track.bound and track.filter.state() is not None:
                        track.filter.reset()  # it had stopped: the gap is no period
                    else:
                        track.filter.update(period)

    def _observe(self, now: float) -> list[ObserverResult]:
        results: list[ObserverResult] = []
        for feed in self._topics:
            self._drain(feed)
            for group in feed.groups:
                result = self._report(feed, group, now)
                if result is not None:
                    results.append(result)
        return results

    def _report(self, feed: _Topic, group: _Group, now: float) -> ObserverResult | None:
        settings = group.config.settings
        live: list[FilterState] = []
        waiting = False
        for caller, track in group.tracks.items():
            silence = self.since(feed.heard[caller])
            periods = track.filter.state()
            if periods is None:  # one message so far: wait for a second, not forever
                track.bound = settings.timeout or max(self.config.start_up_time, 2 * self.period)
                waiting = waiting or silence <= track.bound
                continue
            track.bound = settings.timeout or max(self.period, 2 * periods.value)
            if silence <= track.bound:
                live.append(frequency_of(periods))
        resource = (feed.config.name,)
        callerids = group.config.callerids
        if live:
            frequency = total(live)
            note = f" Hz from {frequency.sample_size} periods"
            found = classify(settings.states, {"frequency": frequency}, note)
            values = {"frequency": frequency.value}
            return self.result(resource, found, now, values=values, callerids=callerids)
        if waiting:
            return None
        if group.tracks:
            silence = self.since(max(feed.heard[c] for c in group.tracks))
            verbose = f"stopped: no message for {silence:.3g} s"
        else:
            silence = self.since(self.started_ns)
            bound = settings.timeout or max(self.config.start_up_time, 2 * self.period)
            if silence <= bound:
                return None
            verbose = f"stopped: no message since the start {silence:.3g} s ago"
        stopped = Verdict(TIMEOUT, "stopped", verbose)
        return self.result(resource, stopped, now, values={"frequency": 0.0}, callerids=callerids)
