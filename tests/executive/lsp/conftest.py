"""A real LSP client (pytest-lsp) talking to ``dura lsp`` in a process of its own, in a
copy of the use-case robot's files that each test may change."""

from __future__ import annotations

import asyncio
import shutil
import sys
from collections.abc import AsyncIterator, Callable
from pathlib import Path

import pytest
import pytest_lsp
from lsprotocol import types
from pytest_lsp import ClientServerConfig, LanguageClient, client_capabilities

from tests.conftest import ROOT

WAIT = 60.0  # seconds a test waits for the server: a loaded machine is slow, never wrong


@pytest.fixture
def usecase(tmp_path: Path) -> Path:
    """A copy of the use case: ``examples/usecase`` and its domain, in their places."""
    shutil.copytree(
        ROOT / "examples" / "usecase",
        tmp_path / "examples" / "usecase",
        ignore=shutil.ignore_patterns("*.png", "__pycache__"),
    )
    shutil.copytree(ROOT / "domains" / "usecase", tmp_path / "domains" / "usecase")
    return tmp_path


@pytest_lsp.fixture(
    config=ClientServerConfig(server_command=[sys.executable, "-m", "executive.cli", "lsp"]),
)
async def client(lsp_client: LanguageClient, usecase: Path) -> AsyncIterator[LanguageClient]:
    await lsp_client.initialize_session(
        types.InitializeParams(
            capabilities=client_capabilities("visual-studio-code"),
            workspace_folders=[types.WorkspaceFolder(usecase.as_uri(), "usecase")],
        )
    )
    yield lsp_client
    await lsp_client.shutdown_session()


def uri(path: Path) -> str:
    return path.resolve().as_uri()


def open_file(client: LanguageClient, path: Path, text: str | None = None) -> str:
    """Open a file in the client (with ``text`` instead of the file's, unsaved)."""
    language = "pddl" if path.suffix == ".pddl" else "yaml"
    content = path.read_text() if text is None else text
    client.text_document_did_open(
        types.DidOpenTextDocumentParams(
            types.TextDocumentItem(uri=uri(path), language_id=language, version=1, text=content)
        )
    )
    return uri(path)


def change_file(client: LanguageClient, path: Path, text: str, version: int = 2) -> None:
    """Replace an open document's whole text, unsaved."""
    client.text_document_did_change(
        types.DidChangeTextDocumentParams(
            types.VersionedTextDocumentIdentifier(version=version, uri=uri(path)),
            [types.TextDocumentContentChangeWholeDocument(text)],
        )
    )


async def diagnostics_until(
    client: LanguageClient, path: Path, wanted: Callable[[list[types.Diagnostic]], bool]
) -> list[types.Diagnostic]:
    """The diagnostics of a file once they are as ``wanted`` (or the last ones, after
    :data:`WAIT` seconds, for the test's assertion to show)."""

    async def arrive() -> list[types.Diagnostic]:
        while True:
            shown = client.diagnostics.get(uri(path))
            if shown is not None and wanted(shown):
                return list(shown)
            await client.wait_for_notification(types.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)

    try:
        return await asyncio.wait_for(arrive(), WAIT)
    except TimeoutError:
        return list(client.diagnostics.get(uri(path), []))
