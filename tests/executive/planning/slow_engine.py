"""A real planner that takes its time: Kairos, answering no sooner than ``THINK``
seconds after it was asked (as on a slow computer or a larger problem).

Tests that need a planning round to last (to cancel a goal while its plan is being
computed) register it as a planner plugin, exactly as a third-party engine is
registered: an entry point in the group ``dura.planners``. The plans are Kairos' own,
validated like any other; only the answer waits.
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any

from up_kairos.engine import KairosEngine

NAME = "kairos-slow"
THINK = 2.0  # seconds, unless the environment says otherwise:
THINK_VARIABLE = "DURA_SLOW_KAIROS_SECONDS"


class SlowKairos(KairosEngine):  # type: ignore[misc]
    """Kairos that answers ``THINK`` (or ``$DURA_SLOW_KAIROS_SECONDS``) seconds after it
    was asked, at the earliest."""

    @property
    def name(self) -> str:
        return NAME

    def _solve_with_params(self, problem: Any, *args: Any, **kwargs: Any) -> Any:
        began = time.monotonic()
        result = super()._solve_with_params(problem, *args, **kwargs)
        think = float(os.environ.get(THINK_VARIABLE, THINK))
        time.sleep(max(0.0, think - (time.monotonic() - began)))
        return result


def register(folder: Path) -> Path:
    """Install the engine as a plugin for every process with ``folder`` on its path."""
    info = folder / "dura_slow_kairos-1.0.dist-info"
    info.mkdir(parents=True, exist_ok=True)
    (info / "METADATA").write_text(
        "Metadata-Version: 2.1\nName: dura-slow-kairos\nVersion: 1.0\n", encoding="utf-8"
    )
    (info / "entry_points.txt").write_text(
        f"[dura.planners]\n{NAME} = tests.executive.planning.slow_engine:SlowKairos\n",
        encoding="utf-8",
    )
    return folder
