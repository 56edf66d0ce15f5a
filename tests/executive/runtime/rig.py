"""What runtime tests share: robots made of chosen components, a launcher on a real bus
and KB, and recorders of bus messages."""

from __future__ import annotations

import contextlib
import dataclasses
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import psutil

from executive.bus.keys import EXECUTIVE_ALIVE, component
from executive.bus.message import Message
from executive.bus.payloads import ComponentState
from executive.bus.session import Bus
from executive.runtime.launcher import Launcher
from knowledge.description import BehaviorSpec, ComponentSpec, FunctionalitySpec, RobotDescription
from knowledge.knowledge_base import KnowledgeBase
from knowledge.robot import read_robot
from tests.conftest import USECASE, wait_for

_read, _ = read_robot(USECASE)
assert _read is not None
USECASE_ROBOT: RobotDescription = _read


def usecase(name: str, **changes: Any) -> ComponentSpec:
    """A use-case component, with changed fields (``params=...``)."""
    return dataclasses.replace(USECASE_ROBOT.components[name], **changes)


def scripted(
    name: str, module: str, *args: str, behavior: bool = False, **fields: Any
) -> ComponentSpec:
    """A component running ``python -m module args...`` (``tests.*`` needs PYTHONPATH)."""
    kind = BehaviorSpec if behavior else FunctionalitySpec
    return kind(name=name, command=("python", "-m", module, *args), **fields)


def robot(*components: ComponentSpec, name: str = "testbot") -> RobotDescription:
    """A robot of these components, run in the use case's folder (so they import)."""
    return dataclasses.replace(
        USECASE_ROBOT,
        name=name,
        functionalities={c.name: c for c in components if isinstance(c, FunctionalitySpec)},
        behaviors={c.name: c for c in components if isinstance(c, BehaviorSpec)},
        tasks={},
    )


class Recorder:
    """Collects the messages on one key, thread-safely."""

    def __init__(self, bus: Bus, key: str) -> None:
        self._messages: list[Message] = []
        self._lock = threading.Lock()
        bus.subscribe(key, self._add)

    def _add(self, message: Message) -> None:
        with self._lock:
            self._messages.append(message)

    @property
    def messages(self) -> list[Message]:
        with self._lock:
            return list(self._messages)

    @property
    def payloads(self) -> list[dict[str, Any]]:
        return [m.payload for m in self.messages]

    def clear(self) -> None:
        with self._lock:
            self._messages.clear()

    def wait(self, predicate: Callable[[dict[str, Any]], bool], timeout: float = 30.0) -> bool:
        """Wait for a message whose payload satisfies ``predicate``."""
        return wait_for(lambda: any(predicate(p) for p in self.payloads), timeout)

    def count(self) -> int:
        return len(self.messages)


def states(recorder: Recorder, name: str) -> list[str]:
    """The states a component went through, from its state messages."""
    return [
        ComponentState.from_payload(p).state.value
        for p in recorder.payloads
        if p.get("component") == name
    ]


@dataclass
class Rig:
    launcher: Launcher
    bus: Bus
    kb: KnowledgeBase
    robot: RobotDescription
    states: Recorder
    others: frozenset[psutil.Process]  # child processes that were there before the rig

    def children(self) -> set[psutil.Process]:
        """The child processes of this test that the rig's launcher started (and not
        yet reaped): another test's leftovers are not its to judge."""
        return set(psutil.Process().children(recursive=True)) - self.others


@contextlib.contextmanager
def rig(
    robot: RobotDescription, endpoint: str, folder: Path, *, grace: float = 1.0
) -> Iterator[Rig]:
    """A launcher on a real, listening bus (with the executive's token) and a real KB.

    Leaving it stops every component; it fails if any child process it started is left
    (a process that was there before, another test's, is not its to judge).
    """
    others = frozenset(psutil.Process().children(recursive=True))
    with (
        Bus(robot.name, name="executive", endpoint=endpoint, listen=True) as bus,
        KnowledgeBase(folder / "kb.db") as kb,
    ):
        bus.declare_alive(EXECUTIVE_ALIVE)
        recorder = Recorder(bus, component("*", "state"))
        with Launcher(robot, bus, kb, log_dir=folder / "logs", grace=grace) as launcher:
            made = Rig(launcher, bus, kb, robot, recorder, others)
            yield made
    leftovers = list(made.children())
    for child in leftovers:
        with contextlib.suppress(psutil.NoSuchProcess):
            child.kill()
    assert not leftovers, f"processes left behind: {leftovers}"
