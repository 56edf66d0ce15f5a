"""``dura lsp``: the language server, wired to pygls.

This module only connects the protocol to dura: the open documents and the projects
they belong to (:class:`Session`), the checks (at once when none runs; the changes made
during one coalesced into one more after it), and one handler per feature,
each a call into the module that knows the answer.
"""

from __future__ import annotations

import asyncio
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from lsprotocol import types
from pygls.lsp.server import LanguageServer
from pygls.uris import from_fs_path, to_fs_path

from executive.lsp import features
from executive.lsp.checks import check
from executive.lsp.diagnostics import diagnostic
from executive.lsp.navigation import Names
from executive.lsp.pddl_syntax import Lines
from executive.lsp.project import (
    Project,
    domain_name,
    find_robots,
    is_robot_text,
    problem_domain,
    projects_of,
    robot_project,
)
from knowledge.finding import Finding
from knowledge.sources import Memo, read_text


def path_of(uri: str) -> Path | None:
    """The file of a ``file:`` URI, resolved; ``None`` for another scheme."""
    path = to_fs_path(uri)
    return Path(path).resolve() if path and uri.startswith("file:") else None


def uri_of(path: Path) -> str:
    return from_fs_path(str(path)) or path.as_uri()


class Session:
    """The open documents, the robot descriptions of the workspace, and the checks that
    are due; every method runs in the server's event loop (its one owner)."""

    def __init__(self, server: LanguageServer) -> None:
        self.server = server
        self.robots: dict[Path, Project] = {}
        self.due: dict[Project, asyncio.Handle] = {}
        self.running: set[Project] = set()  # being checked
        self.again: set[Project] = set()  # changed while being checked
        self.checked: dict[Path | Project, frozenset[Path]] = {}  # by robot, or project
        self.memo = Memo()  # written by the checker thread only
        self.checker = ThreadPoolExecutor(
            1, thread_name_prefix="dura-lsp-check"
        )  # UP is not thread-safe

    def texts(self) -> dict[Path, str]:
        """The open documents' texts, by file."""
        found = {}
        for uri, document in self.server.workspace.text_documents.items():
            path = path_of(uri)
            if path is not None:
                found[path] = document.source
        return found

    def versions(self) -> dict[Path, int | None]:
        """The open documents' versions, by file."""
        found = {}
        for uri, document in self.server.workspace.text_documents.items():
            path = path_of(uri)
            if path is not None:
                found[path] = document.version
        return found

    def text(self, path: Path) -> str:
        """A file's text: its open document's, else the file's, else empty."""
        texts = self.texts()
        if path in texts:
            return texts[path]
        try:
            return read_text(path)
        except (OSError, UnicodeDecodeError):
            return ""

    def scan(self, folders: list[Path]) -> None:
        for robot in find_robots(folders):
            self.robots[robot] = robot_project(robot, self.text(robot))

    def changed(self, path: Path) -> None:
        """A document opened, changed or saved: check every project it belongs to."""
        if path.suffix in (".yaml", ".yml"):
            text = self.text(path)
            if is_robot_text(text):
                project = robot_project(path, text)
                if project.domain is not None or path not in self.robots:
                    self.robots[path] = project  # else half-typed: it keeps its files
            else:
                self.robots.pop(path, None)
        for project in projects_of(path, self.robots, self.texts()):
            self.schedule(project)

    def schedule(self, project: Project) -> None:
        """Check a project at once, or after the check under way: however fast the user
        types, one check runs at a time and the last text is always checked."""
        if project in self.running:
            self.again.add(project)
            return
        previous = self.due.pop(project, None)
        if previous is not None:
            previous.cancel()
        loop = asyncio.get_running_loop()
        self.due[project] = loop.call_soon(lambda: loop.create_task(self.run_checks(project)))

    async def run_checks(self, project: Project) -> None:
        """Check a project, once at a time: changes made meanwhile are checked after."""
        self.due.pop(project, None)
        if project in self.running:
            self.again.add(project)
            return
        self.running.add(project)
        loop = asyncio.get_running_loop()
        try:
            while True:
                self.again.discard(project)
                texts, versions = self.texts(), self.versions()
                try:
                    by_file = await loop.run_in_executor(
                        self.checker, check, project, texts, self.memo
                    )
                except Exception as e:  # a check that breaks must not take the server with it
                    message = f"dura: checking failed: {e!r}"
                    self.server.window_log_message(
                        types.LogMessageParams(types.MessageType.Error, message)
                    )
                    by_file = {}
                for path, findings in by_file.items():  # placed in the texts checked
                    self.publish(path, findings, texts.get(path), versions.get(path))
                if by_file:
                    self.forget(project, frozenset(by_file))
                if project not in self.again:
                    return
        finally:
            self.running.discard(project)

    def forget(self, project: Project, files: frozenset[Path]) -> None:
        """Clear the diagnostics of the files the project's last check covered and this
        one did not (a robot's ``domain:`` edited), unless another project checks them;
        such a file still open is checked on its own."""
        owner = project.robot or project
        before = self.checked.get(owner, frozenset())
        self.checked[owner] = files
        if project.robot is not None:  # what a robot checks is no longer checked alone
            for alone in [o for o, f in self.checked.items() if isinstance(o, Project)]:
                if self.checked[alone] & files:
                    del self.checked[alone]
        covered = frozenset().union(*self.checked.values())
        open_files = self.texts()
        for path in before - covered:
            self.publish(path, [])
            if path in open_files:
                self.changed(path)

    def names(self, path: Path) -> Names:
        """The names of the files checked with ``path`` (and of ``path``), and of the open
        problems of their domain."""
        texts = self.texts()
        projects = projects_of(path, self.robots, texts)
        files = dict.fromkeys([path, *(f for p in projects for f in p.files)])
        domains = {domain_name(self.text(p.domain)) for p in projects if p.domain is not None}
        for other, text in texts.items():
            if other.suffix.lower() == ".pddl" and problem_domain(text) in domains - {None}:
                files[other] = None
        robot = next((p.robot for p in projects if p.robot is not None), None)
        return Names.of({f: self.text(f) for f in files}, robot)

    def lines(self, text: str) -> Lines:
        """A text's lines, their columns counted as the client and the server agreed."""
        return Lines(text, self.server.workspace.position_encoding or "utf-16")

    def publish(
        self,
        path: Path,
        findings: list[Finding],
        text: str | None = None,
        version: int | None = None,
    ) -> None:
        """Show a file's findings, placed in ``text`` (by default, the file's now), as
        found in the document's ``version`` (an editor drops those of an older one)."""
        lines = self.lines(self.text(path) if text is None else text)
        self.server.text_document_publish_diagnostics(
            types.PublishDiagnosticsParams(
                uri=uri_of(path),
                diagnostics=[diagnostic(f, lines) for f in findings],
                version=version,
            )
        )


def make_server(version: str) -> LanguageServer:
    """The language server with every feature registered."""
    server = LanguageServer(
        "dura", version, text_document_sync_kind=types.TextDocumentSyncKind.Incremental
    )
    session = Session(server)

    @server.feature(types.INITIALIZED)
    def initialized(ls: LanguageServer, params: types.InitializedParams) -> None:
        folders = [path_of(f.uri) for f in ls.workspace.folders.values()]
        session.scan([f for f in folders if f is not None])

    @server.feature(types.TEXT_DOCUMENT_DID_OPEN)
    def did_open(ls: LanguageServer, params: types.DidOpenTextDocumentParams) -> None:
        path = path_of(params.text_document.uri)
        if path is not None:
            session.changed(path)

    @server.feature(types.TEXT_DOCUMENT_DID_CHANGE)
    def did_change(ls: LanguageServer, params: types.DidChangeTextDocumentParams) -> None:
        path = path_of(params.text_document.uri)
        if path is not None:
            session.changed(path)

    @server.feature(types.TEXT_DOCUMENT_DID_SAVE)
    def did_save(ls: LanguageServer, params: types.DidSaveTextDocumentParams) -> None:
        path = path_of(params.text_document.uri)
        if path is not None:
            session.changed(path)

    @server.feature(types.TEXT_DOCUMENT_DID_CLOSE)
    def did_close(ls: LanguageServer, params: types.DidCloseTextDocumentParams) -> None:
        path = path_of(params.text_document.uri)
        if path is not None:  # its file on disk is what counts now
            session.changed(path)

    features.register(server, session)
    return server
