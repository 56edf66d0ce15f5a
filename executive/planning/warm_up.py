"""The high level's warm-up, in the background: the planner worker loads
unified-planning and parses the domain (the executive process itself never imports
unified-planning), the robot's tasks are checked against the domain, the robot's initial
world is loaded into an empty knowledge base, and the integrity rules are read.

One small state machine with one condition variable::

    LOADING --> WARM      the domain is there; who waits for it goes on
    LOADING --> FAILED    the domain does not fit the robot, or the planner did not start
    any     --> STOPPED   stopped (a failure while stopping is no failure)
"""

from __future__ import annotations

import enum
import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass

from executive.planning.integrity import IntegrityRule, read_rules
from executive.planning.planner import Planner
from executive.planning.problem import seed
from knowledge.description import RobotDescription
from knowledge.domain import DomainInfo
from knowledge.errors import ConfigError, DuraError
from knowledge.knowledge_base import KnowledgeBase

log = logging.getLogger("dura.high_level")


class WarmUpState(enum.Enum):
    LOADING = "loading"
    WARM = "warm"
    FAILED = "failed"
    STOPPED = "stopped"


@dataclass(frozen=True)
class Warm:
    """What the warm-up found: the domain's signatures and the integrity rules."""

    domain: DomainInfo
    rules: tuple[IntegrityRule, ...]


class WarmUp:
    """Warms the planner up on a thread of its own (see the module docstring).

    Args:
        robot: its domain, problem, tasks and integrity rules.
        kb: where the initial world goes, if it holds none.
        planner: the planner whose worker loads the domain.
        on_failure: called (on the warm-up's thread) with the one-line reason when the
            warm-up fails.
    """

    def __init__(
        self,
        robot: RobotDescription,
        kb: KnowledgeBase,
        planner: Planner,
        *,
        on_failure: Callable[[str], None],
    ) -> None:
        self.robot = robot
        self.kb = kb
        self.planner = planner
        self.on_failure = on_failure
        self._changed = threading.Condition()
        self._state = WarmUpState.LOADING
        self._warm: Warm | None = None
        self._has_world = False  # the knowledge base held a world before the warm-up
        self._waiting: list[Callable[[Warm], None]] = []  # told once it is warm
        self._thread = threading.Thread(target=self._run, name="high-level warm-up", daemon=True)

    @property
    def state(self) -> WarmUpState:
        return self._state

    @property
    def warm(self) -> Warm | None:
        """What the warm-up found, once it is warm (``None`` until then)."""
        return self._warm

    def start(self) -> None:
        """Begin in the background."""
        kb = self.kb
        self._has_world = self.robot.problem is None or bool(kb.objects() or kb.facts())
        self._thread.start()

    def stop(self) -> None:
        """Stop: a domain still loading is given up (its worker killed)."""
        with self._changed:
            loading = self._state is WarmUpState.LOADING
            self._state = WarmUpState.STOPPED
            self._waiting.clear()
            self._changed.notify_all()
        if self._thread.is_alive():
            if loading:
                self.planner.interrupt()  # the warm-up waits for the worker: end it now
            self._thread.join()

    def when_warm(self, then: Callable[[Warm], None]) -> None:
        """Call ``then`` once warm: now (on this thread) if it is, else on the warm-up's
        thread when it is; never if it fails or stops first."""
        with self._changed:
            if self._state is WarmUpState.LOADING:
                self._waiting.append(then)
                return
            warm = self._warm if self._state is WarmUpState.WARM else None
        if warm is not None:
            then(warm)

    def wait_for_world(self, timeout: float) -> None:
        """Wait (bounded) until the knowledge base holds the robot's world (a new robot's
        comes with the domain), or the warm-up ended without it."""
        with self._changed:
            self._changed.wait_for(
                lambda: self._has_world or self._state is not WarmUpState.LOADING, timeout
            )

    def _run(self) -> None:
        try:
            warm = self._load()
        except DuraError as e:
            self._fail(str(e))
            return
        except Exception as e:  # a bug: say so, rather than leave goals waiting
            if self._state is WarmUpState.LOADING:
                log.exception("the high level's warm-up failed")
            self._fail(f"the planner's start failed: {type(e).__name__}: {e}")
            return
        with self._changed:
            if self._state is not WarmUpState.LOADING:
                return  # stopped meanwhile
            self._state, self._warm = WarmUpState.WARM, warm
            waiting, self._waiting = self._waiting, []
            self._changed.notify_all()
        for then in waiting:
            then(warm)

    def _load(self) -> Warm:
        """Load the domain in the planner worker, check the robot against it, seed the
        world, read the integrity rules."""
        from knowledge.validation import check_domain  # on the warm-up thread, not at start

        robot, kb = self.robot, self.kb
        self.planner.start()
        domain = self.planner.describe(robot.domain)
        world = None
        if robot.problem is not None:
            world = self.planner.read_world(robot.domain, robot.problem)
        objects = world.objects if world is not None else {}
        errors = [f for f in check_domain(robot, domain, objects) if f.is_error]
        if errors:
            raise ConfigError(str(errors[0]))
        if world is not None and robot.problem is not None and not (kb.objects() or kb.facts()):
            seed(kb, world, robot.problem)
        rules: list[IntegrityRule] = []
        for path in robot.integrity:
            rules.extend(read_rules(path, robot, domain, kb.objects()))
        return Warm(domain, tuple(rules))

    def _fail(self, reason: str) -> None:
        with self._changed:
            if self._state is not WarmUpState.LOADING:
                return  # stopped: the planner was interrupted
            self._state = WarmUpState.FAILED
            self._waiting.clear()
            self._changed.notify_all()
        self.on_failure(reason)
