"""The rule engine as a service: observations and diagnoses in, repair actions out.

Every observation and diagnosis on the bus is taken in and the rules are evaluated
at once; the actions of the rules that fire run on worker threads (each bounded by
its own timeout), so a slow or failing action never holds up the engine. Each firing
and each failed action is logged and written to the knowledge base's event log.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from executive.bus.keys import DIAGNOSES, OBSERVATIONS, host_alive
from executive.bus.message import Message
from executive.bus.payloads import DiagnosisInfo, ObservationInfo
from executive.bus.service import Context, Service
from knowledge.errors import BusError, DuraError
from monitoring.repair.action import ActionContext
from monitoring.repair.engine import Fired, RuleEngine
from monitoring.repair.rule import RuleSet, read_rules

log = logging.getLogger("dura.repair")


class RuleService(Service):
    """Runs the robot's repair rules (``rules:`` of the robot description).

    Args:
        context: robot, bus and knowledge base.
        rule_sets: the rules (default: read the robot's rules files).
        workers: actions that may run at the same time.

    Raises:
        ConfigError, AspError: a rules file is invalid.
    """

    name = "rules"

    def __init__(
        self, context: Context, rule_sets: list[RuleSet] | None = None, *, workers: int = 4
    ) -> None:
        super().__init__(context)
        if rule_sets is None:
            rule_sets = [read_rules(path) for path in context.robot.rules]
        self.engine = RuleEngine(rule_sets)
        self._actions = ActionContext(context.bus, context.robot.path.parent)
        self._lock = threading.Lock()
        self._workers = workers
        self._pool: ThreadPoolExecutor | None = None
        self._entities: list[Any] = []
        self._hosts: set[str] = set()  # the host agents there now

    def on_activate(self) -> None:
        self._pool = ThreadPoolExecutor(max_workers=self._workers, thread_name_prefix="dura-repair")
        bus = self.context.bus
        self._entities = [
            bus.subscribe(OBSERVATIONS, self._on_observation),
            bus.subscribe(DIAGNOSES, self._on_diagnosis),
        ]
        if self.context.robot.hosts:
            self._entities.append(bus.watch_alive(host_alive("*"), self._on_host))

    def _on_host(self, key: str, alive: bool) -> None:
        name = key.rsplit("/", 1)[-1]
        with self._lock:
            (self._hosts.add if alive else self._hosts.discard)(name)

    def unavailable(self) -> frozenset[str]:
        """The components placed on hosts whose agents are not there: a diagnosis of
        them is their host's absence, not a fault to repair."""
        return frozenset(
            name
            for name, spec in self.context.robot.components.items()
            if spec.host is not None and spec.host not in self._hosts
        )

    def on_deactivate(self) -> None:
        for entity in self._entities:
            entity.undeclare()
        self._entities = []
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def _on_observation(self, message: Message) -> None:
        try:
            info = ObservationInfo.from_payload(message.payload)
        except (KeyError, ValueError, TypeError) as e:
            raise BusError(f"malformed observation: {e}") from e
        self._take(lambda: self.engine.observe(info))

    def _on_diagnosis(self, message: Message) -> None:
        try:
            diagnosis = DiagnosisInfo.from_payload(message.payload)
        except (KeyError, ValueError, TypeError) as e:
            raise BusError(f"malformed diagnosis: {e}") from e
        self._take(lambda: self.engine.diagnosed(diagnosis))

    def _take(self, feed: Callable[[], None]) -> None:
        """Feed the engine one message, evaluate, and start the actions that fire."""
        with self._lock:
            feed()
            self._act_on(self.engine.evaluate())

    def _act_on(self, fired: list[Fired]) -> None:
        pool = self._pool
        unavailable = self.unavailable()
        for item in fired:
            faulty = set(item.firing.faulty)
            if faulty and faulty <= unavailable:
                log.info("rule '%s' not run: %s unavailable (their host is not there)",
                         item.rule.name, ", ".join(sorted(faulty)))  # fmt: skip
                continue
            log.info("rule '%s' fired: %s", item.rule.name, item.rule.action.describe())
            self.context.kb.log_event(
                "RULE_FIRED",
                item.rule.name,
                {"action": item.rule.action.describe(), "faulty": list(item.firing.faulty)},
            )
            if pool is not None:
                pool.submit(self._run, item)

    def _run(self, item: Fired) -> None:
        try:
            item.rule.action.run(self._actions, item.firing)
        except (DuraError, OSError) as e:
            log.warning("action of rule '%s' failed: %s", item.rule.name, e)
            self.context.kb.log_event("RULE_FAILED", item.rule.name, {"error": str(e)})
        except Exception as e:  # an action (or plugin) fails in its own way; the engine goes on
            log.exception("action of rule '%s' failed", item.rule.name)
            self.context.kb.log_event("RULE_FAILED", item.rule.name, {"error": repr(e)})
