"""Names in PDDL text: what a PDDL name is, the objects an expression names, and fact
patterns (``robot_at``, ``(robot_at lab)``, ``(robot_at *)``), read as the reader reads
expressions."""

from __future__ import annotations

import re
from dataclasses import dataclass

from executive.planning.expression.reader import Sexp, Signature, read_sexp, show_sexp
from knowledge.errors import DomainError, did_you_mean
from knowledge.records import Fact

_NAME = re.compile(r"[^\W\d_][\w-]*")
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")
_QUANTIFIERS = ("forall", "exists")
ANY = "*"


def is_name(text: str) -> bool:
    """Whether ``text`` is a PDDL name: a letter, then letters, digits, ``-`` or ``_``."""
    return _NAME.fullmatch(text) is not None


def named_objects(text: str) -> frozenset[str]:
    """The objects a PDDL expression names as arguments: not its predicates, functions
    or connectives, variables, numbers, or the variables and types a quantifier
    declares. Nothing for text that is not an expression."""
    try:
        tree = read_sexp(text)
    except (ValueError, RecursionError):
        return frozenset()
    found: set[str] = set()

    def walk(s: Sexp) -> None:
        if isinstance(s, str) or not s:
            return
        head, rest = s[0], s[1:]
        if not isinstance(head, str):
            walk(head)
        elif head.lower() in _QUANTIFIERS:
            rest = rest[1:]  # the declared variables
        for item in rest:
            if not isinstance(item, str):
                walk(item)
            elif not item.startswith("?") and _NUMBER.fullmatch(item) is None:
                found.add(item)

    walk(tree)
    return frozenset(found)


@dataclass(frozen=True)
class FactPattern:
    """Facts by name and leading arguments; ``*`` (or nothing) matches any."""

    name: str = ANY
    args: tuple[str, ...] = ()

    @classmethod
    def read(cls, text: str) -> FactPattern:
        """Read ``robot_at``, ``(robot_at lab)``, ``(robot_at *)`` or "" (every fact).

        Raises:
            DomainError: ``fact pattern '(robot_at (lab))': expected a name or *, not (lab)``.
        """
        shown = " ".join(text.split())
        if not shown:
            return cls()
        try:
            words = read_sexp(shown if shown.startswith("(") else f"({shown})")
            if isinstance(words, str) or not words:
                raise ValueError("expected a predicate or a function, and its arguments")
            for word in words:
                if not isinstance(word, str):
                    raise ValueError(f"expected a name or {ANY}, not {show_sexp(word)}")
        except (ValueError, RecursionError) as e:
            raise DomainError(f"fact pattern '{shown}': {e}") from e
        name, *args = (str(w) for w in words)
        return cls(name, tuple(args))

    def check(self, signature: Signature) -> None:
        """Refuse names the domain and the objects do not know.

        Raises:
            DomainError: an unknown predicate, function or object, or too many arguments.
        """
        if self.name == ANY:
            parameters = None
        elif self.name in signature.predicates:
            parameters = signature.predicates[self.name]
        elif self.name in signature.functions:
            parameters = signature.functions[self.name]
        else:
            known = sorted({*signature.predicates, *signature.functions})
            raise DomainError(
                f"fact pattern '{self}': unknown predicate or function "
                f"'{self.name}'{did_you_mean(self.name, known)}"
            )
        if parameters is not None and len(self.args) > len(parameters):
            names = signature.parameter_names.get(self.name, ())
            typed = " ".join(f"{n} - {k}" for n, k in zip(names, parameters, strict=False))
            raise DomainError(
                f"fact pattern '{self}': '{self.name}' takes {len(parameters)} "
                f"argument{'' if len(parameters) == 1 else 's'}"
                f"{f' ({typed})' if typed else ''}, not {len(self.args)}"
            )
        for arg in self.args:
            if arg != ANY and arg not in signature.objects:
                raise DomainError(
                    f"fact pattern '{self}': unknown object "
                    f"'{arg}'{did_you_mean(arg, sorted(signature.objects))}"
                )

    def matches(self, fact: Fact) -> bool:
        if self.name not in (ANY, fact.name):
            return False
        return all(w in (ANY, a) for w, a in zip(self.args, fact.args, strict=False))

    def __str__(self) -> str:
        return f"({' '.join((self.name, *self.args))})"
