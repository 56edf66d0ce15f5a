"""Broken, half-typed and huge files: every part of the language server answers, none
raises. Prefixes of the repository's real files stand for what a user has typed so far."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lsprotocol import types
from pytest_lsp import LanguageClient

from executive.lsp.checks import check
from executive.lsp.completion import complete
from executive.lsp.diagnostics import diagnostic
from executive.lsp.formatting import format_pddl
from executive.lsp.navigation import Names
from executive.lsp.pddl_syntax import Lines
from executive.lsp.project import robot_project
from tests.conftest import ROOT
from tests.executive.lsp.conftest import change_file, diagnostics_until, open_file
from tests.executive.lsp.test_navigation import _doc

FILES = sorted(
    p.resolve()
    for folder in ("domains", "examples")
    for pattern in ("*.pddl", "*.yaml")
    for p in (ROOT / folder).rglob(pattern)
)
USECASE = ROOT / "examples" / "usecase"
PROJECT = robot_project(USECASE.resolve() / "robot.yaml", (USECASE / "robot.yaml").read_text())


def _every_answer(names: Names, path: Path) -> None:
    text = names.texts[path]
    for offset in sorted({0, len(text) // 2, len(text)}):
        complete(names, path, offset)
    for name in names.occurrences:
        names.hover(name)
        names.definitions(name)
        names.references(name)


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(FILES), st.floats(0, 1))
def test_a_prefix_of_a_real_file_is_read_completed_hovered_and_formatted(
    path: Path, fraction: float
) -> None:
    full = path.read_text()
    prefix = full[: int(len(full) * fraction)]
    texts = {p: p.read_text() for p in PROJECT.files}
    texts[path] = prefix
    _every_answer(Names.of(texts, PROJECT.robot), path)
    if path.suffix == ".pddl":
        once = format_pddl(prefix)
        assert format_pddl(once) == once


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from([p for p in PROJECT.files]), st.floats(0, 1))
def test_the_checks_of_a_project_with_a_half_typed_file_give_findings_not_errors(
    path: Path, fraction: float
) -> None:
    full = path.read_text()
    prefix = full[: int(len(full) * fraction)]
    by_file = check(PROJECT, {path: prefix})
    lines = Lines(prefix)
    for finding in by_file.get(path, []):
        diagnostic(finding, lines)  # a place in the text, whatever the line says


def test_a_huge_problem_is_read_completed_and_formatted() -> None:
    objects = " ".join(f"place{i}" for i in range(20_000))
    facts = "\n".join(f"    (connected place{i} place{i + 1})" for i in range(20_000))
    text = f"(define (problem huge) (:domain usecase)\n  (:objects {objects} - place)\n  (:init\n{facts})\n  (:goal (and)))\n"
    path = USECASE.resolve() / "huge.pddl"
    domain = PROJECT.domain
    assert domain is not None
    names = Names.of({path: text, domain: domain.read_text()}, None)
    labels = [i.label for i in complete(names, path, text.index("(connected place0") + 1)]
    assert "connected" in labels
    assert format_pddl(text) == text


@pytest.mark.slow
@pytest.mark.asyncio
async def test_the_server_answers_while_a_domain_is_typed_and_checks_the_whole_at_the_end(
    client: LanguageClient, usecase: Path
) -> None:
    domain = usecase / "domains" / "usecase" / "domain.pddl"
    robot = usecase / "examples" / "usecase" / "robot.yaml"
    text = domain.read_text()
    open_file(client, robot)
    open_file(client, domain, "")
    for version, end in enumerate(range(0, len(text), 37), start=2):
        change_file(client, domain, text[:end], version)
        at = types.Position(text[:end].count("\n"), 0)
        await client.text_document_hover_async(
            types.HoverParams(text_document=_doc(domain), position=at)
        )
        await client.text_document_completion_async(
            types.CompletionParams(text_document=_doc(domain), position=at)
        )
    half = await diagnostics_until(client, domain, lambda d: len(d) > 0)
    assert half  # a half-typed domain is an error, not a crash
    change_file(client, domain, text, version=10_000)
    assert await diagnostics_until(client, domain, lambda d: len(d) == 0) == []
    assert await diagnostics_until(client, robot, lambda d: len(d) == 0) == []
