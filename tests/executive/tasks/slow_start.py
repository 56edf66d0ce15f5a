"""A scripted functionality that takes ``delay`` seconds (parameter, default 3) to
configure, as a driver that waits for its hardware does; it then provides the camera's
``image`` topic."""

from __future__ import annotations

import time
from typing import Any

from tests.executive.runtime.probe import Probe


class SlowStart(Probe):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        time.sleep(float(self.param("delay", 3.0)))
        super().on_configure(params, achievements)

    def tick(self) -> None:
        self.publish("image", {})


if __name__ == "__main__":
    SlowStart.main()
