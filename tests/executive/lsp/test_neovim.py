"""``dura lsp`` in a real editor: a headless Neovim, set up by the documented snippet for
Neovim 0.7 (docs/how-to/editors.md), opens the use case's files, makes mistakes and asks
for every feature (``neovim_driver.lua``); the test checks what the editor got."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from tests.conftest import ROOT
from tests.executive.lsp.test_encoding import CAM

NVIM = shutil.which("nvim")
DRIVER = Path(__file__).with_name("neovim_driver.lua")

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(NVIM is None, reason="nvim is not installed (apt-get install neovim)"),
]


def documented_setup() -> str:
    """The Neovim 0.7 set-up of the editors page (the Lua block that uses start_client)."""
    page = (ROOT / "docs" / "how-to" / "editors.md").read_text()
    blocks = re.findall(r"```lua\n(.*?)```", page, re.DOTALL)
    return next(b for b in blocks if "vim.lsp.start_client" in b)


def run_neovim(usecase: Path, tmp_path: Path) -> dict[str, Any]:
    """Neovim's findings, from the use case's folder as its working directory."""
    assert NVIM is not None
    init = tmp_path / "init.lua"
    init.write_text(documented_setup() + "\n" + DRIVER.read_text())
    out = tmp_path / "neovim.json"
    env = {
        **os.environ,
        "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}",  # dura
        "PYTHONPATH": str(ROOT),
        "XDG_STATE_HOME": str(tmp_path / "state"),  # the client's log
        "DURA_NVIM_OUT": str(out),
        "DURA_PROBLEM": str(usecase / "examples" / "usecase" / "problem.pddl"),
        "DURA_ROBOT": str(usecase / "examples" / "usecase" / "robot.yaml"),
    }
    command = [NVIM, "--headless", "-n", "-i", "NONE", "-u", str(init)]
    done = subprocess.run(
        command,
        check=False,
        cwd=usecase,
        env=env,
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.exists(), f"neovim wrote nothing: {done.stdout}{done.stderr}"
    found: dict[str, Any] = json.loads(out.read_text())
    return found


def test_neovim_shows_diagnostics_hover_definition_completion_formatting_and_fixes(
    usecase: Path, tmp_path: Path
) -> None:
    problem = usecase / "examples" / "usecase" / "problem.pddl"
    problem.write_text(problem.read_text().replace("(robot_at dock)", "(robot_at dokc)"))
    robot = usecase / "examples" / "usecase" / "robot.yaml"
    text = robot.read_text()
    start = text.index("  cam:\n")
    cam = CAM.replace("laser_scna", "laser_scan")
    robot.write_text(text[:start] + cam + text[text.index("\n\n", start) :])
    got = run_neovim(usecase, tmp_path)
    assert "error" not in got, got["error"]
    assert got["log"] == []

    # the mistake on disk, at its word (lines from 0, columns in bytes)
    line = problem.read_text().splitlines().index("    (robot_at dokc)")
    [dokc] = got["problem"]
    assert (dokc["lnum"], dokc["col"], dokc["end_col"]) == (line, 14, 18)
    assert dokc["message"] == "unknown object 'dokc' (did you mean 'dock'?)"
    assert dokc["severity"] == 1  # an error
    assert got["robot_opened"] == []

    # a typo typed in robot.yaml after an emoji, then its quick fix
    [typo] = got["robot_typo"]
    assert typo["message"] == (
        "functionality 'cam' requires unknown capability 'laser_scna' (did you mean 'laser_scan'?)"
    )
    line = robot.read_text().splitlines().index(cam.rstrip("\n"))  # the file is as it was
    column = cam.encode().index(b"laser_scan")
    assert (typo["lnum"], typo["col"], typo["end_col"]) == (line, column, column + 10)
    assert got["code_actions"] == ["Change to 'laser_scan'"]
    assert got["fixed_line"] == cam.rstrip("\n")
    assert got["robot_fixed"] == []

    # the task's definition is the domain's action; hover there tells of it
    [definition] = got["definition"]
    assert definition["uri"].endswith("/domains/usecase/domain.pddl")
    assert definition["range"]["start"] == {"line": 28, "character": 20}
    assert got["jumped"] == {"file": "domain.pddl", "cursor": [29, 20]}
    assert "**action** `take_picture`" in got["hover"]
    assert "task: behavior `take_picture`" in got["hover"]
    assert got["references"] == 7  # declared, 4 uses in the domain, the problem, integrity
    assert {"robot_at", "connected", "picture_taken", "travel_time"} <= set(got["completion"])
    assert got["formatted_as_written"] is True
