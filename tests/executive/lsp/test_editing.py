"""Completion, the outline, formatting and quick fixes, asked by a real LSP client of
``dura lsp``."""

from __future__ import annotations

from pathlib import Path

import pytest
from lsprotocol import types
from pytest_lsp import LanguageClient

from tests.executive.lsp.conftest import change_file, diagnostics_until, open_file, uri
from tests.executive.lsp.test_navigation import _doc, _position

pytestmark = [pytest.mark.slow, pytest.mark.asyncio]


async def _labels(
    client: LanguageClient, path: Path, text: str, marker: str, inside: int
) -> list[str]:
    found = await client.text_document_completion_async(
        types.CompletionParams(text_document=_doc(path), position=_position(text, marker, inside))
    )
    items = found.items if isinstance(found, types.CompletionList) else found or []
    return [i.label for i in items]


async def test_completion_offers_predicates_after_a_parenthesis_and_types_after_a_dash(
    client: LanguageClient, usecase: Path
) -> None:
    domain = usecase / "domains" / "usecase" / "domain.pddl"
    text = domain.read_text().replace("(over all (connected ?from ?to))", "(over all (co))")
    open_file(client, domain, text)
    labels = await _labels(client, domain, text, "(over all (co", len("(over all (co"))
    assert {"connected", "robot_at", "travel_time", "and", "not"} <= set(labels)
    assert "place" not in labels
    labels = await _labels(client, domain, text, "?p - place)", len("?p - "))
    assert labels == ["place", "object"]
    labels = await _labels(client, domain, text, "(robot_at ?from))", len("(robot_at ?"))
    assert labels == ["?duration", "?from", "?to"]


async def test_completion_in_the_problem_offers_its_objects(
    client: LanguageClient, usecase: Path
) -> None:
    robot = usecase / "examples" / "usecase" / "robot.yaml"
    open_file(client, robot)
    problem = usecase / "examples" / "usecase" / "problem.pddl"
    text = problem.read_text().replace("(robot_at dock)", "(robot_at d)")
    open_file(client, problem, text)
    labels = await _labels(client, problem, text, "(robot_at d)", len("(robot_at d"))
    assert {"dock", "lab", "office"} <= set(labels)


async def test_completion_in_the_robot_description_offers_keys_and_names(
    client: LanguageClient, usecase: Path
) -> None:
    robot = usecase / "examples" / "usecase" / "robot.yaml"
    text = robot.read_text()
    open_file(client, robot)
    labels = await _labels(client, robot, text, "requires: [obstacle_scan", len("requires: ["))
    assert sorted(labels) == ["base", "camera", "laser_scan", "obstacle_scan"]
    labels = await _labels(client, robot, text, "    behavior: take_picture", len("    behavior: "))
    assert sorted(labels) == ["move_to", "take_picture"]
    labels = await _labels(client, robot, text, "    subscribes: [scan]", len("    subscribes: ["))
    assert {"scan", "scan_filtered", "image", "odom", "imu", "cmd_vel"} == set(labels)
    labels = await _labels(
        client, robot, text, "    rating: 10\n    max_faults: 3\n    params: {rate: 10.0}", 4
    )
    assert {"provides", "requires", "command", "max_faults"} <= set(labels)
    assert "behavior" not in labels
    labels = await _labels(client, robot, text, "  timeout: 30", 2)
    assert {"engine", "timeout"} <= set(labels)
    more = text.replace(
        "    subscribes: [scan]", "    subscribes: [scan]\n    may_subscribe: []", 1
    )
    change_file(client, robot, more)
    labels = await _labels(
        client, robot, more, "    may_subscribe: []", len("    may_subscribe: [")
    )
    assert {"scan", "scan_filtered", "image", "odom"} <= set(labels)
    change_file(client, robot, text)
    typed = text.replace("  take_picture:\n    behavior", "  mo\n  take_picture:\n    behavior")
    change_file(client, robot, typed)
    labels = await _labels(client, robot, typed, "  mo\n", 4)
    assert labels == ["move_to", "take_picture"]


async def test_the_outline_lists_the_domains_declarations(
    client: LanguageClient, usecase: Path
) -> None:
    domain = usecase / "domains" / "usecase" / "domain.pddl"
    open_file(client, domain)
    symbols = await client.text_document_document_symbol_async(
        types.DocumentSymbolParams(text_document=_doc(domain))
    )
    assert symbols is not None
    assert [(s.name, s.detail) for s in symbols if isinstance(s, types.DocumentSymbol)] == [
        ("usecase", "domain"),
        ("place", "type place - object"),
        ("robot_at", "(robot_at ?p - place)"),
        ("connected", "(connected ?from ?to - place)"),
        ("picture_taken", "(picture_taken ?p - place)"),
        ("photographable", "(photographable ?p - place)"),
        ("travel_time", "(travel_time ?from ?to - place)"),
        ("move_to", "durative-action"),
        ("take_picture", "durative-action"),
    ]


def _apply(text: str, edits: list[types.TextEdit]) -> str:
    lines = text.splitlines(keepends=True)
    (edit,) = edits
    start = sum(len(line) for line in lines[: edit.range.start.line]) + edit.range.start.character
    end = sum(len(line) for line in lines[: edit.range.end.line]) + edit.range.end.character
    return text[:start] + edit.new_text + text[end:]


async def test_formatting_indents_canonically_keeps_comments_and_is_stable(
    client: LanguageClient, usecase: Path
) -> None:
    domain = usecase / "domains" / "usecase" / "domain.pddl"
    canonical = domain.read_text()
    messy = "\n".join(line.strip() + "   " for line in canonical.splitlines()).replace(
        "(over all", "(  over   all"
    )
    open_file(client, domain, messy)
    options = types.FormattingOptions(tab_size=2, insert_spaces=True)
    edits = await client.text_document_formatting_async(
        types.DocumentFormattingParams(text_document=_doc(domain), options=options)
    )
    assert edits
    formatted = _apply(messy, edits)
    assert formatted == canonical
    change_file(client, domain, formatted)
    again = await client.text_document_formatting_async(
        types.DocumentFormattingParams(text_document=_doc(domain), options=options)
    )
    assert not again  # nothing to change


async def test_a_did_you_mean_has_a_quick_fix_that_writes_the_name(
    client: LanguageClient, usecase: Path
) -> None:
    robot = usecase / "examples" / "usecase" / "robot.yaml"
    typo = robot.read_text().replace(
        "requires: [obstacle_scan, base]", "requires: [obstacle_scna, base]"
    )
    open_file(client, robot, typo)
    shown = await diagnostics_until(client, robot, lambda d: len(d) > 0)
    actions = await client.text_document_code_action_async(
        types.CodeActionParams(
            text_document=_doc(robot),
            range=shown[0].range,
            context=types.CodeActionContext(diagnostics=list(shown)),
        )
    )
    assert actions is not None
    (action,) = actions
    assert isinstance(action, types.CodeAction)
    assert action.title == "Change to 'obstacle_scan'"
    assert action.edit is not None and action.edit.changes is not None
    fixed = _apply(typo, list(action.edit.changes[uri(robot)]))
    assert fixed == robot.read_text()


async def test_the_outline_of_a_robot_description_lists_its_components_and_tasks(
    client: LanguageClient, usecase: Path
) -> None:
    robot = usecase / "examples" / "usecase" / "robot.yaml"
    open_file(client, robot)
    symbols = await client.text_document_document_symbol_async(
        types.DocumentSymbolParams(text_document=_doc(robot))
    )
    assert symbols is not None
    assert [(s.name, s.detail) for s in symbols if isinstance(s, types.DocumentSymbol)] == [
        ("lidar", "functionality"),
        ("lidar_filter", "functionality"),
        ("robot_base", "functionality"),
        ("cam", "functionality"),
        ("cam_to_lidar", "functionality"),
        ("move_to", "behavior"),
        ("take_picture", "behavior"),
        ("move_to", "action"),
        ("take_picture", "action"),
    ]


async def test_completion_of_an_observers_topic_offers_the_robots_topics(
    client: LanguageClient, usecase: Path
) -> None:
    robot = usecase / "examples" / "usecase" / "robot.yaml"
    text = robot.read_text()
    open_file(client, robot)
    labels = await _labels(client, robot, text, "          - name: scan", len("          - name: "))
    assert {"scan", "scan_filtered", "image"} <= set(labels)
