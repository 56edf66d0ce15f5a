"""``dura record`` as a user runs it: without an executive, and with bad sizes."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from subprocess import CompletedProcess

from tests.conftest import USECASE, free_endpoint

Dura = Callable[..., CompletedProcess[str]]


def test_record_without_an_executive_says_so_in_one_line(dura: Dura, tmp_path: Path) -> None:
    out = tmp_path / "run.mcap"
    result = dura("record", str(out), "--robot", str(USECASE), "--endpoint", free_endpoint())
    assert result.returncode == 1
    assert result.stderr.startswith("dura: no executive for robot 'usecase' at tcp/127.0.0.1:")
    assert result.stderr.count("\n") == 1
    assert not out.exists()


def test_a_size_below_what_a_recording_needs_is_a_usage_error(dura: Dura, tmp_path: Path) -> None:
    result = dura("record", str(tmp_path / "run.mcap"), "--max-size", "0.01")
    assert result.returncode == 2
    assert "argument --max-size: must be from 0.0625 to 1048576 MB, not 0.01" in result.stderr
