"""How dura's processes start fast: every start-up trick, and nothing else, is here.

A quick command (``dura status``, ``goal list``, ``component list``) costs about twice a
bare ``python -c pass``, ``dura validate`` half a second of CPU, and a planner worker
warms up in 0.4 s of CPU, because of the five tricks below. Each changes how
Python or a dependency behaves, for speed alone, so each says what it saves, why it is
safe, and who uses it. Everywhere else, a module that needs something late imports it
late: a plain import inside the function, with the reason beside it.

What each saves, left out in turn with the others kept (median CPU of the process and
its children over 40-60 interleaved runs of a quick command, 6-8 of the others; quiet,
then with one core of two kept busy):

- :func:`defer_modules` (the ``dura`` console script): 3.5, 4.3 ms of ``dura status``'s 35;
- :func:`collection_paused` (the console script): 0.6, 0.9 ms; 6.8, 7.0 ms with
  :func:`exit_at_once` left out too, since both spare the teardown of the imports'
  objects;
- :func:`exit_at_once` (the commands that keep nothing open): 1.6, 1.4 ms; see above;
- :func:`import_unified_planning` (the planner worker, :func:`use_reader_environment`):
  0.78, 0.80 s of the worker's 1.2 s to warm up; 0.68, 0.64 s of ``dura validate``'s 1.1 s;
- :func:`use_reader_environment` (``dura validate``, ``dura domain show --offline``,
  ``dura plan --offline``): 85, 82 ms of ``dura validate``'s 0.5 s; with the trick above,
  1.0 s of ``dura plan --offline``'s 1.8 s.

Without the first three, ``dura status`` costs 13 ms more, 2.8 times a bare Python (the
benchmark's limit is 2.5). ``python -m tests.benchmarks.cli`` measures the quick commands
and ``dura validate``, ``python -m tests.benchmarks.planning`` the worker's warm-up.
argparse's help formatter in :mod:`executive.cli` saves another 1.7 ms (``shutil`` left
unimported), through argparse's public ``formatter_class``: not a trick.
"""

from __future__ import annotations

import atexit
import contextlib
import gc
import importlib
import os
import sys
import threading
import types
from collections.abc import Iterator
from typing import Any, NoReturn

DEFERRED = ("inspect", "copy")
"""The modules :func:`defer_modules` defers: the standard library's ``dataclasses``
imports them, and no quick command uses them."""

_LOADING = threading.RLock()  # the first use of a stand-in may come from any thread


class DeferredModule(types.ModuleType):
    """A stand-in in ``sys.modules`` for a module not imported yet: it imports the module
    at the first name asked of it and from then on holds the module's names. Whoever
    imported the stand-in gets the module's functions; whoever imports the module
    afterwards gets the module itself."""

    def __getattr__(self, name: str) -> Any:
        if name == "__path__":  # asked by every ``from X import name``: not a use
            raise AttributeError(name)
        with _LOADING:
            if sys.modules.get(self.__name__) is self:
                del sys.modules[self.__name__]
            module = importlib.import_module(self.__name__)
            self.__dict__.update(module.__dict__)
        return getattr(module, name)


def defer_modules(names: tuple[str, ...] = DEFERRED) -> None:
    """Import each of these modules (not packages) at its first use, those not imported
    yet.

    Saves: ``dataclasses`` imports ``inspect`` (with ``ast``, ``dis`` and ``tokenize``)
    only to write the docstring of a dataclass that has none, and ``copy`` only for
    ``asdict``, ``astuple`` and ``replace``'s deep copies; every quick command imports
    ``dataclasses`` (the bus API's records) and uses neither: 3.5-4.3 ms of ``dura
    status``'s 35.

    Safe: the stand-in answers every name as the module does, from any thread (the first
    use imports the module under a lock), and stands in only until then. Only the
    ``dura`` console script defers (:func:`executive.cli.entry`), not a program or a
    test that calls :func:`executive.cli.main`.
    """
    for name in names:
        if name not in sys.modules:
            sys.modules[name] = DeferredModule(name)


@contextlib.contextmanager
def collection_paused() -> Iterator[None]:
    """Collect no garbage while the block runs (a command's imports), and leave the
    objects it made out of every later collection.

    Saves: the imports make tens of thousands of objects that live until the process
    ends; collecting among them, during the imports, after them and at the exit, only
    costs time. With :func:`exit_at_once` the exit's share is gone already: 0.6-0.9 ms
    of ``dura status``'s 35 alone, 7 ms without :func:`exit_at_once`.

    Safe: ``gc.disable`` and ``gc.freeze`` (every tracked object moved to a permanent
    generation that later collections skip) are the ``gc`` module's public means; the
    collector runs again after the block, whatever happens in it, for every object the
    command makes later. A reference cycle that the imports made and dropped is never
    freed: memory made once, also in a long-running ``dura run``.
    """
    gc.disable()
    try:
        yield
    finally:
        gc.freeze()
        gc.enable()


def exit_at_once(code: int) -> NoReturn:
    """End a command that keeps nothing open (no file being written, no process, no
    thread of its own): exit handlers run and output is flushed as at any exit, but the
    memory is not freed object by object and Zenoh's runtime threads are not stopped one
    by one, since the kernel does both at once. Only when the main thread is the last:
    otherwise Python's own exit, which waits for the others.

    Saves: Python's teardown: 1.4-1.6 ms of ``dura status``'s 35 alone, 7 ms without
    :func:`collection_paused`.

    Safe: the exit handlers run (logging's flush, any library's clean-up), then
    ``sys.stdout`` and ``sys.stderr`` are flushed; a reader that went away is not an
    error. ``atexit._run_exitfuncs`` is private, but it runs the handlers as Python's own
    exit does and has been there since Python 2; should it ever go, the command ends by
    Python's exit. The public way, ending in a handler registered first (they run last
    to first), would skip those registered before it, such as coverage's in a measured
    subprocess.
    """
    run_exit_handlers = getattr(atexit, "_run_exitfuncs", None)
    if threading.active_count() > 1 or run_exit_handlers is None:
        sys.exit(code)
    run_exit_handlers()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError):  # a reader went away (dura status | head)
            stream.flush()
    os._exit(code)


class _ConfigurationSpace:
    """``ConfigSpace.ConfigurationSpace`` as unified-planning's engine module binds it:
    making one imports ``ConfigSpace`` and makes a real one."""

    def __new__(cls, *args: Any, **kwargs: Any) -> Any:
        return importlib.import_module("ConfigSpace").ConfigurationSpace(*args, **kwargs)


def import_unified_planning() -> None:
    """Import unified-planning's engines with ``ConfigSpace`` left unimported until
    something uses it (nothing, if unified-planning's engines are imported already).

    Saves: unified-planning's engine base class imports ``ConfigSpace`` only to annotate
    and make ``Engine.get_configuration_space`` (parameter tuning, which dura never
    does), and ``ConfigSpace`` imports numpy and scipy.stats: 0.8 s of a planner
    worker's 1.2 s of CPU to warm up (the worker is ready in 0.3 s instead of 1 s, quiet),
    0.65 s of ``dura validate``'s 1.1 s.

    Safe: a stand-in takes ``ConfigSpace``'s place in ``sys.modules`` only while
    unified-planning's engines import, and hands their module a ``ConfigurationSpace``
    that makes a real one; any other name asked of it meanwhile imports the real
    package. After the import nothing stands in: whoever imports ``ConfigSpace`` gets
    it. Must come before anything imports unified-planning (the planner worker's first
    step; :func:`use_reader_environment`'s).
    """
    if "unified_planning.engines" in sys.modules or "ConfigSpace" in sys.modules:
        return
    stand_in = DeferredModule("ConfigSpace")
    stand_in.ConfigurationSpace = _ConfigurationSpace  # type: ignore[attr-defined]
    sys.modules["ConfigSpace"] = stand_in
    try:
        importlib.import_module("unified_planning.engines")
    finally:
        if sys.modules.get("ConfigSpace") is stand_in:
            del sys.modules["ConfigSpace"]


def use_reader_environment() -> None:
    """Make unified-planning's global environment without planning engines, for a
    process that reads PDDL and never plans (once, and only if nothing made it yet:
    then this changes nothing).

    Saves: the environment's engine factory imports every installed planner (Aries and
    its gRPC stack, Fast Downward, Kairos) when it is made: 85 ms of ``dura validate``'s
    0.5 s of CPU; with :func:`import_unified_planning`, 1.0 s of ``dura plan
    --offline``'s 1.8 s (it reads the problem before its worker plans).

    Safe: unified-planning's factory reads its default engines from two module
    dictionaries when it is made; they are emptied only while the environment is made,
    and restored whatever happens. Reading PDDL uses no engine. A process that plans
    (``dura run``, the planner worker) never calls this: its engines would be missing.
    """
    import_unified_planning()
    # here, not at the top: the console script imports this module, and a quick command
    # must not load unified-planning
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
