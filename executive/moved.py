"""Names that moved: each old module of the documented API, the module it now lives in.

An old module (``executive.component``, ``executive.harness``, ...) is a small file that
forwards every name to its new place with a :class:`DeprecationWarning` naming that place,
for one minor version after the move (its ``REMOVED_IN``). The new modules are named as
strings and imported when a name is first asked for: the old module loads nothing of the
layers above it until it is used.
"""

from __future__ import annotations

import importlib
import warnings
from collections.abc import Callable
from typing import Any

REMOVED_IN = "0.3.0"

# old module -> new module (every name the old one had is found in the new one)
MOVED: dict[str, str] = {
    "executive.component": "executive.sdk",
    "executive.harness": "executive.testing.harness",
    "executive.launcher": "executive.runtime.launcher",
    "executive.translator": "executive.runtime.translator",
}

# old name -> new name, for single names that moved out of a package that stays
MOVED_NAMES: dict[str, str] = {
    "executive.bus.Bus": "executive.bus.session.Bus",
    "executive.bus.Message": "executive.sdk.Message",
}


def warn(old: str, new: str, stacklevel: int = 3) -> None:
    """Warn that ``old`` is deprecated for ``new``."""
    warnings.warn(
        f"{old} moved to {new}: import it from there ({old} goes in dura {REMOVED_IN})",
        DeprecationWarning,
        stacklevel=stacklevel,
    )


def resolve(new: str) -> Any:
    """The object a dotted name ``package.module.Name`` names."""
    module, _, name = new.rpartition(".")
    return getattr(importlib.import_module(module), name)


def forward(old_module: str) -> Callable[[str], Any]:
    """A module ``__getattr__`` for ``old_module``: each name, from its new module, with a
    warning naming it there."""
    new_module = MOVED[old_module]

    def __getattr__(name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        try:
            value = getattr(importlib.import_module(new_module), name)
        except AttributeError:
            raise AttributeError(
                f"module {old_module!r} (moved to {new_module}) has no attribute {name!r}"
            ) from None
        warn(f"{old_module}.{name}", f"{new_module}.{name}")
        return value

    return __getattr__


def forward_names(package: str) -> Callable[[str], Any]:
    """A package ``__getattr__`` for the single names of ``package`` that moved."""

    def __getattr__(name: str) -> Any:
        new = MOVED_NAMES.get(f"{package}.{name}")
        if new is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        warn(f"{package}.{name}", new)
        return resolve(new)

    return __getattr__
