"""The requests an editor makes about a place in a file, answered from a project's names:
hover, definition, references, completion, outline, formatting and quick fixes."""

from __future__ import annotations

from typing import TYPE_CHECKING

from lsprotocol import types
from pygls.lsp.server import LanguageServer

from executive.lsp.completion import complete
from executive.lsp.diagnostics import fix_range
from executive.lsp.formatting import format_pddl
from executive.lsp.names import Occurrence
from executive.lsp.navigation import Names

if TYPE_CHECKING:
    from executive.lsp.server import Session

_SYMBOL_KINDS = {
    "domain": types.SymbolKind.Namespace,
    "problem": types.SymbolKind.Namespace,
    "type": types.SymbolKind.Class,
    "predicate": types.SymbolKind.Function,
    "function": types.SymbolKind.Function,
    "action": types.SymbolKind.Method,
    "object": types.SymbolKind.Constant,
    "component": types.SymbolKind.Module,
}


def _range(session: Session, names: Names, o: Occurrence) -> types.Range:
    lines = session.lines(names.texts[o.path])
    return types.Range(
        types.Position(*lines.position(o.start)), types.Position(*lines.position(o.end))
    )


def _location(session: Session, names: Names, o: Occurrence) -> types.Location:
    from executive.lsp.server import uri_of

    return types.Location(uri_of(o.path), _range(session, names, o))


def register(server: LanguageServer, session: Session) -> None:
    """Register each request's handler."""
    from executive.lsp.server import path_of

    def at(
        params: types.HoverParams | types.DefinitionParams | types.ReferenceParams,
    ) -> tuple[Names, Occurrence | None]:
        path = path_of(params.text_document.uri)
        if path is None:
            return Names({}, ()), None
        names = session.names(path)
        lines = session.lines(names.texts.get(path, ""))
        offset = lines.offset(params.position.line, params.position.character)
        return names, names.at(path, offset)

    @server.feature(types.TEXT_DOCUMENT_HOVER)
    def hover(ls: LanguageServer, params: types.HoverParams) -> types.Hover | None:
        names, name = at(params)
        if name is None:
            return None
        return types.Hover(
            types.MarkupContent(types.MarkupKind.Markdown, names.hover(name)),
            _range(session, names, name),
        )

    @server.feature(types.TEXT_DOCUMENT_DEFINITION)
    def definition(ls: LanguageServer, params: types.DefinitionParams) -> list[types.Location]:
        names, name = at(params)
        return (
            [] if name is None else [_location(session, names, d) for d in names.definitions(name)]
        )

    @server.feature(types.TEXT_DOCUMENT_REFERENCES)
    def references(ls: LanguageServer, params: types.ReferenceParams) -> list[types.Location]:
        names, name = at(params)
        if name is None:
            return []
        found = names.references(name, params.context.include_declaration)
        return [_location(session, names, o) for o in found]

    @server.feature(
        types.TEXT_DOCUMENT_COMPLETION,
        types.CompletionOptions(trigger_characters=["(", "?", ":", " ", "-", "["]),
    )
    def completion(ls: LanguageServer, params: types.CompletionParams) -> types.CompletionList:
        path = path_of(params.text_document.uri)
        if path is None:
            return types.CompletionList(False, [])
        names = session.names(path)
        lines = session.lines(names.texts.get(path, ""))
        offset = lines.offset(params.position.line, params.position.character)
        return types.CompletionList(False, complete(names, path, offset))

    @server.feature(types.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
    def symbols(
        ls: LanguageServer, params: types.DocumentSymbolParams
    ) -> list[types.DocumentSymbol]:
        path = path_of(params.text_document.uri)
        if path is None:
            return []
        names = Names.of({path: session.text(path)}, None)
        return [
            types.DocumentSymbol(
                name=o.name,
                kind=_SYMBOL_KINDS.get(o.kind, types.SymbolKind.Variable),
                range=_range(session, names, o),
                selection_range=_range(session, names, o),
                detail=o.detail or o.kind,
            )
            for o in names.occurrences
            if o.kind in _SYMBOL_KINDS and (o.declared or o.kind == "action")  # tasks too
        ]

    @server.feature(types.TEXT_DOCUMENT_FORMATTING)
    def formatting(
        ls: LanguageServer, params: types.DocumentFormattingParams
    ) -> list[types.TextEdit]:
        path = path_of(params.text_document.uri)
        if path is None or path.suffix.lower() != ".pddl":
            return []
        text = session.text(path)
        formatted = format_pddl(text)
        if formatted == text:
            return []
        end = session.lines(text).position(len(text))
        return [types.TextEdit(types.Range(types.Position(0, 0), types.Position(*end)), formatted)]

    @server.feature(
        types.TEXT_DOCUMENT_CODE_ACTION,
        types.CodeActionOptions(code_action_kinds=[types.CodeActionKind.QuickFix]),
    )
    def code_actions(ls: LanguageServer, params: types.CodeActionParams) -> list[types.CodeAction]:
        path = path_of(params.text_document.uri)
        lines = session.lines(session.text(path) if path is not None else "")
        found = []
        for d in params.context.diagnostics:
            data = d.data if isinstance(d.data, dict) else {}
            replacement = data.get("replacement")
            if d.source != "dura" or not isinstance(replacement, str):
                continue
            edit = types.TextEdit(fix_range(d, lines), replacement)
            found.append(
                types.CodeAction(
                    title=f"Change to '{replacement}'",
                    kind=types.CodeActionKind.QuickFix,
                    diagnostics=[d],
                    is_preferred=True,
                    edit=types.WorkspaceEdit(changes={params.text_document.uri: [edit]}),
                )
            )
        return found
