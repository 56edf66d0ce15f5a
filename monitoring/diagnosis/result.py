"""What a diagnosis finds: a status and the minimal sets of faulty candidates."""

from __future__ import annotations

import enum
from dataclasses import dataclass

from executive.bus.payloads import DiagnosisInfo
from monitoring.diagnosis.model import ModelObserver


class Status(enum.Enum):
    OK = "OK"  # no observation failed
    DIAGNOSED = "DIAGNOSED"  # every minimal diagnosis (within the size bound) is listed
    INCONSISTENT = "INCONSISTENT"  # no set of faulty candidates explains the observations
    TIMEOUT = "TIMEOUT"  # cut off by the time bound: those found, and every smallest one


@dataclass(frozen=True)
class DiagnosisResult:
    """The outcome of one diagnosis.

    ``diagnoses`` are subset-minimal sets of candidate names, each sorted, smallest
    first. ``conflicts`` (INCONSISTENT only) is a minimal set of observations that
    no diagnosis explains together. ``failed`` lists the failed observations.
    With a size bound, DIAGNOSED with no diagnoses means every diagnosis is larger.
    """

    status: Status
    diagnoses: tuple[tuple[str, ...], ...] = ()
    conflicts: tuple[ModelObserver, ...] = ()
    failed: tuple[ModelObserver, ...] = ()
    elapsed: float = 0.0

    def to_info(self, stamp: float = 0.0) -> DiagnosisInfo:
        """The payload published on ``diagnoses``."""
        return DiagnosisInfo(
            status=self.status.value,
            diagnoses=self.diagnoses,
            conflicts=tuple(o.to_payload() for o in self.conflicts),
            failed=tuple(o.to_payload() for o in self.failed),
            elapsed=self.elapsed,
            stamp=stamp,
        )


def ordered(diagnoses: list[tuple[str, ...]] | set[tuple[str, ...]]) -> tuple[tuple[str, ...], ...]:
    """Diagnoses with sorted names, smallest first, then by name."""
    return tuple(sorted({tuple(sorted(d)) for d in diagnoses}, key=lambda d: (len(d), d)))
