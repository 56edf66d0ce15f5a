"""The one adapter between dura and clingo: programs in, Python values out.

Every use of ``clingo.Control`` in dura goes through :class:`Asp`. It loads programs
from files or text under a source name, adds facts and externals, grounds parts and
solves (optionally under a time bound and with assumptions). Models come back as
:class:`Answer` objects holding plain Python values, and every clingo failure (a
syntax error in a user's ``.lp`` file, an unsafe variable, a grounding error) becomes
an :class:`~knowledge.errors.AspError` whose message starts with ``file:line:``.
"""

from __future__ import annotations

import re
import threading
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import clingo

from knowledge.errors import AspError

# Python value of a symbol: numbers, strings (constants and quoted strings alike),
# tuples for tuples, and (name, args) for functions with arguments.
Value = int | str | tuple["Value", ...]

_LOCATION = re.compile(
    r"^(?P<src>.*?):(?P<line>\d+):\d+(?:-\d+(?::\d+)?)?: (?P<kind>\w+): (?P<msg>.*)$"
)


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


def facts(atoms: Iterable[clingo.Symbol]) -> str:
    """Program text with one fact per atom (symbols print as valid, escaped ASP)."""
    return "".join(f"{a}.\n" for a in atoms)


@dataclass(frozen=True)
class Answer:
    """One model: its shown atoms by predicate name, as argument tuples."""

    atoms: dict[str, list[tuple[Value, ...]]]
    cost: tuple[int, ...] = ()  # when asked for; the last model of an exhausted search is optimal

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
    """

    def __init__(self, arguments: Sequence[str] = ()) -> None:
        self._messages: list[str] = []
        try:
            self._control = clingo.Control(list(arguments), logger=self._log, message_limit=20)
        except RuntimeError as e:
            raise AspError(f"invalid clingo options {list(arguments)}: {e}") from e

    def _log(self, code: clingo.MessageCode, message: str) -> None:
        self._messages.append(message)

    def _fail(self, what: str, error: Exception, source: str | None = None) -> AspError:
        """An AspError naming the first located clingo message, else the error itself."""
        lines = [line for m in self._messages for line in m.splitlines()]
        if source is not None:
            lines = [line.replace("<block>", source) for line in lines]
        self._messages.clear()
        for i, line in enumerate(lines):
            match = _LOCATION.match(line)
            if match and match["kind"] == "error":
                message = match["msg"].rstrip(":")
                detail = " ".join(x.strip() for x in lines[i + 1 : i + 2] if not _LOCATION.match(x))
                text = f"{message}: {detail}" if detail else message
                return AspError(f"{match['src']}:{match['line']}: {text}")
        detail = next((line for line in lines if line.strip()), str(error))
        return AspError(f"{what}: {detail}")

    # --- programs -------------------------------------------------------------------

    def load(self, path: Path) -> None:
        """Load a program file; errors name ``path:line``."""
        if not path.is_file():
            raise AspError(f"{path}: cannot read: no such file")
        try:
            self._control.load(str(path))
        except RuntimeError as e:
            raise self._fail(str(path), e) from e

    def add(
        self,
        text: str,
        *,
        part: str = "base",
        params: Sequence[str] = (),
        source: str = "<program>",
    ) -> None:
        """Add program text to a part; errors name ``source:line``."""
        try:
            self._control.add(part, list(params), text)
        except RuntimeError as e:
            raise self._fail(source, e, source) from e

    def ground(self, parts: Sequence[tuple[str, Sequence[object]]] = (("base", ()),)) -> None:
        """Ground program parts with their arguments (Python values)."""
        try:
            self._control.ground([(name, [to_symbol(a) for a in args]) for name, args in parts])
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
        keep: bool = True,
        costs: bool = False,
    ) -> Outcome:
        """Solve; collect the models (all, or only the last one).

        Args:
            assumptions: atoms fixed true or false for this call only.
            timeout: seconds until the search is interrupted; ``None`` waits for the end.
            keep: keep every model in the outcome (else only the last).
            costs: record each model's cost (optimisation; slower).
        """
        answers: list[Answer] = []

        def on_model(model: clingo.Model) -> bool:
            answer = _answer(model, costs)
            if keep or not answers:
                answers.append(answer)
            else:
                answers[-1] = answer
            return True

        core: list[int] = []
        # A timer interrupts the search: cheaper than an asynchronous solve and a wait.
        timer = threading.Timer(timeout, self._control.interrupt) if timeout is not None else None
        if timer is not None:
            timer.daemon = True
            timer.start()
        try:
            result = self._control.solve(
                assumptions=list(assumptions), on_model=on_model, on_core=core.extend
            )
        except RuntimeError as e:
            raise self._fail("solving", e) from e
        finally:
            if timer is not None:
                timer.cancel()
        satisfiable: bool | None = None if result.unknown else bool(result.satisfiable)
        if answers and satisfiable is None:
            satisfiable = True
        return Outcome(
            answers=answers,
            satisfiable=satisfiable,
            exhausted=bool(result.exhausted),
            interrupted=bool(result.interrupted),
            core=self._core_symbols(core) if result.unsatisfiable else [],
        )

    def _core_symbols(self, literals: list[int]) -> list[clingo.Symbol]:
        wanted = {abs(literal) for literal in literals}
        return [a.symbol for a in self._control.symbolic_atoms if a.literal in wanted]


def _answer(model: clingo.Model, costs: bool) -> Answer:
    atoms: dict[str, list[tuple[Value, ...]]] = {}
    for symbol in model.symbols(shown=True):
        atoms.setdefault(symbol.name, []).append(tuple(to_python(a) for a in symbol.arguments))
    if not costs:
        return Answer(atoms)
    return Answer(atoms, tuple(model.cost))
