"""A hostile bag's metadata.yaml goes through dura's one safe YAML reader: refused in a
moment with one line naming the file and line, by the real command."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import USECASE, run_dura
from tests.knowledge.test_yamlsource import BOMB, DEEP_FLOW


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        (BOMB, "metadata.yaml:6: its aliases expand to more than"),
        (DEEP_FLOW, "metadata.yaml"),
        ("x: " + "y" * (2 << 20), "metadata.yaml: too large"),
        ("[1, 2]\n", "metadata.yaml: not rosbag2 metadata"),
    ],
)
def test_a_hostile_bag_metadata_is_one_line(tmp_path: Path, text: str, reason: str) -> None:
    bag = tmp_path / "bag"
    bag.mkdir()
    (bag / "metadata.yaml").write_text(text)
    done = run_dura("replay", str(bag), "--robot", str(USECASE), timeout=30)
    assert done.returncode != 0
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and reason in lines[0], done.stderr[-2000:]
