"""The diagnosis engine: the newest observations against the current model, in clingo.

The model is grounded once per model update (``diagnosis.lp`` plus its facts);
observations are externals, so a changed observation only re-solves. Every answer
set of the domain-heuristic enumeration (``--enum-mode=domRec``) is a subset-minimal
diagnosis. Not thread-safe: the service calls it from one thread.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import clingo

from executive.protocol import ObservationInfo
from knowledge.asp import Asp, atom, facts
from knowledge.errors import ConfigError
from monitoring.diagnosis.model import ModelUpdate, Observer, ObserverType, SystemDescription
from monitoring.diagnosis.result import DiagnosisResult, Status, ordered

PROGRAM = Path(__file__).with_name("diagnosis.lp")
OPTIONS = ("--heuristic=Domain", "--enum-mode=domRec", "--project", "--models=0")


def model_facts(model: SystemDescription, index: dict[Observer, int]) -> str:
    """The facts of a system description, observers numbered by ``index``."""
    out = [atom("candidate", c) for c in model.candidates]
    for node in model.nodes:
        out += [atom("pub", node.name, m) for m in node.pub_topic]
        out += [atom("sub", node.name, m) for m in node.sub_topic]
    for observer, i in index.items():
        out.append(atom("observer", i))
        if observer.type.watches_nodes:
            name = observer.resource[0]
            out.append(atom("blame", i, name))
            if observer.type is ObserverType.RESOURCES:
                watched = model.node(name)
                out += [atom("feeds", i, m) for m in watched.sub_topic] if watched else []
            continue
        for topic in observer.topics:
            publishers = model.publishers(topic)
            chosen = (
                [p for p in publishers if p in observer.callerids]
                if observer.callerids
                else publishers
            )
            out += [atom("watch", i, topic, p) for p in chosen]
        if observer.behavior:
            out.append(atom("blame", i, observer.behavior))
    return facts(out)


@dataclass
class _Grounded:
    """The current model, grounded, and what is assigned to its externals."""

    asp: Asp
    assigned: dict[clingo.Symbol, bool]
    bounds: set[int]


class DiagnosisEngine:
    """Diagnoses the newest observations against a changing system description.

    Args:
        model: the initial system description (default: empty).
        exonerate: an OK topic observation means that topic is not abnormal.
        max_card: list only diagnoses of at most this many candidates.
        timeout: seconds one diagnosis may take; then the result is TIMEOUT.
    """

    def __init__(
        self,
        model: SystemDescription | None = None,
        *,
        exonerate: bool = False,
        max_card: int | None = None,
        timeout: float | None = None,
    ) -> None:
        self.exonerate = exonerate
        self.max_card = max_card
        self.timeout = timeout
        self._model = SystemDescription()
        self._index: dict[Observer, int] = {}
        self._observations: dict[Observer, ObservationInfo] = {}
        self._grounded: _Grounded | None = None
        if model is not None:
            self.set_model(model)

    # --- the model ----------------------------------------------------------------------

    @property
    def model(self) -> SystemDescription:
        return self._model

    def update(self, update: ModelUpdate) -> SystemDescription:
        """Change the model; raises :class:`ConfigError` (and changes nothing) if invalid."""
        self.set_model(self._model.apply(update))
        return self._model

    def set_model(self, model: SystemDescription) -> None:
        """Replace the model; observations of observers it no longer has are forgotten."""
        problems = model.problems()
        if problems:
            raise ConfigError(problems[0][1])
        self._model = model
        self._index = {o: i for i, o in enumerate(dict.fromkeys(model.observers))}
        self._observations = {o: v for o, v in self._observations.items() if o in self._index}
        self._grounded = None

    # --- observations -------------------------------------------------------------------

    def observe(self, info: ObservationInfo) -> bool:
        """Keep an observation if it is the newest of its observer.

        Returns whether the diagnosis may change (the observer's verdict changed).

        Raises:
            ConfigError: the observation's type is unknown, or no observer of the
                model made it.
        """
        observer = Observer.make(info.type, info.resource, info.callerids)
        if observer not in self._index:
            raise ConfigError(f"observation of {observer}: no such observer in the model")
        old = self._observations.get(observer)
        if old is not None and info.stamp < old.stamp:
            return False
        self._observations[observer] = info
        return old is None or old.failed != info.failed

    @property
    def observations(self) -> dict[Observer, ObservationInfo]:
        return dict(self._observations)

    def failed(self) -> tuple[Observer, ...]:
        return tuple(o for o, info in self._observations.items() if info.failed)

    # --- diagnosis ----------------------------------------------------------------------

    def diagnose(self) -> DiagnosisResult:
        """All subset-minimal diagnoses of the newest observations."""
        start = time.perf_counter()
        failed = self.failed()
        if not failed:
            return DiagnosisResult(Status.OK, elapsed=time.perf_counter() - start)
        grounded = self._ground()
        self._assign(grounded, self._wanted())
        self._bound(grounded, self.max_card)
        outcome = grounded.asp.solve(timeout=self.timeout)
        found = ordered(
            [tuple(str(a[0]) for a in answer.get("faulty")) for answer in outcome.answers]
        )
        if outcome.interrupted:
            status = Status.TIMEOUT
        elif found or (self.max_card is not None and self._consistent(grounded)):
            status = Status.DIAGNOSED
        else:
            status = Status.INCONSISTENT
        conflicts = self._conflicts(grounded) if status is Status.INCONSISTENT else ()
        return DiagnosisResult(status, found, conflicts, failed, time.perf_counter() - start)

    def _ground(self) -> _Grounded:
        if self._grounded is None:
            asp = Asp(OPTIONS)
            asp.load(PROGRAM)
            asp.add(model_facts(self._model, self._index), source="<model>")
            asp.ground()
            self._grounded = _Grounded(asp, {}, set())
        return self._grounded

    def _wanted(self) -> dict[clingo.Symbol, bool]:
        """The value of every observation external for the newest observations."""
        wanted: dict[clingo.Symbol, bool] = {}
        for observer, i in self._index.items():
            info = self._observations.get(observer)
            wanted[atom("failed", i)] = info is not None and info.failed
            wanted[atom("ok", i)] = info is not None and not info.failed and self.exonerate
        return wanted

    @staticmethod
    def _assign(grounded: _Grounded, wanted: dict[clingo.Symbol, bool]) -> None:
        for symbol, value in wanted.items():
            if grounded.assigned.get(symbol) is not value:
                grounded.asp.assign_external(symbol, value)
                grounded.assigned[symbol] = value

    @staticmethod
    def _bound(grounded: _Grounded, max_card: int | None) -> None:
        if max_card is not None and max_card not in grounded.bounds:
            grounded.asp.ground([("bound", (max_card,))])
            grounded.bounds.add(max_card)
        for k in grounded.bounds:
            grounded.asp.assign_external(atom("limit", k), k == max_card)

    def _consistent(self, grounded: _Grounded) -> bool:
        """Whether some diagnosis exists, of any size."""
        self._bound(grounded, None)
        grounded.asp.set("solve.models", "1")
        try:
            return bool(grounded.asp.solve(timeout=self.timeout).answers)
        finally:
            grounded.asp.set("solve.models", "0")
            self._bound(grounded, self.max_card)

    def _conflicts(self, grounded: _Grounded) -> tuple[Observer, ...]:
        """A minimal set of observations that no diagnosis explains together.

        The observations become assumptions: clingo's unsatisfiable core is a first
        conflict, and dropping each member that is not needed makes it minimal.
        """
        observers = {i: o for o, i in self._index.items()}
        wanted = self._wanted()
        present = [s for s, value in wanted.items() if value]
        for symbol in wanted:
            grounded.asp.assign_external(symbol, None)
        grounded.assigned.clear()
        self._bound(grounded, None)
        grounded.asp.set("solve.models", "1")

        def core_of(chosen: list[clingo.Symbol]) -> list[clingo.Symbol] | None:
            """The failing part of the chosen observations, or None if they are consistent."""
            keep = set(chosen)
            assumptions = [(s, s in keep) for s in wanted]
            outcome = grounded.asp.solve(assumptions=assumptions, timeout=self.timeout)
            if outcome.satisfiable is not False:
                return None
            return [s for s in chosen if s in set(outcome.core)] or chosen

        try:
            core = core_of(present) or present
            i = 0
            while i < len(core):
                smaller = core_of(core[:i] + core[i + 1 :])
                if smaller is None:
                    i += 1  # needed
                else:
                    core = smaller
                    i = min(i, len(core))
        finally:
            grounded.asp.set("solve.models", "0")
            self._assign(grounded, wanted)
            self._bound(grounded, self.max_card)
        numbers = sorted({int(str(s.arguments[0])) for s in core})
        return tuple(observers[i] for i in numbers)
