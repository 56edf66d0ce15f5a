"""What a replay saw: a timeline of component states, observations that changed,
diagnoses and would-be repairs, and how long each diagnosis held.

Times are seconds since the start of the recording (``Timeline.origin`` is that start
in the recording's own clock, seconds since the epoch for a ROS 2 bag). Entries are
pure data, so a test can pin them and two replays of one recording compare equal.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

from executive.bus.payloads import DiagnosisInfo, ObservationInfo
from executive.bus.undecodable import Undecodable
from knowledge.errors import ConfigError
from monitoring.diagnosis.model import observer_from

Names = tuple[str, ...]


class EntryKind(enum.Enum):
    STATE = "state"  # a component's lifecycle state changed (recordings of dura runs)
    OBSERVATION = "observation"  # an observer's verdict on a resource changed
    DIAGNOSIS = "diagnosis"  # the diagnosis result changed
    REPAIR = "repair"  # a repair rule fired: its action would run


def _number(value: float) -> float:
    """Round a time or value to the microsecond, as it is printed and compared."""
    return round(value, 6)


@dataclass(frozen=True)
class StateEntry:
    time: float
    component: str
    state: str
    reason: str = ""
    kind: ClassVar[EntryKind] = EntryKind.STATE

    def describe(self) -> str:
        return f"{self.component} is {self.state}" + (f" ({self.reason})" if self.reason else "")

    def to_payload(self) -> dict[str, Any]:
        return {"time": self.time, "kind": self.kind.value, "component": self.component,
                "state": self.state, "reason": self.reason}  # fmt: skip


@dataclass(frozen=True)
class ObservationEntry:
    time: float
    observer: str  # the observer's id, <component>/<index>
    info: ObservationInfo
    values: Mapping[str, float] = field(default_factory=dict)
    kind: ClassVar[EntryKind] = EntryKind.OBSERVATION

    @property
    def resource(self) -> str:
        """The resource as people write it: ``scan``, ``scan [lidar]``."""
        text = ", ".join(self.info.resource)
        return text + (f" [{', '.join(self.info.callerids)}]" if self.info.callerids else "")

    def describe(self) -> str:
        info = self.info
        values = ", ".join(f"{k} {v:.4g}" for k, v in self.values.items())
        detail = f"; {info.verbose_observation_msg}" if info.verbose_observation_msg else ""
        measured = f" [{values}]" if values else ""
        return (
            f"{self.observer} {info.type} {self.resource}: "
            f"{info.observation_msg} ({info.observation}){measured}{detail}"
        )

    def to_payload(self) -> dict[str, Any]:
        info = self.info.to_payload()
        del info["stamp"]
        values = {k: _number(v) for k, v in self.values.items()}
        return {"time": self.time, "kind": self.kind.value, "observer": self.observer,
                **info, "values": values}  # fmt: skip


@dataclass(frozen=True)
class DiagnosisEntry:
    time: float
    status: str  # OK, DIAGNOSED, INCONSISTENT or TIMEOUT
    diagnoses: tuple[Names, ...] = ()
    failed: Names = ()  # the failed observations, as ``type[resources]``
    kind: ClassVar[EntryKind] = EntryKind.DIAGNOSIS

    def describe(self) -> str:
        if self.status == "OK":
            return "OK: nothing is faulty"
        found = " | ".join(", ".join(d) for d in self.diagnoses) or "none"
        return f"{self.status}: {found} (failed: {'; '.join(self.failed) or '-'})"

    def to_payload(self) -> dict[str, Any]:
        return {"time": self.time, "kind": self.kind.value, "status": self.status,
                "diagnoses": [list(d) for d in self.diagnoses],
                "failed": list(self.failed)}  # fmt: skip


@dataclass(frozen=True)
class RepairEntry:
    time: float
    rule: str
    action: str  # what it would do: "restart lidar"
    faulty: Names = ()  # the possibly faulty components of the newest diagnosis
    kind: ClassVar[EntryKind] = EntryKind.REPAIR

    def describe(self) -> str:
        faulty = f" (possibly faulty: {', '.join(self.faulty)})" if self.faulty else ""
        return f"rule {self.rule} would {self.action}{faulty}"

    def to_payload(self) -> dict[str, Any]:
        return {"time": self.time, "kind": self.kind.value, "rule": self.rule,
                "action": self.action, "faulty": list(self.faulty)}  # fmt: skip


Entry = StateEntry | ObservationEntry | DiagnosisEntry | RepairEntry


def recorded_diagnosis(payload: dict[str, Any], time: float) -> DiagnosisEntry:
    """Read a recorded ``diagnoses`` payload as an entry.

    Raises:
        KeyError, ValueError, TypeError: the payload is malformed.
    """
    info = DiagnosisInfo.from_payload(payload)
    failed = tuple(_observer_text(f) for f in info.failed)
    return DiagnosisEntry(time, info.status, info.diagnoses, failed)


def recorded_repair(payload: dict[str, Any], time: float) -> RepairEntry | None:
    """Read a recorded ``events`` payload as an entry if it is a RULE_FIRED event."""
    data = payload.get("data")
    if payload.get("kind") != "RULE_FIRED" or not isinstance(data, dict):
        return None
    faulty = tuple(str(n) for n in data.get("faulty", ()))
    return RepairEntry(time, str(payload.get("subject")), str(data.get("action", "")), faulty)


def _observer_text(payload: dict[str, Any]) -> str:
    """Name an observer of a diagnosis payload as the diagnosis does: ``type[resources]``."""
    try:
        return str(observer_from(payload))
    except (ConfigError, KeyError, TypeError, ValueError):
        return str(payload)


@dataclass(frozen=True)
class Hold:
    """How long one diagnosis (a set of faulty names) was part of the published result."""

    diagnosis: Names
    periods: tuple[tuple[float, float], ...]  # (from, to); ``to`` is the end if still held
    held_at_end: bool = False

    @property
    def total(self) -> float:
        return _number(sum(end - begin for begin, end in self.periods))

    def to_payload(self) -> dict[str, Any]:
        return {
            "diagnosis": list(self.diagnosis),
            "total": self.total,
            "periods": [list(p) for p in self.periods],
            "held_at_end": self.held_at_end,
        }


def _close(ours: list[float], theirs: list[float], tolerance: float) -> bool:
    return len(ours) == len(theirs) and all(
        abs(a - b) <= tolerance for a, b in zip(ours, theirs, strict=True)
    )


def _periods(periods: tuple[tuple[float, float], ...]) -> str:
    return ", ".join(f"{a:.3f}-{b:.3f}" for a, b in periods) or "never"


def _firings(entries: list[RepairEntry]) -> str:
    return ", ".join(f"{e.rule} at {e.time:.3f}" for e in entries) or "none"


def holds(entries: tuple[DiagnosisEntry, ...], end: float) -> list[Hold]:
    """Compute how long each diagnosis held, in order of first appearance."""
    since: dict[Names, float] = {}
    periods: dict[Names, list[tuple[float, float]]] = {}
    for entry in entries:
        now = set(entry.diagnoses)
        for diagnosis in [d for d in since if d not in now]:
            periods[diagnosis].append((since.pop(diagnosis), entry.time))
        for diagnosis in entry.diagnoses:
            if diagnosis not in since:
                since[diagnosis] = entry.time
                periods.setdefault(diagnosis, [])
    for diagnosis, begin in since.items():
        periods[diagnosis].append((begin, end))
    return [Hold(d, tuple(p), d in since) for d, p in periods.items()]


@dataclass(frozen=True)
class Timeline:
    """The outcome of a replay.

    Args:
        origin: the recording's time of the timeline's 0 (its first message).
        begin, end: the replayed window, in seconds since ``origin``.
        entries: what happened, in order.
        recorded: what the recording itself says was diagnosed and repaired (a dura
            run's own ``diagnoses`` and RULE_FIRED events), to compare with.
        messages: how many messages were replayed.
        skipped: observers that were not replayed, each with the reason.
        undecodable: the topics with messages that did not decode: how many, and why
            the first did not (the replay went on without them).
    """

    origin: float
    begin: float
    end: float
    entries: tuple[Entry, ...] = ()
    recorded: tuple[DiagnosisEntry | RepairEntry, ...] = ()
    messages: int = 0
    skipped: tuple[str, ...] = ()
    undecodable: tuple[Undecodable, ...] = ()

    def observations(self, observer: str | None = None) -> list[ObservationEntry]:
        return [
            e
            for e in self.entries
            if isinstance(e, ObservationEntry) and observer in (None, e.observer)
        ]

    def diagnoses(self) -> list[DiagnosisEntry]:
        return [e for e in self.entries if isinstance(e, DiagnosisEntry)]

    def repairs(self) -> list[RepairEntry]:
        return [e for e in self.entries if isinstance(e, RepairEntry)]

    def states(self) -> list[StateEntry]:
        return [e for e in self.entries if isinstance(e, StateEntry)]

    def holds(self) -> list[Hold]:
        """Compute how long each diagnosis held (to the end if it still did)."""
        return holds(tuple(self.diagnoses()), self.end)

    def recorded_holds(self) -> list[Hold]:
        """Compute how long each diagnosis held in the recording's own (live) diagnoses."""
        recorded = tuple(e for e in self.recorded if isinstance(e, DiagnosisEntry))
        return holds(recorded, self.end)

    def diagnosed(self) -> list[Names]:
        """List every diagnosis that held at some time, in order of first appearance."""
        return [h.diagnosis for h in self.holds()]

    def differences(self, tolerance: float) -> list[str]:
        """Compare the replay with what the recording says the live run diagnosed and
        fired: one line per difference (none: as live, within ``tolerance`` seconds)."""
        if not self.recorded:
            return []
        found = []
        live = {h.diagnosis: h.periods for h in self.recorded_holds()}
        replayed = {h.diagnosis: h.periods for h in self.holds()}
        for diagnosis in [*live, *(d for d in replayed if d not in live)]:
            ours, theirs = replayed.get(diagnosis, ()), live.get(diagnosis, ())
            if not _close([x for p in ours for x in p], [x for p in theirs for x in p], tolerance):
                found.append(
                    f"diagnosis {', '.join(diagnosis) or '(none)'}: live {_periods(theirs)}, "
                    f"replayed {_periods(ours)}"
                )
        live_fired = [e for e in self.recorded if isinstance(e, RepairEntry)]
        fired = self.repairs()
        rules = [e.rule for e in fired] == [e.rule for e in live_fired]
        if not rules or not _close(
            [e.time for e in fired], [e.time for e in live_fired], tolerance
        ):
            found.append(f"rules fired: live {_firings(live_fired)}, replayed {_firings(fired)}")
        if found and self.skipped:
            found.append(f"not replayed, so not compared: {'; '.join(self.skipped)}")
        return found

    def to_payload(self) -> dict[str, Any]:
        return {
            "origin": self.origin,
            "begin": self.begin,
            "end": self.end,
            "messages": self.messages,
            "timeline": [e.to_payload() for e in self.entries],
            "summary": {
                "diagnoses": [h.to_payload() for h in self.holds()],
                "repairs": [e.to_payload() for e in self.repairs()],
                "recorded_diagnoses": [h.to_payload() for h in self.recorded_holds()],
            },
            "recorded": [e.to_payload() for e in self.recorded],
            "skipped": list(self.skipped),
            "undecodable": [u.to_payload() for u in self.undecodable],
        }
