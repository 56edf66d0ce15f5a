"""A unified-planning environment that reads PDDL and never plans: for commands that
only read a domain (``dura validate``, ``dura domain show --offline``).

unified-planning's global environment, made when its PDDL reader is first used, builds
the engine factory: it imports every installed planner (Aries and its gRPC stack, Fast
Downward, Kairos) and, through its engine base class, ConfigSpace and with it
scipy.stats, which alone costs most of a second. Reading a domain needs none of them.
:func:`use_reader_environment` makes the global environment without engines and lets
``ConfigSpace`` load only if something really asks for it. A process that plans
(``dura run``, ``dura plan``) never calls it; its planner workers are processes of
their own.
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import Any


class _ConfigSpaceOnDemand(types.ModuleType):
    """Stands in for ``ConfigSpace`` until something other than unified-planning's
    annotation of ``Engine.get_configuration_space`` uses it; then loads the real one."""

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):  # the import system's questions: not a use
            raise AttributeError(name)
        return getattr(_real_config_space(), name)


class _ConfigurationSpace:
    """``ConfigSpace.ConfigurationSpace`` as unified-planning's engine module binds it:
    making one makes a real one."""

    def __new__(cls, *args: Any, **kwargs: Any) -> Any:
        return _real_config_space().ConfigurationSpace(*args, **kwargs)


def _real_config_space() -> types.ModuleType:
    if isinstance(sys.modules.get("ConfigSpace"), _ConfigSpaceOnDemand):
        del sys.modules["ConfigSpace"]
    return importlib.import_module("ConfigSpace")


def use_reader_environment() -> None:
    """Make unified-planning's global environment without planning engines (once, and
    only if nothing made it yet: then this changes nothing)."""
    if "unified_planning.engines" not in sys.modules and "ConfigSpace" not in sys.modules:
        stand_in = _ConfigSpaceOnDemand("ConfigSpace")
        stand_in.ConfigurationSpace = _ConfigurationSpace  # type: ignore[attr-defined]
        sys.modules["ConfigSpace"] = stand_in
    from unified_planning import environment
    from unified_planning.engines import factory

    if environment.GLOBAL_ENVIRONMENT is not None:
        return
    engines, meta_engines = factory.DEFAULT_ENGINES, factory.DEFAULT_META_ENGINES
    factory.DEFAULT_ENGINES, factory.DEFAULT_META_ENGINES = {}, {}
    try:
        environment.get_environment()
    finally:
        factory.DEFAULT_ENGINES, factory.DEFAULT_META_ENGINES = engines, meta_engines
