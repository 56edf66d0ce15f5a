"""Positions in the units the client and the server agreed on: UTF-16 by default (an
emoji is two), UTF-8 or UTF-32 when the client offers them, on lines with accents and
an emoji before the name a feature is about."""

from __future__ import annotations

import sys
from collections.abc import AsyncIterator
from pathlib import Path

import attrs
import pytest
import pytest_lsp
from lsprotocol import types
from pytest_lsp import ClientServerConfig, LanguageClient, client_capabilities

from tests.executive.lsp.conftest import change_file, diagnostics_until, open_file, uri

pytestmark = [pytest.mark.slow, pytest.mark.asyncio]

CAM = (
    "  cam: {command: [python, -m, components.cam], params: {label: "
    '"caméra 📷"}, requires: [laser_scna], provides: [camera], publishes: [image]}\n'
)
PICTURE = '"caméra 📷"'  # 10 characters: 11 UTF-16 units, 14 UTF-8 bytes
EXTRA = {"utf-16": 1, "utf-8": 4, "utf-32": 0}  # the units it has more than characters


@pytest_lsp.fixture(
    config=ClientServerConfig(server_command=[sys.executable, "-m", "executive.cli", "lsp"]),
    params=[None, ["utf-8", "utf-16"], ["utf-32"]],
)
async def client(
    lsp_client: LanguageClient, usecase: Path, request: pytest.FixtureRequest
) -> AsyncIterator[LanguageClient]:
    """A client that offers no encoding (UTF-16 then), UTF-8 first or UTF-32."""
    capabilities = client_capabilities("visual-studio-code")
    assert capabilities.general is not None
    capabilities.general.position_encodings = request.param
    result = await lsp_client.initialize_session(
        types.InitializeParams(
            capabilities=capabilities,
            workspace_folders=[types.WorkspaceFolder(usecase.as_uri(), "usecase")],
        )
    )
    offered = request.param or ["utf-16"]
    assert result.capabilities.position_encoding == offered[0]
    yield lsp_client
    await lsp_client.shutdown_session()


def _encoding(client: LanguageClient) -> str:
    offered = client.capabilities.general and client.capabilities.general.position_encodings
    return offered[0] if offered else "utf-16"


def _with_camera_line(usecase: Path) -> tuple[Path, str, int]:
    """The use case's robot with ``cam`` on one line: a picture, then a typo."""
    robot = usecase / "examples" / "usecase" / "robot.yaml"
    text = robot.read_text()
    start = text.index("  cam:\n")
    text = text[:start] + CAM + text[text.index("\n\n", start) :]
    return robot, text, text.splitlines().index(CAM.rstrip("\n"))


async def test_a_mistake_after_an_emoji_is_shown_at_its_name_in_the_clients_units(
    client: LanguageClient, usecase: Path
) -> None:
    robot, text, line = _with_camera_line(usecase)
    open_file(client, robot, text)
    [shown] = await diagnostics_until(client, robot, lambda d: len(d) > 0)
    assert "'cam' requires unknown capability 'laser_scna'" in shown.message
    column = CAM.index("laser_scna") + EXTRA[_encoding(client)]
    assert shown.range == types.Range(
        types.Position(line, column), types.Position(line, column + len("laser_scna"))
    )
    # the quick fix; Neovim 0.7 sends the diagnostic back with byte columns: same fix
    columns = CAM.encode().index(b"laser_scna"), CAM.encode().index(b"laser_scna") + 10
    in_bytes = types.Range(types.Position(line, columns[0]), types.Position(line, columns[1]))
    for sent in (shown, attrs.evolve(shown, range=in_bytes)):
        actions = await client.text_document_code_action_async(
            types.CodeActionParams(
                text_document=types.TextDocumentIdentifier(uri(robot)),
                range=sent.range,
                context=types.CodeActionContext(diagnostics=[sent]),
            )
        )
        assert actions is not None
        [action] = actions
        assert isinstance(action, types.CodeAction) and action.edit and action.edit.changes
        [edit] = action.edit.changes[uri(robot)]
        assert edit.range == shown.range and edit.new_text == "laser_scan"


async def test_hover_references_and_completion_after_an_emoji_count_the_clients_units(
    client: LanguageClient, usecase: Path
) -> None:
    robot, text, line = _with_camera_line(usecase)
    open_file(client, robot, text)
    await diagnostics_until(client, robot, lambda d: True)
    extra = EXTRA[_encoding(client)]
    camera = CAM.index("[camera]") + 1
    hover = await client.text_document_hover_async(
        types.HoverParams(
            types.TextDocumentIdentifier(uri(robot)), types.Position(line, camera + extra + 3)
        )
    )
    assert hover is not None and isinstance(hover.contents, types.MarkupContent)
    assert hover.contents.value.startswith("**capability** `camera`")
    assert hover.range == types.Range(
        types.Position(line, camera + extra), types.Position(line, camera + extra + 6)
    )
    required = next(i for i, t in enumerate(text.splitlines()) if "requires: [camera]" in t)
    found = await client.text_document_references_async(
        types.ReferenceParams(
            text_document=types.TextDocumentIdentifier(uri(robot)),
            position=types.Position(required, text.splitlines()[required].index("camera")),
            context=types.ReferenceContext(include_declaration=True),
        )
    )
    assert found is not None
    assert types.Position(line, camera + extra) in [r.range.start for r in found]
    typing = CAM.replace("requires: [laser_scna]", "requires: [obst]")
    change_file(client, robot, text.replace(CAM, typing))
    cursor = typing.index("[obst]") + len("[obst")
    completion = await client.text_document_completion_async(
        types.CompletionParams(
            types.TextDocumentIdentifier(uri(robot)), types.Position(line, cursor + extra)
        )
    )
    assert isinstance(completion, types.CompletionList)
    assert "obstacle_scan" in [i.label for i in completion.items]


async def test_formatting_replaces_up_to_the_end_in_the_clients_units(
    client: LanguageClient, usecase: Path
) -> None:
    domain = usecase / "domains" / "usecase" / "domain.pddl"
    text = domain.read_text().replace("  (:types place)", "(:types place)") + "; fin 📷"
    open_file(client, domain, text)
    edits = await client.text_document_formatting_async(
        types.DocumentFormattingParams(
            types.TextDocumentIdentifier(uri(domain)),
            types.FormattingOptions(tab_size=2, insert_spaces=True),
        )
    )
    assert edits is not None
    [edit] = edits
    last = text.count("\n")
    end = len("; fin 📷") + (1 if _encoding(client) == "utf-16" else 0)
    end += 3 if _encoding(client) == "utf-8" else 0
    assert edit.range == types.Range(types.Position(0, 0), types.Position(last, end))
    assert "  (:types place)" in edit.new_text and edit.new_text.endswith("; fin 📷\n")
