"""Translators: lifecycle commands for programs not written with the SDK (thesis 6.1).

A translator plug-in carries the executive's commands to one program. Its host is an
SDK component, so the executive handles the pair like any other component; the
program runs as the host's child, in the host's process group, and dies with it::

    command: [python, -m, executive.runtime.translator, process, --, ./driver, --port, /dev/ttyUSB0]

Plug-ins register in the entry-point group ``dura.translators`` (``process`` comes with
dura: :mod:`executive.runtime.translators.process`). Whether the host is a functionality or a
behavior comes from the launcher (``DURA_KIND``).
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import sys
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from importlib.metadata import entry_points
from typing import Any

from executive.bus import keys
from executive.bus.session import Bus
from executive.sdk import Behavior, Functionality
from executive.sdk.component import Component
from knowledge.description import Kind
from knowledge.errors import ComponentError

GROUP = "dura.translators"
USAGE = "usage: python -m executive.runtime.translator TRANSLATOR [--] PROGRAM [ARG ...]"


class Translator(ABC):
    """Carries lifecycle commands to one program (one translator per component process).

    Args:
        argv: the program and its arguments.
        log: the host component's logger.
        on_exit: to call with the program's return code (negative: killed by that
            signal) when it ends on its own; the host then ends the same way.
    """

    name = "translator"

    def __init__(
        self, argv: Sequence[str], log: logging.Logger, on_exit: Callable[[int], None]
    ) -> None:
        self.argv = list(argv)
        self.log = log
        self.on_exit = on_exit

    @abstractmethod
    def start(self, params: dict[str, Any]) -> None:
        """Start a functionality's program."""

    def pause(self) -> None:
        raise ComponentError(f"the {self.name} translator cannot pause")

    def resume(self) -> None:
        raise ComponentError(f"the {self.name} translator cannot resume")

    def reconfigure(self, params: dict[str, Any]) -> None:
        raise ComponentError(f"the {self.name} translator cannot reconfigure")

    @abstractmethod
    def stop(self) -> None:
        """End the program (if it runs)."""

    def execute(self, goal: dict[str, Any], behavior: Behavior) -> dict[str, Any]:
        """Carry out a behavior's goal; call ``behavior.checkpoint()`` while waiting."""
        raise ComponentError(f"the {self.name} translator runs no goals")


def load(name: str) -> type[Translator]:
    """The translator plug-in registered under ``name``.

    Raises:
        ComponentError: none is registered, or it fails to load.
    """
    found = {ep.name: ep for ep in entry_points(group=GROUP)}
    if name not in found:
        known = ", ".join(sorted(found)) or "none"
        raise ComponentError(f"no translator {name!r} (installed: {known})")
    try:
        loaded = found[name].load()
    except Exception as e:
        raise ComponentError(f"translator {name!r} failed to load: {e}") from e
    if not (isinstance(loaded, type) and issubclass(loaded, Translator)):
        raise ComponentError(f"translator {name!r} is not a Translator: {loaded!r}")
    return loaded


class _Host(Component):
    """The lifecycle hooks both hosts share: they forward to the translator."""

    def __init__(
        self, name: str, bus: Bus, translator: type[Translator], argv: Sequence[str]
    ) -> None:
        super().__init__(name, bus)
        self.translator = translator(argv, self.log, self._program_ended)

    def on_pause(self) -> None:
        self.translator.pause()

    def on_resume(self) -> None:
        self.translator.resume()

    def on_reconfigure(self, params: dict[str, Any]) -> None:
        self.translator.reconfigure(params)

    def on_stop(self) -> None:
        self.translator.stop()

    def _program_ended(self, returncode: int) -> None:
        """The program ended on its own: end this process the same way."""

        def end() -> None:
            self.log.warning("the program ended on its own (return code %d)", returncode)
            if returncode < 0:
                with contextlib.suppress(OSError, ValueError):  # SIGKILL has no handler
                    signal.signal(-returncode, signal.SIG_DFL)
                os.kill(os.getpid(), -returncode)
            self._framework.end(returncode)

        self._framework.post(end)


class TranslatedFunctionality(_Host, Functionality):
    def on_start(self) -> None:
        self.translator.start(self.params)


class TranslatedBehavior(_Host, Behavior):
    def execute(self, goal: dict[str, Any]) -> dict[str, Any]:
        return self.translator.execute(goal, self)


def main(argv: Sequence[str] | None = None) -> None:
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) >= 2 and args[1] == "--":
        del args[1]
    if len(args) < 2:
        print(USAGE, file=sys.stderr)
        sys.exit(2)
    try:
        translator = load(args[0])
    except ComponentError as e:
        print(f"dura translator: {e}", file=sys.stderr)
        sys.exit(1)
    behavior = os.environ.get(keys.ENV_KIND) == Kind.BEHAVIOR.value
    host = TranslatedBehavior if behavior else TranslatedFunctionality
    sys.exit(host.run_process(translator, args[1:]))


if __name__ == "__main__":
    # Run the module proper: plug-ins subclass its Translator, not this __main__ copy's.
    import importlib

    importlib.import_module("executive.runtime.translator").main()
