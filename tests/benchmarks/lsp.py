"""Benchmark of ``dura lsp``: diagnostics after a change and completion, beside ``dura
validate`` and ``dura domain check`` of the same files.

    python -m tests.benchmarks.lsp [--runs N]

Starts ``dura lsp`` (a real process, spoken to over stdio by pygls' client), opens the
use case's robot description, domain and problem, and measures, round-robin so that
each sees the same machine:

- a change to the robot description (a component's rating) until the diagnostics of the
  robot description and the domain arrive;
- a change to the domain (a comment that is new each time, so that it is parsed again)
  until the same diagnostics arrive;
- completion in the domain (after ``(``) and in the robot description (a ``requires``
  list): the request's round trip;
- ``dura validate`` of the robot description and ``dura domain check`` of its domain and
  problem, as processes (the baseline: what a user ran before, wall time).

The server checks at once (no debounce), so the diagnostics' figure is the check itself.
Issue 32's goals: diagnostics 150 ms after a change, completion 50 ms.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

from lsprotocol import types
from pygls.lsp.client import LanguageClient

from tests.conftest import ROOT

ROBOT = ROOT / "examples" / "usecase" / "robot.yaml"
DOMAIN = ROOT / "domains" / "usecase" / "domain.pddl"
PROBLEM = ROOT / "examples" / "usecase" / "problem.pddl"
GOALS_MS = {"diagnostics": 150.0, "completion": 50.0}


class Client:
    """A pygls client of ``dura lsp`` that notes when each file's diagnostics arrive."""

    def __init__(self) -> None:
        self.lsp = LanguageClient("dura-benchmark", "1")
        self.arrived: dict[str, asyncio.Event] = {}
        self.version: dict[str, int | None] = {}  # the document version last diagnosed

        @self.lsp.feature(types.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
        def published(params: types.PublishDiagnosticsParams) -> None:
            self.version[params.uri] = params.version
            self.arrived.setdefault(params.uri, asyncio.Event()).set()

    def expect(self, *paths: Path) -> list[asyncio.Event]:
        events = []
        for path in paths:
            event = asyncio.Event()
            self.arrived[path.as_uri()] = event
            events.append(event)
        return events

    def open(self, path: Path) -> None:
        self.lsp.text_document_did_open(
            types.DidOpenTextDocumentParams(
                types.TextDocumentItem(
                    uri=path.as_uri(), language_id="text", version=1, text=path.read_text()
                )
            )
        )

    def change(self, path: Path, text: str, version: int) -> None:
        self.lsp.text_document_did_change(
            types.DidChangeTextDocumentParams(
                types.VersionedTextDocumentIdentifier(version=version, uri=path.as_uri()),
                [types.TextDocumentContentChangeWholeDocument(text)],
            )
        )


async def _diagnosed(client: Client, path: Path, text: str, version: int) -> float:
    """Until the diagnostics of the changed text (its version) and of the other file came."""
    began = time.perf_counter()
    client.change(path, text, version)
    while True:
        events = client.expect(ROBOT, DOMAIN)
        await asyncio.wait_for(asyncio.gather(*(e.wait() for e in events)), 60)
        if client.version.get(path.as_uri()) == version:
            return (time.perf_counter() - began) * 1000


async def _completed(client: Client, path: Path, text: str, marker: str, inside: int) -> float:
    offset = text.index(marker) + inside
    line = text.count("\n", 0, offset)
    column = offset - (text.rfind("\n", 0, offset) + 1)
    began = time.perf_counter()
    found = await client.lsp.text_document_completion_async(
        types.CompletionParams(
            text_document=types.TextDocumentIdentifier(path.as_uri()),
            position=types.Position(line, column),
        )
    )
    took = (time.perf_counter() - began) * 1000
    items = found.items if isinstance(found, types.CompletionList) else found
    if not items:
        raise SystemExit(f"no completion at {marker!r} of {path.name}")
    return took


def _process_ms(argv: list[str]) -> float:
    began = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, check=False, cwd=ROOT)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed:\n{done.stderr.decode(errors='replace')}")
    return (time.perf_counter() - began) * 1000


async def measure(runs: int) -> dict[str, list[float]]:
    dura = [sys.executable, "-m", "executive.cli"]
    client = Client()
    await client.lsp.start_io(*dura, "lsp")
    await client.lsp.initialize_async(
        types.InitializeParams(
            capabilities=types.ClientCapabilities(),
            workspace_folders=[types.WorkspaceFolder(ROOT.as_uri(), "dura")],
        )
    )
    client.lsp.initialized(types.InitializedParams())
    first = client.expect(ROBOT, DOMAIN)
    for path in (ROBOT, DOMAIN, PROBLEM):
        client.open(path)
    await asyncio.wait_for(asyncio.gather(*(e.wait() for e in first)), 120)
    robot, domain = ROBOT.read_text(), DOMAIN.read_text()
    samples: dict[str, list[float]] = {
        "diagnostics after a robot.yaml change": [],
        "diagnostics after a domain change": [],
        "completion in the domain": [],
        "completion in robot.yaml": [],
        "dura validate (process)": [],
        "dura domain check (process)": [],
    }
    version = 1
    for run in range(runs):
        version += 1
        rating = "rating: 11" if run % 2 == 0 else "rating: 10"
        changed = robot.replace("rating: 10", rating, 1)
        samples["diagnostics after a robot.yaml change"].append(
            await _diagnosed(client, ROBOT, changed, version)
        )
        samples["diagnostics after a domain change"].append(
            await _diagnosed(client, DOMAIN, domain + f"; edit {run}\n", version)
        )
        samples["completion in the domain"].append(
            await _completed(client, DOMAIN, domain, "(over all (connected", len("(over all ("))
        )
        samples["completion in robot.yaml"].append(
            await _completed(client, ROBOT, changed, "requires: [obstacle_scan", len("requires: ["))
        )
        samples["dura validate (process)"].append(_process_ms([*dura, "validate", str(ROBOT)]))
        samples["dura domain check (process)"].append(
            _process_ms([*dura, "domain", "check", str(DOMAIN), str(PROBLEM)])
        )
    await client.lsp.shutdown_async(None)
    client.lsp.exit(None)
    await client.lsp.stop()
    return samples


def report(samples: dict[str, list[float]]) -> list[str]:
    lines = [f"{'measure':<40} {'runs':>4} {'median ms':>10} {'p90 ms':>8} {'goal ms':>8}"]
    for name, values in samples.items():
        ordered = sorted(values)
        p90 = ordered[min(len(ordered) - 1, int(len(ordered) * 0.9))]
        goal = next((g for k, g in GOALS_MS.items() if name.startswith(k)), None)
        lines.append(
            f"{name:<40} {len(values):>4} {statistics.median(values):>10.1f} {p90:>8.1f} "
            f"{'' if goal is None else f'{goal:.0f}':>8}"
        )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=10)
    args = parser.parse_args()
    samples = asyncio.run(measure(args.runs))
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    for line in report(samples):
        print(line)


if __name__ == "__main__":
    main()
