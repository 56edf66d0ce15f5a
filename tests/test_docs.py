"""The documentation site: it builds without a warning (``mkdocs build --strict``), its
generated reference pages say what the code has, and the tutorial runs as written.

The tutorial's runner: each fenced block in the page's order. A block with a ``title``
(```` ```pddl title="domain.pddl" ````) is a file the reader writes: it is written there
(before the section where the reader starts changing the robot, ``CHANGES_FROM``, it
must be the file as ``dura new`` made it). A ``console`` block is a session as in the
README (``tests/test_readme.py``: its rules of comparison): ``cd DIR`` changes folder,
``dura`` and ``pytest`` run (with robot time ten times faster), and a command ending in
``&`` runs in the background until its block ends, its first line compared.
"""

from __future__ import annotations

import importlib.util
import os
import re
import shlex
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT, free_endpoint
from tests.test_readme import matches

DOCS = ROOT / "docs"
TUTORIAL = DOCS / "tutorial" / "first-robot.md"
CHANGES_FROM = "## 6."  # the tutorial's section where the reader changes the robot
FENCE = re.compile(r'^```(\w*)(?:\s+title="([^"]+)")?\s*$')


def reference_pages() -> object:
    spec = importlib.util.spec_from_file_location("reference_pages", DOCS / "reference_pages.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_the_site_builds_without_a_warning(tmp_path: Path) -> None:
    if importlib.util.find_spec("mkdocs") is None:
        pytest.skip("mkdocs is not installed: pip install -e '.[docs]'")
    built = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(tmp_path / "site")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
        check=False,
    )
    assert built.returncode == 0, built.stderr
    tutorial = (tmp_path / "site" / "tutorial" / "first-robot" / "index.html").read_text()
    assert "Your first robot" in tutorial and "Teach it to charge" in tutorial
    sdk = (tmp_path / "site" / "reference" / "sdk" / "index.html").read_text()
    assert "executive.sdk.Behavior" in sdk and "wait_until" in sdk


def test_the_generated_references_say_what_the_code_has() -> None:
    pages = reference_pages()
    from executive.cli import COMMANDS

    cli = pages.command_line()  # type: ignore[attr-defined]
    assert all(f"## `dura {name}`" in cli for name in COMMANDS)
    assert "### `dura goal add`" in cli and "--wait" in cli
    description = pages.robot_description()  # type: ignore[attr-defined]
    for key in ("`domain`", "`standby`", "`max_restarts`", "`sensing`", "`domain_id`"):
        assert key in description, key
    assert "| `max_faults` | integer, at least 1 | `3` |" in description
    bus = pages.bus_api()  # type: ignore[attr-defined]
    assert "| `GOAL_ADD` | `executive/api/goal/add` | `GoalAdd` (expression," in bus
    changelog = pages.changelog()  # type: ignore[attr-defined]
    assert "## [0.2.0]" in changelog


def blocks(text: str) -> list[tuple[int, str, str | None, list[str]]]:
    """Each fenced block of a page: its line, language, title and lines."""
    lines, found, i = text.splitlines(), [], 0
    while i < len(lines):
        fence = FENCE.match(lines[i])
        if not fence:
            i += 1
            continue
        end = next(j for j in range(i + 1, len(lines)) if lines[j].startswith("```"))
        found.append((i + 1, fence.group(1), fence.group(2), lines[i + 1 : end]))
        i = end + 1
    return found


def argv_of(words: list[str]) -> list[str]:
    if words[0] == "dura":
        return [sys.executable, "-m", "executive.cli", *words[1:]]
    if words[0] == "pytest":
        return [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", *words[1:]]
    raise AssertionError(f"the tutorial runs only dura and pytest, not {words[0]}")


def session(body: list[str]) -> list[tuple[str, list[str]]]:
    commands: list[tuple[str, list[str]]] = []
    for line in body:
        if line.startswith("$ "):
            commands.append((line[2:], []))
        elif commands:
            commands[-1][1].append(line)
    return commands


@pytest.mark.slow
def test_the_tutorial_runs_as_written(tmp_path: Path) -> None:
    text = TUTORIAL.read_text(encoding="utf-8")
    changing_from = text[: text.index(CHANGES_FROM)].count("\n") + 1
    cwd, made = tmp_path, set()
    env = {**os.environ, "DURA_TIME_SCALE": "10", "COLUMNS": "200"}
    env.pop("PYTEST_ADDOPTS", None)  # the options of this suite's run are not the reader's
    for line, language, title, body in blocks(text):
        where = f"{TUTORIAL.name}:{line}"
        if title is not None:
            path = cwd / title
            written = "\n".join(body) + "\n"
            if line < changing_from and path.exists():
                assert path.read_text() == written, f"{where}: {title} is not as dura new makes it"
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(written)
            made.add(title)
            continue
        if language != "console":
            continue
        background: list[subprocess.Popen[str]] = []
        try:
            for command, shown in session(body):
                words = shlex.split(command)
                if words[0] == "cd":
                    cwd = cwd / words[1]
                    continue
                if words[-1] == "&":
                    argv = argv_of(words[:-1])
                    if words[1] == "run":
                        argv += ["--endpoint", free_endpoint()]
                    job = subprocess.Popen(argv, cwd=cwd, env=env, stdout=subprocess.PIPE,
                                           stderr=subprocess.STDOUT, text=True)  # fmt: skip
                    background.append(job)
                    assert job.stdout is not None
                    first = job.stdout.readline().rstrip("\n")
                    assert matches([first], shown), f"{where}: {command}\n{first}"
                    continue
                done = subprocess.run(argv_of(words), cwd=cwd, env=env, capture_output=True,
                                      text=True, timeout=300, check=False)  # fmt: skip
                printed = (done.stdout or done.stderr).splitlines()
                assert done.returncode == 0, f"{where}: {command}\n{done.stdout}{done.stderr}"
                assert matches(printed, shown), f"{where}: {command} printed\n{done.stdout}"
        finally:
            for job in background:
                job.send_signal(signal.SIGINT)
                job.communicate(timeout=60)
    assert {"domain.pddl", "robot.yaml", "components/charge.py"} <= made
