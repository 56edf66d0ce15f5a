"""A scripted component for SDK and launcher tests: it reports what happens to it.

Every hook publishes ``{"component", "hook", ...}`` on ``topic/probe/hooks``; while
running it publishes ``topic/probe/tick`` at ``rate`` Hz. Parameters: ``rate`` (20),
``explode`` (an exception in the rate loop), ``say`` (a line printed at configure).
"""

from __future__ import annotations

import os
from typing import Any

from executive.bus import keys
from executive.sdk import Functionality

ENVIRONMENT = (
    keys.ENV_ROBOT,
    keys.ENV_COMPONENT,
    keys.ENV_ENDPOINT,
    keys.ENV_KIND,
    keys.ENV_INSTANCE,
)


class Probe(Functionality):
    def report(self, hook: str, **data: Any) -> None:
        self.bus.publish(keys.topic("probe/hooks"), {"component": self.name, "hook": hook, **data})

    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        print(self.param("say", f"probe {self.name} configured"), flush=True)
        self.report("configure", params=params, achievements=achievements)

    def on_start(self) -> None:
        self.report(
            "start",
            pid=os.getpid(),
            pgid=os.getpgid(0),
            env={k: os.environ.get(k) for k in ENVIRONMENT},
        )
        self.at_rate(
            self.param("rate", 20.0), self.explode if self.param("explode", False) else self.tick
        )

    def tick(self) -> None:
        self.publish("probe/tick", {})

    def explode(self) -> None:
        raise RuntimeError("the probe explodes")

    def on_pause(self) -> None:
        self.report("pause")

    def on_resume(self) -> None:
        self.report("resume")

    def on_reconfigure(self, params: dict[str, Any]) -> None:
        self.report("reconfigure", params=params)

    def on_stop(self) -> None:
        self.report("stop")


if __name__ == "__main__":
    Probe.main()
