"""``dura lsp`` is a command like the others: listed, and loading pygls only when run."""

from __future__ import annotations

import subprocess
import sys

from tests.conftest import ROOT


def test_the_command_line_loads_no_language_server_until_dura_lsp_runs() -> None:
    code = (
        "import sys, executive.cli, executive.cli.lsp\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('pygls', 'lsprotocol')"
        " or m.startswith('executive.lsp')))"
    )
    loaded = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    ).stdout.strip()
    assert loaded == "[]"


def test_dura_lsp_is_in_the_help() -> None:
    shown = subprocess.run(
        [sys.executable, "-m", "executive.cli", "--help"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=True,
    ).stdout
    assert "lsp" in shown and "language server" in shown


def test_a_malformed_message_is_one_line_on_stderr_and_the_server_ends_with_its_input() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "executive.cli", "lsp"],
        input=b"Content-Length: 5\r\n\r\nhello",
        capture_output=True,
        cwd=ROOT,
        timeout=60,
        check=False,
    )
    assert done.returncode == 0
    assert done.stderr.decode().splitlines() == [
        "dura lsp: Unable to handle message: Expecting value: line 1 column 1 (char 0)"
    ]
