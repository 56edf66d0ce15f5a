"""Standard modules that a command's imports name but seldom use, imported at first use.

``dataclasses`` imports ``inspect`` (and with it ``ast``, ``dis`` and ``tokenize``) only
to write the docstring of a dataclass that has none: 8 ms of CPU at every command's
start, a sixth of what ``dura status`` cost beyond a bare Python, for nothing the quick
commands use; and ``copy`` (with ``weakref``: 0.8 ms), which it needs only for
``asdict`` and ``astuple``. :func:`defer` puts a stand-in in ``sys.modules`` that
imports the module when something first asks it for a name, and from then on holds the
module's names: whoever imported the stand-in gets the module's functions, whoever
imports the module afterwards gets the module. Only the ``dura`` console script defers
(see :func:`executive.cli.entry`), not a program that calls :func:`executive.cli.main`.
"""

from __future__ import annotations

import importlib
import sys
import threading
import types
from typing import Any

DEFERRED = ("inspect", "copy")
"""The modules :func:`defer` defers: imported by modules on a quick command's path, used
by none of them there."""

_LOADING = threading.RLock()  # the first use of a stand-in may come from any thread


class DeferredModule(types.ModuleType):
    """A stand-in for a module not imported yet: imports it at the first name asked."""

    def __getattr__(self, name: str) -> Any:
        with _LOADING:
            if sys.modules.get(self.__name__) is self:
                del sys.modules[self.__name__]
            module = importlib.import_module(self.__name__)
            self.__dict__.update(module.__dict__)
        return getattr(module, name)


def defer(names: tuple[str, ...] = DEFERRED) -> None:
    """Import each of these modules at its first use (those not imported yet)."""
    for name in names:
        if name not in sys.modules:
            sys.modules[name] = DeferredModule(name)
