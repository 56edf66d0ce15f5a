"""A unified-planning environment that reads PDDL and never plans: for commands that
only read a domain (``dura validate``, ``dura domain show --offline``).

unified-planning's global environment, made when its PDDL reader is first used, builds
the engine factory: it imports every installed planner (Aries and its gRPC stack, Fast
Downward, Kairos) and, through its engine base class, ConfigSpace and with it
scipy.stats, which alone costs most of a second. Reading a domain needs none of them.
:func:`use_reader_environment` makes the global environment without engines and lets
``ConfigSpace`` load only if something really asks for it
(:mod:`executive.planning.config_space`). A process that plans
(``dura run``, ``dura plan``) never calls it; its planner workers are processes of
their own.
"""

from __future__ import annotations

from executive.planning import config_space


def use_reader_environment() -> None:
    """Make unified-planning's global environment without planning engines (once, and
    only if nothing made it yet: then this changes nothing)."""
    config_space.defer()
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
