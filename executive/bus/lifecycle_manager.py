"""One driver for the services of a process, as Nav2's lifecycle manager drives nodes.

It configures the services in order, then activates them in order; it deactivates them
in reverse, then shuts them down in reverse. So what a service serves while inactive
answers before any service of the process works (the high level's API answers, and its
planner warms up, before the task executor starts; it plans only once every service
before it is active), and nothing works any more when the first one lets go of what it
holds. Services may be added in stages (:meth:`LifecycleManager.add`), each configured
at the next :meth:`~LifecycleManager.configure`: what answers first need not wait for
the others to be loaded.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from types import TracebackType

from executive.bus.service import Service, ServiceState

log = logging.getLogger("dura.services")


class LifecycleManager:
    """Drives services through their lifecycle, together.

    Args:
        services: in the order they configure and activate.
        progress: told what the manager does now (``dura run``'s live line).
        on_failure: called with the reason when a service fails while it runs (see
            :meth:`~executive.bus.service.Service.fail`); without it the failure is
            logged.
    """

    def __init__(
        self,
        services: Sequence[Service],
        *,
        progress: Callable[[str], None] | None = None,
        on_failure: Callable[[str], None] | None = None,
    ) -> None:
        self.services: tuple[Service, ...] = ()
        self._progress = progress or (lambda _: None)
        self._on_failure = on_failure
        self.add(services)

    def add(self, services: Sequence[Service], *, before: Service | None = None) -> None:
        """Drive these services too: in this order, before ``before`` (one of the services
        already added) or after every other. They are configured at the next
        :meth:`configure`."""
        at = len(self.services) if before is None else self.services.index(before)
        self.services = (*self.services[:at], *services, *self.services[at:])
        for service in services:
            service.add_failure_listener(self._failed)

    def configure(self) -> None:
        """Configure every service not configured yet, in order (what they serve while
        inactive answers)."""
        for service in self.services:
            if service.state is ServiceState.UNCONFIGURED:
                self._progress(f"configuring the {service.name} service")
                service.configure()

    def activate(self) -> None:
        """Activate every configured service, in order. One that failed meanwhile (its
        failure was reported then) stays in ERROR."""
        for service in self.services:
            if service.state is ServiceState.ERROR:
                continue
            self._progress(f"starting the {service.name} service")
            service.activate()

    def close(self) -> None:
        """Deactivate the active services in reverse, then shut every service down in
        reverse; idempotent.

        Raises:
            Exception: the first a deactivation raised (after all were shut down).
        """
        errors: list[Exception] = []
        for service in reversed(self.services):
            if service.state in (ServiceState.ACTIVE, ServiceState.ACTIVATING):
                try:
                    service.deactivate()
                except Exception as e:
                    log.exception("the %s service failed to deactivate", service.name)
                    errors.append(e)
        for service in reversed(self.services):
            if service.state is not ServiceState.FINALIZED:
                service.shutdown()
        if errors:
            raise errors[0]

    def __enter__(self) -> LifecycleManager:
        try:
            self.configure()
            self.activate()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.close()

    def _failed(self, service: Service) -> None:
        if self._on_failure is not None:
            self._on_failure(service.reason)
        else:
            log.error("the %s service failed: %s", service.name, service.reason)
