"""The one lifecycle of every service, and the driver of a process's services."""

from __future__ import annotations

import threading
from collections.abc import Iterator

import pytest

from executive.bus.lifecycle_manager import LifecycleManager
from executive.bus.service import Context, Service, ServiceState
from executive.bus.session import Bus
from knowledge.errors import ConfigError, ServiceError
from knowledge.knowledge_base import KnowledgeBase
from knowledge.robot import load_robot
from tests.conftest import USECASE, free_endpoint


@pytest.fixture(scope="module")
def context(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Context]:
    robot = load_robot(USECASE, domain=False)
    folder = tmp_path_factory.mktemp("service")
    with (
        Bus(robot.name, name="executive", endpoint=free_endpoint(), listen=True) as bus,
        KnowledgeBase(folder / "kb.db") as kb,
    ):
        yield Context(robot, bus, kb)


class Recorded(Service):
    """A service that writes each hook it runs to a shared log, and fails where told."""

    name = "recorded"

    def __init__(self, context: Context, name: str, log: list[str], fails: str = "") -> None:
        super().__init__(context)
        self.label, self.log, self.fails = name, log, fails

    def _hook(self, hook: str) -> None:
        self.log.append(f"{self.label}.{hook}")
        if hook == self.fails:
            raise ConfigError(f"{self.label} cannot {hook}")

    def on_configure(self) -> None:
        self._hook("configure")

    def on_activate(self) -> None:
        self._hook("activate")

    def on_deactivate(self) -> None:
        self._hook("deactivate")

    def on_shutdown(self) -> None:
        self._hook("shutdown")


class Later(Service):
    """A service whose activation completes when it is told to."""

    activates_later = True

    def __init__(self, context: Context) -> None:
        super().__init__(context)
        self.go = threading.Event()

    def on_activate(self) -> None:
        threading.Thread(target=lambda: self.go.wait(5) and self._activated()).start()


def test_a_service_is_configured_activated_and_shut_down_through_its_hooks(
    context: Context,
) -> None:
    log: list[str] = []
    service = Recorded(context, "a", log)
    assert service.state is ServiceState.UNCONFIGURED
    service.configure()
    assert service.state is ServiceState.INACTIVE
    service.activate()
    assert service.state is ServiceState.ACTIVE
    service.deactivate()
    service.activate()
    service.shutdown()  # from active: deactivated first
    assert service.state is ServiceState.FINALIZED
    assert log == [
        "a.configure", "a.activate", "a.deactivate", "a.activate", "a.deactivate", "a.shutdown"
    ]  # fmt: skip


def test_a_transition_the_state_does_not_allow_is_refused_loudly(context: Context) -> None:
    log: list[str] = []
    service = Recorded(context, "a", log)
    with pytest.raises(
        ServiceError, match=r"^the recorded service cannot activate while unconfigured$"
    ):
        service.activate()
    service.configure()
    with pytest.raises(ServiceError, match="cannot configure while inactive"):
        service.configure()
    with pytest.raises(ServiceError, match="cannot deactivate while inactive"):
        service.deactivate()
    service.shutdown()
    with pytest.raises(ServiceError, match="cannot shutdown while finalized"):
        service.shutdown()
    assert log == ["a.configure", "a.shutdown"]
    never = Recorded(context, "b", log)
    never.shutdown()  # nothing to release: no hook runs
    assert never.state is ServiceState.FINALIZED and log == ["a.configure", "a.shutdown"]


def test_a_hook_that_raises_leaves_the_service_in_error_and_shutdown_releases_it(
    context: Context,
) -> None:
    log: list[str] = []
    service = Recorded(context, "a", log, fails="activate")
    service.configure()
    with pytest.raises(ConfigError, match="a cannot activate"):
        service.activate()
    assert (service.state, service.reason) == (ServiceState.ERROR, "a cannot activate")
    assert not service.wait_for(ServiceState.ACTIVE, 5)  # at once: it never will be
    with pytest.raises(ServiceError, match=r"cannot activate while error \(a cannot activate\)"):
        service.activate()
    service.shutdown()  # what the half-done activation began, then the configuration
    assert log == ["a.configure", "a.activate", "a.deactivate", "a.shutdown"]
    assert service.state is ServiceState.FINALIZED


def test_a_failure_while_it_runs_is_an_error_its_listeners_are_told_of(context: Context) -> None:
    service = Recorded(context, "a", [])
    heard: list[str] = []
    service.add_failure_listener(lambda s: heard.append(s.reason))
    service.configure()
    service.activate()
    service.fail("the disk is full")
    service.fail("and then some")  # the first failure stands
    assert (service.state, service.reason) == (ServiceState.ERROR, "the disk is full")
    assert heard == ["the disk is full"]
    service.shutdown()
    service.fail("while gone")  # changes nothing
    assert service.state is ServiceState.FINALIZED and heard == ["the disk is full"]


def test_a_service_that_activates_later_is_activating_until_it_says_it_is_active(
    context: Context,
) -> None:
    service = Later(context)
    service.configure()
    service.activate()
    assert service.state is ServiceState.ACTIVATING
    assert not service.wait_for(ServiceState.ACTIVE, 0.1)
    service.go.set()
    assert service.wait_for(ServiceState.ACTIVE, 5)
    service.shutdown()


def test_a_service_that_defines_a_framework_method_is_refused() -> None:
    with pytest.raises(
        TypeError, match=r"^Old defines start\(\): override on_activate\(\) instead$"
    ):

        class Old(Service):
            def start(self) -> None:
                pass

    with pytest.raises(TypeError, match=r"^Sly defines wait_for\(\): it is the framework's$"):

        class Sly(Service):
            def wait_for(self) -> None:
                pass


def test_the_manager_configures_all_then_activates_all_and_stops_in_reverse(
    context: Context,
) -> None:
    log: list[str] = []
    said: list[str] = []
    services = [Recorded(context, name, log) for name in ("a", "b")]
    with LifecycleManager(services, progress=said.append):
        assert log == ["a.configure", "b.configure", "a.activate", "b.activate"]
    assert log[4:] == ["b.deactivate", "a.deactivate", "b.shutdown", "a.shutdown"]
    assert said == [
        "configuring the recorded service", "configuring the recorded service",
        "starting the recorded service", "starting the recorded service",
    ]  # fmt: skip


def test_services_added_later_are_configured_then_and_activate_in_their_place(
    context: Context,
) -> None:
    log: list[str] = []
    first, last = Recorded(context, "first", log), Recorded(context, "last", log)
    manager = LifecycleManager([first, last])
    manager.configure()  # what answers first, before the others are even built
    middle = [Recorded(context, name, log) for name in ("m1", "m2")]
    manager.add(middle, before=last)
    manager.configure()
    manager.activate()
    assert log == ["first.configure", "last.configure", "m1.configure", "m2.configure",
                   "first.activate", "m1.activate", "m2.activate", "last.activate"]  # fmt: skip
    manager.close()
    assert log[8:12] == ["last.deactivate", "m2.deactivate", "m1.deactivate", "first.deactivate"]


def test_a_service_that_cannot_configure_stops_the_start_and_everything_is_released(
    context: Context,
) -> None:
    log: list[str] = []
    services = [Recorded(context, "a", log), Recorded(context, "b", log, fails="configure")]
    services.append(Recorded(context, "c", log))
    with pytest.raises(ConfigError, match="b cannot configure"), LifecycleManager(services):
        pass
    assert log == ["a.configure", "b.configure", "b.shutdown", "a.shutdown"]
    assert {s.state for s in services} == {ServiceState.FINALIZED}


def test_a_service_that_fails_before_its_activation_stays_in_error_and_is_reported(
    context: Context,
) -> None:
    log: list[str] = []
    failures: list[str] = []
    first, second = Recorded(context, "a", log), Recorded(context, "b", log)
    manager = LifecycleManager([first, second], on_failure=failures.append)
    manager.configure()
    first.fail("the domain does not fit")
    manager.activate()
    assert failures == ["the domain does not fit"]
    assert (first.state, second.state) == (ServiceState.ERROR, ServiceState.ACTIVE)
    manager.close()
    manager.close()  # once is enough
    assert log == ["a.configure", "b.configure", "b.activate", "b.deactivate", "b.shutdown",
                   "a.shutdown"]  # fmt: skip
