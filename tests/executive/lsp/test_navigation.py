"""Hover, go to definition and find references across the domain, the problem and the
robot description, asked by a real LSP client of ``dura lsp``."""

from __future__ import annotations

from pathlib import Path

import pytest
from lsprotocol import types
from pytest_lsp import LanguageClient

from tests.executive.lsp.conftest import diagnostics_until, open_file, uri

pytestmark = [pytest.mark.slow, pytest.mark.asyncio]


def _position(text: str, marker: str, inside: int = 1) -> types.Position:
    """The place ``inside`` characters into the first ``marker`` of ``text``."""
    offset = text.index(marker) + inside
    line = text.count("\n", 0, offset)
    return types.Position(line, offset - (text.rfind("\n", 0, offset) + 1))


def _doc(path: Path) -> types.TextDocumentIdentifier:
    return types.TextDocumentIdentifier(uri(path))


async def _opened(client: LanguageClient, usecase: Path) -> tuple[Path, Path, Path]:
    robot = usecase / "examples" / "usecase" / "robot.yaml"
    domain = usecase / "domains" / "usecase" / "domain.pddl"
    problem = usecase / "examples" / "usecase" / "problem.pddl"
    for path in (robot, domain, problem):
        open_file(client, path)
    await diagnostics_until(client, robot, lambda d: True)
    return robot, domain, problem


async def test_hover_on_a_task_shows_the_action_its_duration_and_who_carries_it_out(
    client: LanguageClient, usecase: Path
) -> None:
    robot, _, _ = await _opened(client, usecase)
    text = robot.read_text()
    hover = await client.text_document_hover_async(
        types.HoverParams(
            text_document=_doc(robot), position=_position(text, "move_to:\n    behavior")
        )
    )
    assert hover is not None and isinstance(hover.contents, types.MarkupContent)
    shown = hover.contents.value
    assert "durative-action in domain.pddl:18" in shown
    assert "duration: `(= ?duration (travel_time ?from ?to))`" in shown
    assert (
        "condition: `(and (at start (robot_at ?from)) (over all (connected ?from ?to)))`" in shown
    )
    assert "effect: `(and (at start (not (robot_at ?from))) (at end (robot_at ?to)))`" in shown
    assert "task: behavior `move_to` with goal start=?from, target=?to" in shown
    assert "requires `obstacle_scan`: provided by lidar_filter, cam_to_lidar" in shown


async def test_hover_on_a_capability_shows_who_provides_and_requires_it(
    client: LanguageClient, usecase: Path
) -> None:
    robot, _, _ = await _opened(client, usecase)
    text = robot.read_text()
    hover = await client.text_document_hover_async(
        types.HoverParams(
            text_document=_doc(robot), position=_position(text, "obstacle_scan, base]")
        )
    )
    assert hover is not None and isinstance(hover.contents, types.MarkupContent)
    assert "provided by: lidar_filter, cam_to_lidar" in hover.contents.value
    assert "required by: move_to" in hover.contents.value


async def test_hover_on_a_predicate_in_the_problem_shows_its_declaration(
    client: LanguageClient, usecase: Path
) -> None:
    _, _, problem = await _opened(client, usecase)
    hover = await client.text_document_hover_async(
        types.HoverParams(
            text_document=_doc(problem),
            position=_position(problem.read_text(), "(connected dock", 2),
        )
    )
    assert hover is not None and isinstance(hover.contents, types.MarkupContent)
    assert "(connected ?from ?to - place)" in hover.contents.value
    assert "declared in domain.pddl:10" in hover.contents.value


async def test_definition_of_a_task_is_its_action_in_the_domain(
    client: LanguageClient, usecase: Path
) -> None:
    robot, domain, _ = await _opened(client, usecase)
    found = await client.text_document_definition_async(
        types.DefinitionParams(
            text_document=_doc(robot),
            position=_position(robot.read_text(), "take_picture:\n    behavior"),
        )
    )
    assert isinstance(found, list)
    domain_text = domain.read_text()
    assert [(f.uri, f.range.start) for f in found] == [
        (uri(domain), _position(domain_text, "take_picture\n", 0))
    ]


async def test_references_of_an_object_span_the_problem_and_the_integrity_goals(
    client: LanguageClient, usecase: Path
) -> None:
    _, _, problem = await _opened(client, usecase)
    integrity = usecase / "examples" / "usecase" / "integrity.yaml"
    text = problem.read_text()
    found = await client.text_document_references_async(
        types.ReferenceParams(
            text_document=_doc(problem),
            position=_position(text, "dock lab office - place", 0),
            context=types.ReferenceContext(include_declaration=True),
        )
    )
    assert found is not None
    in_problem = [f for f in found if f.uri == uri(problem)]
    assert len(in_problem) == 1 + text.split("(:objects", 1)[1].count("dock") - 1
    assert [f.uri for f in found if f.uri != uri(problem)] == [uri(integrity)]


async def test_references_of_a_predicate_reach_every_open_problem_of_its_domain(
    client: LanguageClient, usecase: Path
) -> None:
    _, domain, _ = await _opened(client, usecase)
    pictures = usecase / "examples" / "usecase" / "pictures.pddl"
    open_file(client, pictures)
    found = await client.text_document_references_async(
        types.ReferenceParams(
            text_document=_doc(domain),
            position=_position(domain.read_text(), "(picture_taken ?p - place)", 1),
            context=types.ReferenceContext(include_declaration=False),
        )
    )
    assert found is not None
    files = sorted({f.uri for f in found})
    assert files == sorted({uri(domain), uri(pictures)})  # the goal of pictures.pddl
    assert len([f for f in found if f.uri == uri(pictures)]) == pictures.read_text().count(
        "picture_taken"
    )
