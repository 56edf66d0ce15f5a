"""The one adapter between dura and clingo: programs in, Python values out.

Every use of ``clingo.Control`` in dura goes through :class:`Asp`. It loads programs
from files or text under a source name, adds facts and externals, grounds parts and
solves (optionally under a time bound and with assumptions). Models come back as
:class:`Answer` objects holding plain Python values, and every clingo failure (a
syntax error in a user's ``.lp`` file, an unsafe variable, a grounding error) becomes
an :class:`~knowledge.errors.AspError` whose message starts with ``file:line:col:``.
A program file the editor has unsaved (:func:`~knowledge.sources.unsaved`) is read from
its buffer, so ``dura lsp`` checks the text in the editor.

A theory (e.g. clingo-dl's difference constraints) plugs in through ``theory=``: its
programs are rewritten by the theory as they are read, and it is prepared after each
grounding.
"""

from __future__ import annotations

import math
import os
import re
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import clingo
from clingo import ast
from clingo.theory import Theory

from knowledge.errors import AspError
from knowledge.sources import unsaved_text

# Python value of a symbol: numbers, strings (constants and quoted strings alike),
# tuples for tuples, and (name, args) for functions with arguments.
Value = int | str | tuple["Value", ...]

_LOCATION = re.compile(
    r"^(?P<src>.*?):(?P<line>\d+):(?P<col>\d+)(?:-\d+(?::\d+)?)?: (?P<kind>\w+): (?P<msg>.*)$"
)
SHOWN_CACHE = 100_000  # converted shown atoms kept per control
PARSED_FILES = 64  # program files kept parsed
# (path, mtime, size), or (path, text) of an editor's buffer -> statements
PARSED: dict[tuple[str, int, int] | tuple[str, str], list[ast.AST]] = {}


def to_python(symbol: clingo.Symbol) -> Value:
    """The Python value of a symbol (``f(a,1)`` becomes ``("f", "a", 1)``)."""
    kind = symbol.type
    if kind is clingo.SymbolType.Number:
        return symbol.number
    if kind is clingo.SymbolType.String:
        return symbol.string
    if kind is clingo.SymbolType.Function:
        args = tuple(to_python(a) for a in symbol.arguments)
        if not symbol.name:
            return args
        return (symbol.name, *args) if args else symbol.name
    return str(symbol)  # #inf and #sup


def to_symbol(value: object) -> clingo.Symbol:
    """A symbol for a Python value: ints stay numbers, strings become quoted strings."""
    if isinstance(value, bool):
        raise TypeError("booleans have no ASP form")
    if isinstance(value, int):
        return clingo.Number(value)
    if isinstance(value, str):
        return clingo.String(value)
    if isinstance(value, tuple):
        return clingo.Tuple_([to_symbol(v) for v in value])
    raise TypeError(f"no ASP form for {type(value).__name__}")


def atom(name: str, *args: object) -> clingo.Symbol:
    """The symbol ``name(args...)`` with the arguments converted by :func:`to_symbol`."""
    return clingo.Function(name, [to_symbol(a) for a in args])


_QUOTED_OR_COMMENT = re.compile(r'"(?:\\.|[^"\\\n])*"|%\*.*?\*%|%[^\n]*', re.DOTALL)
_FOREIGN = re.compile(r"[^\x00-\x7f]")


def _refuse_foreign(source: str, text: str) -> None:
    """Refuse a character beyond ASCII outside strings and comments, at its line and
    column: clingo's lexer would report it with its bytes cut, which its Python logger
    cannot decode, and the process would abort."""
    if text.isascii():
        return
    code = _QUOTED_OR_COMMENT.sub(lambda m: re.sub(r"[^\n]", " ", m.group()), text)
    found = _FOREIGN.search(code)
    if found is not None:
        line = code.count("\n", 0, found.start()) + 1
        column = found.start() - (code.rfind("\n", 0, found.start()) + 1) + 1
        character = text[found.start()]
        raise AspError(f"{source}:{line}:{column}: unexpected character '{character}'")


def facts(atoms: Iterable[clingo.Symbol]) -> str:
    """Program text with one fact per atom (symbols print as valid, escaped ASP)."""
    return "".join(f"{a}.\n" for a in atoms)


class _Alarm:
    """The time bound of one solve call: interrupts it, or (with a grace period and no
    model yet) lets the first model end it."""

    def __init__(self, control: clingo.Control, timeout: float, grace: float) -> None:
        self.control = control
        self.timeout = timeout
        self.grace = grace
        self.answered = False  # a model came
        self.late = False  # past the bound without a model: the next model ends the search
        self.fired = False  # the control was interrupted

    def ring(self) -> float | None:
        """Called at the bound; returns the seconds more to wait, or None when done."""
        if self.grace > 0 and not self.late and not self.answered:
            self.late = True
            return self.grace
        self.fired = True
        self.control.interrupt()
        return None


class _Watchdog:
    """One thread that rings the alarms of every solve call with a time bound.

    Arming, disarming and ringing hold one lock, so once :meth:`disarm` returns the
    alarm never rings. An alarm that rang just after its search ended left an
    interrupt for the control's next call: :meth:`Asp.solve` takes it up.
    """

    def __init__(self) -> None:
        self._reset()
        os.register_at_fork(after_in_child=self._reset)  # the thread is not forked

    def _reset(self) -> None:
        self._lock = threading.Condition()
        self._alarms: dict[_Alarm, float] = {}  # alarm -> monotonic deadline
        self._thread: threading.Thread | None = None
        self._until = math.inf  # when the thread wakes up next

    def arm(self, alarm: _Alarm) -> None:
        """Ring the alarm when its time bound has passed from now."""
        deadline = time.monotonic() + alarm.timeout
        with self._lock:
            self._alarms[alarm] = deadline
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="asp-watchdog", daemon=True)
                self._thread.start()
            elif deadline < self._until:  # else the thread finds it when it wakes anyway
                self._lock.notify()

    def disarm(self, alarm: _Alarm) -> None:
        with self._lock:
            self._alarms.pop(alarm, None)

    def _run(self) -> None:
        with self._lock:
            while True:
                now = time.monotonic()
                for alarm, deadline in list(self._alarms.items()):
                    if deadline <= now:
                        later = alarm.ring()
                        if later is None:
                            del self._alarms[alarm]
                        else:
                            self._alarms[alarm] = now + later
                self._until = min(self._alarms.values(), default=math.inf)
                self._lock.wait(None if self._until == math.inf else self._until - now)


WATCHDOG = _Watchdog()


@dataclass(frozen=True)
class Answer:
    """One model: its shown atoms by predicate name, as argument tuples.

    ``cost`` (when asked for) holds one sum per optimisation level, most important
    first, and ``priority`` each one's level; the last model of an exhausted search is
    optimal.
    """

    atoms: dict[str, list[tuple[Value, ...]]]
    cost: tuple[int, ...] = ()
    priority: tuple[int, ...] = ()
    optimal: bool = False  # proven optimal (with ``costs``, e.g. in clasp's optN mode)

    def get(self, name: str) -> list[tuple[Value, ...]]:
        return self.atoms.get(name, [])


@dataclass(frozen=True)
class Outcome:
    """What one solve call found.

    ``satisfiable`` is ``None`` when the call was cut off before it knew; ``exhausted``
    says every model was enumerated; ``core`` names the assumptions that together
    admit no model (an unsatisfiable call with assumptions only).
    """

    answers: list[Answer] = field(default_factory=list)
    satisfiable: bool | None = None
    exhausted: bool = False
    interrupted: bool = False
    core: list[clingo.Symbol] = field(default_factory=list)


class Asp:
    """A clingo control with dura's error handling.

    Args:
        arguments: clingo command-line options, e.g. ``["--heuristic=Domain"]``.
        theory: a clingo theory the programs use, e.g. ``clingodl.ClingoDLTheory()``.
    """

    def __init__(self, arguments: Sequence[str] = (), *, theory: Theory | None = None) -> None:
        self._messages: list[str] = []
        self._theory = theory
        # shown atoms already converted: a symbol recurs in many models of an enumeration
        self._shown: dict[clingo.Symbol, tuple[str, tuple[Value, ...]]] = {}
        try:
            self._control = clingo.Control(list(arguments), logger=self._log, message_limit=20)
        except RuntimeError as e:
            raise AspError(f"invalid clingo options {list(arguments)}: {e}") from e
        if theory is not None:
            theory.register(self._control)

    def _log(self, code: clingo.MessageCode, message: str) -> None:
        self._messages.append(message)

    def _fail(
        self, what: str, error: Exception, source: str | None = None, shift: int = 0
    ) -> AspError:
        """An AspError naming the first located clingo message, else the error itself;
        ``shift``: characters clingo read before the text's first line."""
        lines = [line for m in self._messages for line in m.splitlines()]
        if source is not None:
            lines = [line.replace("<block>", source).replace("<string>", source) for line in lines]
        self._messages.clear()
        for i, line in enumerate(lines):
            match = _LOCATION.match(line)
            if match and match["kind"] == "error":
                message = match["msg"].rstrip(":")
                detail = " ".join(x.strip() for x in lines[i + 1 : i + 2] if not _LOCATION.match(x))
                text = f"{message}: {detail}" if detail else message
                row, column = int(match["line"]), int(match["col"])
                column = max(1, column - shift) if row == 1 else column
                return AspError(f"{match['src']}:{row}:{column}: {text}")
        detail = next((line for line in lines if line.strip()), str(error))
        return AspError(f"{what}: {detail}")

    # --- programs -------------------------------------------------------------------

    def load(self, path: Path) -> None:
        """Load a program file; errors name ``path:line:col``."""
        text = unsaved_text(path)
        if text is None and not path.is_file():
            raise AspError(f"{path}: cannot read: no such file")
        try:
            statements = self._parsed(path, text)
            with ast.ProgramBuilder(self._control) as builder:
                add = builder.add if self._theory is None else self._rewriter(self._theory, builder)
                for statement in statements:
                    add(statement)
        except UnicodeDecodeError as e:
            raise AspError(f"{path}: cannot read: not UTF-8 ({e.reason})") from e
        except RuntimeError as e:
            raise self._fail(str(path), e, str(path)) from e

    def _parsed(self, path: Path, text: str | None) -> list[ast.AST]:
        """The statements of a program file (or of ``text``, an editor's buffer of it),
        parsed once while it stays the same (parsing costs more than building a control
        from parsed statements)."""
        key: tuple[str, int, int] | tuple[str, str]
        if text is None:
            stat = path.stat()
            key = (str(path), stat.st_mtime_ns, stat.st_size)
        else:
            key = (str(path), text)
        statements = PARSED.get(key)
        if statements is None:
            statements = []
            _refuse_foreign(str(path), path.read_text(encoding="utf-8") if text is None else text)
            if text is None:
                ast.parse_files([str(path)], statements.append, logger=self._log)
            else:  # its messages name <string>: _fail names the file
                ast.parse_string(text, statements.append, logger=self._log)
            if len(PARSED) >= PARSED_FILES:
                PARSED.clear()
            PARSED[key] = statements
        return statements

    def add(
        self,
        text: str,
        *,
        part: str = "base",
        params: Sequence[str] = (),
        source: str = "<program>",
    ) -> None:
        """Add program text to a part; errors name ``source:line:col``."""
        # with a theory, on the first line: clingo's line numbers stay those of the text
        # (its columns there are shifted by the head)
        head = ""
        if self._theory is not None:
            head = f"#program {part}({','.join(params)}). " if params else f"#program {part}. "
        _refuse_foreign(source, text)
        try:
            if self._theory is None:
                self._control.add(part, list(params), text)
            else:
                with ast.ProgramBuilder(self._control) as builder:
                    rewrite = self._rewriter(self._theory, builder)
                    ast.parse_string(head + text, rewrite, logger=self._log)
        except RuntimeError as e:
            raise self._fail(source, e, source, len(head)) from e

    def add_facts(self, atoms: Iterable[clingo.Symbol], *, part: str = "base") -> None:
        """Add facts to a part (fast: facts never need a theory's rewriting)."""
        try:
            self._control.add(part, [], facts(atoms))
        except RuntimeError as e:
            raise self._fail("facts", e, "<facts>") from e

    @staticmethod
    def _rewriter(theory: Theory, builder: ast.ProgramBuilder) -> Callable[[ast.AST], None]:
        return lambda statement: theory.rewrite_ast(statement, builder.add)

    def ground(self, parts: Sequence[tuple[str, Sequence[object]]] = (("base", ()),)) -> None:
        """Ground program parts with their arguments (Python values)."""
        try:
            self._control.ground([(name, [to_symbol(a) for a in args]) for name, args in parts])
            if self._theory is not None:
                self._theory.prepare(self._control)
        except RuntimeError as e:
            raise self._fail("grounding", e, "<program>") from e

    def assign_external(self, symbol: clingo.Symbol, value: bool | None) -> None:
        """Set an external atom true, false, or free (``None``)."""
        self._control.assign_external(symbol, value)

    def set(self, option: str, value: str) -> None:
        """Change a solver option between calls, e.g. ``set("solve.models", "0")``."""
        group, _, key = option.rpartition(".")
        config = self._control.configuration
        for name in group.split(".") if group else ():
            config = getattr(config, name)
        setattr(config, key, value)

    # --- solving --------------------------------------------------------------------

    def solve(
        self,
        *,
        assumptions: Sequence[tuple[clingo.Symbol, bool]] = (),
        timeout: float | None = None,
        grace: float = 0.0,
        keep: bool = True,
        costs: bool = False,
    ) -> Outcome:
        """Solve; collect the models (all, or only the last one).

        Args:
            assumptions: atoms fixed true or false for this call only.
            timeout: seconds until the search is interrupted; ``None`` waits for the end.
            grace: seconds more to wait for a first model if the timeout passes without
                one; that model then ends the search.
            keep: keep every model in the outcome (else only the last).
            costs: record each model's cost and priorities (optimisation; slower).
        """
        answers: list[Answer] = []
        alarm = None if timeout is None else _Alarm(self._control, timeout, grace)
        try:
            # Synchronous: models are read in this thread as the search yields them (a
            # callback from clasp's own thread costs twice as much per call).
            with self._control.solve(assumptions=list(assumptions), yield_=True) as handle:
                if alarm is not None:
                    WATCHDOG.arm(alarm)
                for model in handle:
                    answer = self._answer(model, costs)
                    if keep or not answers:
                        answers.append(answer)
                    else:
                        answers[-1] = answer
                    if alarm is not None:
                        alarm.answered = True
                        if alarm.late:  # the first model after the time bound ends the search
                            handle.cancel()
                            break
                result = handle.get()
                core = list(handle.core()) if result.unsatisfiable and assumptions else []
        except RuntimeError as e:
            raise self._fail("solving", e) from e
        finally:
            if alarm is not None:
                WATCHDOG.disarm(alarm)
        if alarm is not None and alarm.fired and not result.interrupted:
            self._absorb_interrupt()
        satisfiable: bool | None = None if result.unknown else bool(result.satisfiable)
        if answers and satisfiable is None:
            satisfiable = True
        late = alarm is not None and alarm.late
        return Outcome(
            answers=answers,
            satisfiable=satisfiable,
            exhausted=bool(result.exhausted),
            interrupted=bool(result.interrupted) or late,
            core=self._core_symbols(core, assumptions) if result.unsatisfiable else [],
        )

    def _absorb_interrupt(self) -> None:
        """Take up an interrupt that came after the search ended: clingo keeps it for
        the next solve call, which would otherwise stop at once."""
        with self._control.solve(yield_=True) as handle:
            handle.cancel()

    def _answer(self, model: clingo.Model, costs: bool) -> Answer:
        atoms: dict[str, list[tuple[Value, ...]]] = {}
        shown = self._shown
        for symbol in model.symbols(shown=True):
            known = shown.get(symbol)
            if known is None:
                if len(shown) >= SHOWN_CACHE:  # a long-lived control meets new atoms
                    shown.clear()
                args = tuple(to_python(a) for a in symbol.arguments)
                known = shown[symbol] = (symbol.name, args)
            atoms.setdefault(known[0], []).append(known[1])
        if not costs:
            return Answer(atoms)
        return Answer(atoms, tuple(model.cost), tuple(model.priority), model.optimality_proven)

    def _core_symbols(
        self, literals: list[int], assumptions: Sequence[tuple[clingo.Symbol, bool]]
    ) -> list[clingo.Symbol]:
        """The assumed atoms among a core's literals (a lookup each, not a scan of all atoms)."""
        wanted = {abs(literal) for literal in literals}
        atoms = self._control.symbolic_atoms
        out: list[clingo.Symbol] = []
        for symbol, _ in assumptions:
            found = atoms[symbol]
            if found is not None and found.literal in wanted:
                out.append(symbol)
        return out
