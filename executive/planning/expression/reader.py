"""Reading expressions from PDDL text against a :class:`Signature`.

Text is read against a signature (the domain's predicates, functions and types, and
the objects), so an unknown name, a wrong arity or an object of the wrong type is
refused with a one-line reason: ``goal '(picture_taken lob)': unknown object 'lob' (did
you mean 'lab'?)``. Quantifiers are expanded over the objects known when the text is
read.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Union

from executive.planning.expression.nodes import (
    COMPARISONS,
    FALSE,
    TRUE,
    Arith,
    Atom,
    Compare,
    Const,
    Expression,
    Not,
    Or,
    Value,
    conjunction,
)
from knowledge.domain import DomainInfo, is_a
from knowledge.errors import DomainError, did_you_mean
from knowledge.records import Fact


@dataclass(frozen=True)
class Signature:
    """What expressions may name: predicates and functions (their parameter types),
    objects (name → type), the type hierarchy (type → parent) and the parameters' names
    as the domain writes them (for messages)."""

    predicates: Mapping[str, tuple[str, ...]]
    functions: Mapping[str, tuple[str, ...]]
    objects: Mapping[str, str] = field(default_factory=dict)
    parents: Mapping[str, str | None] = field(default_factory=dict)
    parameter_names: Mapping[str, tuple[str, ...]] = field(default_factory=dict)

    @classmethod
    def of(cls, domain: DomainInfo, objects: Mapping[str, str] | None = None) -> Signature:
        """The domain's signature with its constants and the given objects."""
        return cls(
            dict(domain.predicates),
            dict(domain.functions),
            {**domain.constants, **(objects or {})},
            dict(domain.supertypes),
            dict(domain.parameter_names),
        )

    def is_a(self, type_name: str, wanted: str) -> bool:
        """Whether a type is ``wanted`` or one of its subtypes (``object`` is every type)."""
        return is_a(type_name, wanted, self.parents)

    def objects_of(self, type_name: str) -> list[str]:
        return sorted(o for o, t in self.objects.items() if self.is_a(t, type_name))


_TOKEN = re.compile(r"\s*(?:;[^\n]*\n?\s*)*([()]|[^\s();]+)")
_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")

Sexp = Union[str, list["Sexp"]]  # noqa: UP007 (runtime alias)


def read_sexp(text: str) -> Sexp:
    """One s-expression from text; raises ValueError with the reason."""
    tokens = [m.group(1) for m in _TOKEN.finditer(text)]
    stack: list[list[Sexp]] = [[]]
    for tok in tokens:
        if tok == "(":
            stack.append([])
        elif tok == ")":
            if len(stack) == 1:
                raise ValueError("unbalanced ')'")
            done = stack.pop()
            stack[-1].append(done)
        else:
            stack[-1].append(tok)
    if len(stack) > 1:
        raise ValueError("missing ')'")
    top = stack[0]
    if not top:
        raise ValueError("it is empty")
    if len(top) > 1:
        raise ValueError(f"text after the expression: {show_sexp(top[1])}")
    return top[0]


def show_sexp(s: Sexp) -> str:
    return s if isinstance(s, str) else "(" + " ".join(show_sexp(x) for x in s) + ")"


class _Reader:
    """Turns s-expressions into ground expressions, checking names against a signature."""

    def __init__(self, signature: Signature) -> None:
        self.sig = signature

    # every error is a ValueError with the reason; parse() adds what and where

    def condition(self, s: Sexp, env: Mapping[str, str]) -> Expression:
        if isinstance(s, str):
            raise ValueError(f"expected a condition in parentheses, not '{s}'")
        if not s:
            raise ValueError("empty parentheses")
        head, rest = s[0], s[1:]
        if not isinstance(head, str):
            raise ValueError(f"expected a predicate or a connective, not {show_sexp(head)}")
        key = head.lower()
        if key == "and":
            return conjunction(self.condition(x, env) for x in rest)
        if key == "or":
            return _disjunction([self.condition(x, env) for x in rest])
        if key == "not":
            self._arity(head, rest, 1)
            inner = self.condition(rest[0], env)
            return Const(not inner.value) if isinstance(inner, Const) else Not(inner)
        if key == "imply":
            self._arity(head, rest, 2)
            return _disjunction([Not(self.condition(rest[0], env)), self.condition(rest[1], env)])
        if key in ("exists", "forall"):
            self._arity(head, rest, 2)
            parts = [self.condition(rest[1], {**env, **b}) for b in self._bindings(rest[0])]
            return conjunction(parts) if key == "forall" else _disjunction(parts)
        if key in COMPARISONS:
            self._arity(head, rest, 2)
            if key == "=" and self._is_term(rest[0], env) and self._is_term(rest[1], env):
                return Const(self._term(rest[0], env) == self._term(rest[1], env))
            return Compare(key, self.number(rest[0], env), self.number(rest[1], env))
        if head in self.sig.predicates:
            return Atom(head, self._args(head, self.sig.predicates[head], rest, env))
        if head in self.sig.functions:
            raise ValueError(
                f"'{head}' is a function (a number); compare it, e.g. (>= {show_sexp(s)} 1)"
            )
        raise ValueError(
            f"unknown predicate '{head}'{did_you_mean(head, sorted(self.sig.predicates))}"
        )

    def number(self, s: Sexp, env: Mapping[str, str]) -> Expression:
        if isinstance(s, str):
            if _NUMBER.match(s):
                return Const(float(s))
            raise ValueError(f"expected a number or a function, not '{s}'")
        if not s or not isinstance(s[0], str):
            raise ValueError(f"expected a number or a function, not {show_sexp(s)}")
        head, rest = s[0], s[1:]
        if head in ("+", "-", "*", "/"):
            if not rest or (head != "-" and len(rest) < 2) or (head == "/" and len(rest) != 2):
                raise ValueError(
                    f"'{head}' needs {'one or more' if head == '-' else 'two'} operands"
                )
            return Arith(head, tuple(self.number(x, env) for x in rest))
        if head in self.sig.functions:
            return Value(head, self._args(head, self.sig.functions[head], rest, env))
        if head in self.sig.predicates:
            raise ValueError(f"'{head}' is a predicate, not a number")
        raise ValueError(
            f"unknown function '{head}'{did_you_mean(head, sorted(self.sig.functions))}"
        )

    def _arity(self, head: str, rest: list[Sexp], n: int) -> None:
        if len(rest) != n:
            raise ValueError(f"'{head}' takes {n} operand{'s' if n > 1 else ''}, not {len(rest)}")

    def _is_term(self, s: Sexp, env: Mapping[str, str]) -> bool:
        return isinstance(s, str) and (s in env or s in self.sig.objects)

    def _term(self, s: Sexp, env: Mapping[str, str]) -> str:
        if not isinstance(s, str):
            raise ValueError(f"expected an object, not {show_sexp(s)}")
        if s.startswith("?"):
            if s not in env:
                raise ValueError(f"unbound variable '{s}'")
            return env[s]
        if s not in self.sig.objects:
            raise ValueError(f"unknown object '{s}'{did_you_mean(s, sorted(self.sig.objects))}")
        return s

    def _args(
        self, name: str, types: tuple[str, ...], rest: list[Sexp], env: Mapping[str, str]
    ) -> tuple[str, ...]:
        if len(rest) != len(types):
            names = self.sig.parameter_names.get(name) or [f"?{i + 1}" for i in range(len(types))]
            wanted = " ".join(f"{n} - {t}" for n, t in zip(names, types, strict=False)) or "none"
            raise ValueError(
                f"'{name}' takes {len(types)} argument{'' if len(types) == 1 else 's'} "
                f"({wanted}), not {len(rest)}"
            )
        out: list[str] = []
        for i, (arg, wanted_type) in enumerate(zip(rest, types, strict=True)):
            obj = self._term(arg, env)
            actual = self.sig.objects[obj]
            if not self.sig.is_a(actual, wanted_type):
                raise ValueError(
                    f"argument {i + 1} of '{name}' must be a {wanted_type}, "
                    f"but '{obj}' is a {actual}"
                )
            out.append(obj)
        return tuple(out)

    def _bindings(self, s: Sexp) -> Iterator[dict[str, str]]:
        """Every assignment of objects to the typed variables of a quantifier."""
        if isinstance(s, str):
            raise ValueError(f"expected variables in parentheses, not '{s}'")
        variables: list[tuple[str, str]] = []
        pending: list[str] = []
        items = list(s)
        while items:
            item = items.pop(0)
            if not isinstance(item, str):
                raise ValueError(f"expected a variable, not {show_sexp(item)}")
            if item == "-":
                if not items or not isinstance(items[0], str):
                    raise ValueError("'-' must be followed by a type")
                type_name = str(items.pop(0))
                variables.extend((v, type_name) for v in pending)
                pending = []
            elif item.startswith("?"):
                pending.append(item)
            else:
                raise ValueError(f"expected a variable like ?x, not '{item}'")
        variables.extend((v, "object") for v in pending)
        known_types = set(self.sig.parents) | set(self.sig.objects.values()) | {"object"}
        for _, t in variables:
            if t not in known_types:
                raise ValueError(f"unknown type '{t}'{did_you_mean(t, sorted(known_types))}")

        def assign(i: int, env: dict[str, str]) -> Iterator[dict[str, str]]:
            if i == len(variables):
                yield dict(env)
                return
            name, type_name = variables[i]
            for obj in self.sig.objects_of(type_name):
                env[name] = obj
                yield from assign(i + 1, env)

        yield from assign(0, {})


def _disjunction(parts: list[Expression]) -> Expression:
    flat: list[Expression] = []
    for p in parts:
        if p == TRUE:
            return TRUE
        if isinstance(p, Or):
            flat.extend(p.args)
        elif p != FALSE:
            flat.append(p)
    if not flat:
        return FALSE
    return flat[0] if len(flat) == 1 else Or(tuple(flat))


def parse(text: str, signature: Signature, what: str = "goal") -> Expression:
    """Read a PDDL condition (a goal, a rule's condition) against a signature.

    Raises:
        DomainError: ``goal '(picture_taken lob)': unknown object 'lob' (did you mean 'lab'?)``.
    """
    shown = " ".join(text.split())
    try:
        return _Reader(signature).condition(read_sexp(text), {})
    except (ValueError, RecursionError) as e:
        raise DomainError(f"{what} '{shown}': {e}") from e


def check_syntax(text: str, what: str = "goal") -> None:
    """Check a PDDL condition's form alone, without a signature to name: one expression in
    parentheses, balanced (what :func:`parse` refuses before it looks at any name).

    Raises:
        DomainError: ``goal '(robot_at dock': missing ')'``.
    """
    try:
        form = read_sexp(text)
        if isinstance(form, str):
            raise ValueError(f"expected a condition in parentheses, not '{form}'")
        if not form:
            raise ValueError("empty parentheses")
    except ValueError as e:
        raise DomainError(f"{what} '{' '.join(text.split())}': {e}") from e


def parse_fact(text: str, signature: Signature) -> Fact:
    """Read a fact: ``(robot_at dock)``, ``(not (robot_at dock))`` or ``(= (battery r) 80)``.

    Raises:
        DomainError: naming the fact and what is wrong with it.
    """
    shown = " ".join(text.split())
    reader = _Reader(signature)
    try:
        s = read_sexp(text)
        if isinstance(s, list) and len(s) == 3 and s[0] == "=" and isinstance(s[1], list):
            target = reader.number(s[1], {})
            value = reader.number(s[2], {})
            if not isinstance(target, Value) or not isinstance(value, Const):
                raise ValueError("expected (= (function objects...) number)")
            return Fact(target.name, target.args, float(value.value))
        negated = isinstance(s, list) and len(s) == 2 and s[0] == "not"
        atom = reader.condition(s[1] if negated and isinstance(s, list) else s, {})
        if not isinstance(atom, Atom):
            raise ValueError("expected a predicate with objects, e.g. (robot_at dock)")
        return Fact(atom.name, atom.args, not negated)
    except (ValueError, RecursionError) as e:
        raise DomainError(f"fact '{shown}': {e}") from e
