"""The extension point for the executive's services (launcher, observers, diagnosis, ...),
and their one lifecycle.

The executive process composes services; each talks to the others only through the
bus (see :mod:`executive.bus.keys` and :mod:`executive.bus.payloads`), so any of them
can also run in a process of its own. A service gets its collaborators in its
constructor and has the lifecycle of a ROS 2 managed node::

    UNCONFIGURED --configure--> INACTIVE --activate--> ACTIVE
                                INACTIVE <-deactivate- ACTIVE
    any state --shutdown--> FINALIZED
    any state --a failure--> ERROR (with its reason) --shutdown--> FINALIZED

Configured, a service holds what it needs and answers what it serves at once (the high
level's API); active, it works (threads, subscriptions, components). While a transition
runs the service is in its transition state (CONFIGURING, ACTIVATING, DEACTIVATING,
SHUTTING_DOWN). The transitions are the framework's and final; a service overrides the
``on_*`` hooks, each of which does nothing by default. A hook that raises puts the
service in ERROR with the reason, and the exception goes on to the caller; a transition
the current state does not allow is refused with a :class:`~knowledge.errors.ServiceError`.
:class:`~executive.bus.lifecycle_manager.LifecycleManager` drives the services of a
process; :meth:`Service.wait_for` waits for a state (the readiness of a service).
"""

from __future__ import annotations

import enum
import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar, final

from executive.bus.session import Bus
from knowledge.description import RobotDescription
from knowledge.errors import DuraError, ServiceError
from knowledge.knowledge_base import KnowledgeBase

log = logging.getLogger("dura.service")


@dataclass(frozen=True)
class Context:
    """What every service may use: the robot, its bus session and its knowledge base."""

    robot: RobotDescription
    bus: Bus
    kb: KnowledgeBase


class ServiceState(enum.Enum):
    """Where a service is in its lifecycle (the states of a ROS 2 managed node)."""

    UNCONFIGURED = "unconfigured"  # built: holds nothing yet
    INACTIVE = "inactive"  # configured: holds what it needs, does no work
    ACTIVE = "active"  # works
    FINALIZED = "finalized"  # shut down: released everything, for good
    ERROR = "error"  # failed (see Service.reason); only shutdown leaves it
    # transition states: the hook of the transition runs
    CONFIGURING = "configuring"
    ACTIVATING = "activating"
    DEACTIVATING = "deactivating"
    SHUTTING_DOWN = "shutting down"


_S = ServiceState
_GONE = frozenset({_S.ERROR, _S.SHUTTING_DOWN, _S.FINALIZED})  # never active again
_LEAVING = _GONE | {_S.DEACTIVATING}  # not on the way to ACTIVE
_WAS_ACTIVE = frozenset({_S.ACTIVATING, _S.ACTIVE, _S.DEACTIVATING})

# the framework's methods a subclass must not define: the hook to override instead
HOOKS = {
    "configure": "on_configure",
    "activate": "on_activate",
    "deactivate": "on_deactivate",
    "shutdown": "on_shutdown",
    "start": "on_activate",  # the services' methods before the lifecycle
    "stop": "on_deactivate",
}
FINAL = ("state", "reason", "fail", "add_failure_listener", "wait_for", "_activated")


class Service:
    """One long-running part of the executive, with the lifecycle of the module docstring.

    Override :meth:`on_configure`, :meth:`on_activate`, :meth:`on_deactivate` and
    :meth:`on_shutdown`. A service whose activation completes later (the high level:
    once its planner is warm) sets :attr:`activates_later` and calls
    :meth:`_activated` when it is active.
    """

    name: ClassVar[str] = "service"
    activates_later: ClassVar[bool] = False
    """True: ACTIVATING until the service calls :meth:`_activated` (or fails)."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        for method, hook in HOOKS.items():
            if method in vars(cls):
                raise TypeError(f"{cls.__name__} defines {method}(): override {hook}() instead")
        for method in FINAL:
            if method in vars(cls):
                raise TypeError(f"{cls.__name__} defines {method}(): it is the framework's")

    def __init__(self, context: Context) -> None:
        self.context = context
        self.__state = ServiceState.UNCONFIGURED
        self.__reason = ""
        self.__failed_in = ServiceState.UNCONFIGURED  # the state it failed in
        self.__changed = threading.Condition()
        self.__failure_listeners: list[Callable[[Service], None]] = []

    # --- the hooks ------------------------------------------------------------------------

    def on_configure(self) -> None:
        """Take what the service needs and answer what it serves while inactive; return
        quickly (it runs before any service of the process is active)."""

    def on_activate(self) -> None:
        """Begin the work: threads, subscriptions, verbs; return quickly."""

    def on_deactivate(self) -> None:
        """Stop the work :meth:`on_activate` began (also after it failed half-way)."""

    def on_shutdown(self) -> None:
        """Release what :meth:`on_configure` took (also after it failed half-way)."""

    # --- the framework ------------------------------------------------------------------

    @property
    @final
    def state(self) -> ServiceState:
        return self.__state

    @property
    @final
    def reason(self) -> str:
        """Why the service is in ERROR ("" otherwise)."""
        return self.__reason

    @final
    def configure(self) -> None:
        """UNCONFIGURED -> INACTIVE through :meth:`on_configure`.

        Raises:
            ServiceError: the service is not unconfigured.
        """
        self.__begin("configure", {_S.UNCONFIGURED}, _S.CONFIGURING)
        self.__run(self.on_configure)
        self.__end(_S.CONFIGURING, _S.INACTIVE)

    @final
    def activate(self) -> None:
        """INACTIVE -> ACTIVE through :meth:`on_activate` (ACTIVATING until the service
        says it is active, if it :attr:`activates_later`).

        Raises:
            ServiceError: the service is not inactive.
        """
        self.__begin("activate", {_S.INACTIVE}, _S.ACTIVATING)
        self.__run(self.on_activate)
        if not self.activates_later:
            self.__end(_S.ACTIVATING, _S.ACTIVE)

    @final
    def deactivate(self) -> None:
        """ACTIVE (or ACTIVATING) -> INACTIVE through :meth:`on_deactivate`.

        Raises:
            ServiceError: the service is not active.
        """
        self.__begin("deactivate", {_S.ACTIVE, _S.ACTIVATING}, _S.DEACTIVATING)
        self.__run(self.on_deactivate)
        self.__end(_S.DEACTIVATING, _S.INACTIVE)

    @final
    def shutdown(self) -> None:
        """Any state but FINALIZED -> FINALIZED: an active service is deactivated first,
        then :meth:`on_shutdown` releases what it holds (nothing is called for one never
        configured). A hook that raises is logged: the service is finalized all the same.

        Raises:
            ServiceError: the service is finalized already, or shutting down.
        """
        allowed = {_S.UNCONFIGURED, _S.INACTIVE, _S.ACTIVATING, _S.ACTIVE, _S.ERROR}
        before = self.__begin("shutdown", allowed, _S.SHUTTING_DOWN)
        if before is _S.ERROR:
            before = self.__failed_in
        hooks = []
        if before in _WAS_ACTIVE:
            hooks.append(self.on_deactivate)
        if before is not _S.UNCONFIGURED:
            hooks.append(self.on_shutdown)
        try:
            for hook in hooks:
                try:
                    hook()
                except Exception:
                    log.exception("the %s service failed to shut down cleanly", self.name)
        finally:
            self.__end(_S.SHUTTING_DOWN, _S.FINALIZED)

    @final
    def fail(self, reason: str) -> None:
        """Report a failure found while the service runs (on a thread of its own): the
        service is in ERROR with ``reason``, and its failure listeners are told. A
        failure while it shuts down, or after a first failure, changes nothing."""
        with self.__changed:
            if self.__state in _GONE:
                log.debug("the %s service failed after all: %s", self.name, reason)
                return
            self.__failed_in, self.__state, self.__reason = self.__state, _S.ERROR, reason
            self.__changed.notify_all()
            listeners = list(self.__failure_listeners)
        for listener in listeners:
            listener(self)

    @final
    def add_failure_listener(self, listener: Callable[[Service], None]) -> None:
        """Call ``listener`` with the service when it fails while it runs (:meth:`fail`;
        a hook that raises raises to the caller instead)."""
        with self.__changed:
            self.__failure_listeners.append(listener)

    @final
    def wait_for(self, state: ServiceState, timeout: float | None = None) -> bool:
        """Wait until the service is in ``state``; whether it is. Returns at once (False)
        once it cannot get there any more: it failed, or shuts down (for ACTIVE: or is
        being deactivated)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        with self.__changed:
            while self.__state is not state:
                if state is _S.ACTIVE and self.__state in _LEAVING:
                    return False
                if self.__state in _GONE and state not in _GONE:
                    return False
                if self.__state is _S.FINALIZED:
                    return False
                left = None if deadline is None else deadline - time.monotonic()
                if left is not None and left <= 0:
                    return False
                self.__changed.wait(left)
            return True

    @final
    def _activated(self) -> bool:
        """For a service that :attr:`activates_later`: it is active now. False (and
        nothing changes) when its activation was withdrawn meanwhile (deactivated, shut
        down or failed)."""
        with self.__changed:
            if self.__state is not _S.ACTIVATING:
                return False
            self.__state = _S.ACTIVE
            self.__changed.notify_all()
            return True

    def __begin(
        self, transition: str, allowed: set[ServiceState], during: ServiceState
    ) -> ServiceState:
        with self.__changed:
            before = self.__state
            if before not in allowed:
                raise ServiceError(
                    f"the {self.name} service cannot {transition} while {before.value}"
                    f"{f' ({self.__reason})' if before is _S.ERROR else ''}"
                )
            self.__state = during
            self.__changed.notify_all()
            return before

    def __end(self, during: ServiceState, after: ServiceState) -> None:
        with self.__changed:
            if self.__state is during:  # not failed meanwhile
                self.__state = after
                self.__changed.notify_all()

    def __run(self, hook: Callable[[], None]) -> None:
        """Run a transition's hook; if it raises, the service is in ERROR and the caller
        gets the exception."""
        try:
            hook()
        except BaseException as e:
            reason = str(e) if isinstance(e, DuraError) else f"{type(e).__name__}: {e}"
            with self.__changed:
                self.__failed_in, self.__state, self.__reason = self.__state, _S.ERROR, reason
                self.__changed.notify_all()
            raise

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name}: {self.__state.value}>"
