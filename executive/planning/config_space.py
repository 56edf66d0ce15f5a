"""``ConfigSpace``, loaded only when something really uses it.

unified-planning's engine base class imports ``ConfigSpace`` to annotate
``Engine.get_configuration_space`` (parameter tuning, which dura never does), and
``ConfigSpace`` imports numpy and scipy.stats: most of a second, and most of the time a
planner worker takes to warm up (1.5-2 s of 2.1-2.3 s here, loaded). :func:`defer`
puts a stand-in in its place before unified-planning loads: the stand-in hands out a
``ConfigurationSpace`` that makes a real one, and loads the real package as soon as
anything else of it is asked for, so nothing that uses it changes.
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import Any


class _OnDemand(types.ModuleType):
    """Stands in for ``ConfigSpace`` until something other than unified-planning's
    annotation of ``Engine.get_configuration_space`` uses it; then loads the real one."""

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):  # the import system's questions: not a use
            raise AttributeError(name)
        return getattr(_real(), name)


class _ConfigurationSpace:
    """``ConfigSpace.ConfigurationSpace`` as unified-planning's engine module binds it:
    making one makes a real one."""

    def __new__(cls, *args: Any, **kwargs: Any) -> Any:
        return _real().ConfigurationSpace(*args, **kwargs)


def _real() -> types.ModuleType:
    if isinstance(sys.modules.get("ConfigSpace"), _OnDemand):
        del sys.modules["ConfigSpace"]
    return importlib.import_module("ConfigSpace")


def defer() -> None:
    """Put the stand-in in place, unless unified-planning's engines or ``ConfigSpace``
    are loaded already (then this changes nothing)."""
    if "unified_planning.engines" not in sys.modules and "ConfigSpace" not in sys.modules:
        stand_in = _OnDemand("ConfigSpace")
        stand_in.ConfigurationSpace = _ConfigurationSpace  # type: ignore[attr-defined]
        sys.modules["ConfigSpace"] = stand_in
