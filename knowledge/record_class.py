"""Record classes: frozen dataclasses made at a fraction of what ``dataclass(frozen=True)``
costs.

Every typed record of dura is declared with :func:`record`: the knowledge base's rows
(:mod:`knowledge.records`), what the services report and the payloads of the bus API
(:mod:`executive.bus.reports`, :mod:`executive.bus.api`). A quick command such as ``dura
status`` loads tens of these classes before it has done anything, so a record class
shares its constructor, comparison, hash, repr and immutability with every other one
instead of having them generated and compiled for it.
"""

from __future__ import annotations

import dataclasses
import operator
import reprlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar, dataclass_transform

T = TypeVar("T")


@dataclass_transform(frozen_default=True, field_specifiers=(dataclasses.field,))
def record(cls: type[T]) -> type[T]:
    """A record class: a frozen dataclass, compared, hashed and shown by its fields (a
    class that defines its own comparison, hash or repr keeps it).

    Its constructor, comparison, hash, repr and its refusal to change a field are shared
    by every record class, not generated and compiled for each as by
    ``dataclass(frozen=True)``: a class costs about 0.03 ms to create instead of 0.3
    (0.15 for a dataclass that is not frozen), and a quick command loads tens of them;
    making an instance costs about 0.9 µs instead of 0.4. A class the shared constructor
    cannot make (keyword-only, ``InitVar`` or ``init=False`` fields, a ``__post_init__``,
    dataclass bases) is made by ``dataclass(frozen=True)``."""
    if not _plain(cls):
        made: Any = dataclass(frozen=True, eq=False, repr=False)(cls)
    else:
        made = dataclass(init=False, eq=False, repr=False)(cls)
        made._record_init = _InitPlan(made.__qualname__, dataclasses.fields(made))
        for name in ("__init__", "__setattr__", "__delattr__", "__signature__"):
            setattr(made, name, _Frozen.__dict__[name])
        made.__dataclass_params__.frozen = True
    made._record_values = _getter(tuple(f.name for f in dataclasses.fields(made) if f.compare))
    for name in ("__eq__", "__hash__", "__repr__"):
        if made.__dict__.get(name) is None:
            setattr(made, name, getattr(_ByFields, name))
    return made  # type: ignore[no-any-return]


def _own_annotations(cls: type) -> dict[str, Any]:
    """A class's own annotations, as written (``inspect`` is not imported for them)."""
    found: dict[str, Any] = cls.__dict__.get("__annotations__", {})  # noqa: RUF063
    return found


def _plain(cls: type) -> bool:
    """Whether the shared constructor makes a class: its fields are all positional, and
    it has no ``__post_init__`` nor dataclass bases."""
    if hasattr(cls, "__post_init__") or any(dataclasses.is_dataclass(b) for b in cls.__mro__[1:]):
        return False
    for name, annotation in _own_annotations(cls).items():
        if any(word in str(annotation) for word in ("KW_ONLY", "InitVar")):
            return False
        value = cls.__dict__.get(name)
        if isinstance(value, dataclasses.Field) and (not value.init or value.kw_only is True):
            return False
    return True


class _InitPlan:
    """What the shared constructor of one record class needs: its fields in order, the
    defaults of those that have one."""

    __slots__ = ("defaults", "names", "qualname")

    def __init__(self, qualname: str, fields: tuple[dataclasses.Field[Any], ...]) -> None:
        self.qualname = qualname
        self.names = tuple(f.name for f in fields)
        self.defaults: dict[str, tuple[bool, Any]] = {}  # name -> (is a factory, value)
        for f in fields:
            if f.default is not dataclasses.MISSING:
                self.defaults[f.name] = (False, f.default)
            elif f.default_factory is not dataclasses.MISSING:
                self.defaults[f.name] = (True, f.default_factory)


_set = object.__setattr__


class _Signature:
    """The constructor's signature, for ``inspect.signature`` and ``help`` (made when
    asked: ``inspect`` is not imported before)."""

    def __get__(self, instance: object, owner: type) -> Any:
        import inspect

        plan: _InitPlan = owner._record_init  # type: ignore[attr-defined]
        parameters = []
        for name in plan.names:
            default = inspect.Parameter.empty
            if name in plan.defaults:
                factory, value = plan.defaults[name]
                default = value() if factory else value
            parameters.append(
                inspect.Parameter(name, inspect.Parameter.POSITIONAL_OR_KEYWORD, default=default)
            )
        return inspect.Signature(parameters, return_annotation=None)


class _Frozen:
    """The constructor and the immutability of every record class."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        plan: _InitPlan = self.__class__._record_init  # type: ignore[attr-defined]
        names = plan.names
        if len(args) > len(names):
            raise TypeError(
                f"{plan.qualname}() takes {len(names)} positional arguments but "
                f"{len(args)} were given"
            )
        for name, value in zip(names, args, strict=False):
            _set(self, name, value)
        for name in names[len(args) :]:
            if name in kwargs:
                _set(self, name, kwargs.pop(name))
            elif name in plan.defaults:
                factory, value = plan.defaults[name]
                _set(self, name, value() if factory else value)
            else:
                raise TypeError(f"{plan.qualname}() missing the argument '{name}'")
        if kwargs:
            name = next(iter(kwargs))
            twice = name in names
            raise TypeError(
                f"{plan.qualname}() got {'multiple values for' if twice else 'an unexpected'} "
                f"argument '{name}'"
            )

    def __setattr__(self, name: str, value: Any) -> None:
        raise dataclasses.FrozenInstanceError(f"cannot assign to field '{name}'")

    def __delattr__(self, name: str) -> None:
        raise dataclasses.FrozenInstanceError(f"cannot delete field '{name}'")

    __signature__ = _Signature()


def _getter(names: tuple[str, ...]) -> Callable[[Any], tuple[Any, ...]]:
    """The values of these fields of a record, as a tuple."""
    if len(names) > 1:
        return operator.attrgetter(*names)  # a tuple of them, at C speed
    if names:
        (name,) = names
        return lambda value: (getattr(value, name),)
    return lambda value: ()


def _compared(value: Any) -> tuple[Any, ...]:
    compared: tuple[Any, ...] = value.__class__._record_values(value)
    return compared


class _ByFields:
    """The comparison, hash and repr of every record class, by its fields."""

    def __eq__(self, other: object) -> bool:
        if other.__class__ is not self.__class__:
            return NotImplemented
        return _compared(self) == _compared(other)

    def __hash__(self) -> int:
        return hash(_compared(self))

    @reprlib.recursive_repr()
    def __repr__(self) -> str:
        fields = dataclasses.fields(self)  # type: ignore[arg-type]
        shown = ", ".join(f"{f.name}={getattr(self, f.name)!r}" for f in fields if f.repr)
        return f"{self.__class__.__qualname__}({shown})"
