"""A simulated lidar: a stamped scan at ``rate`` Hz (default 10), which may change while
it runs (``dura param set lidar rate 5``)."""

from __future__ import annotations

import math
from typing import Any

from components.scan import BEAMS, OUT_OF_RANGE, scan
from executive.sdk import FaultMode, Functionality, Rate


class Lidar(Functionality):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.rate = self.param("rate", 10.0)
        self.seq = 0
        self.loop: Rate | None = None

    def on_start(self) -> None:
        self.loop = self.at_rate(self.rate, self.scan)

    def on_reconfigure(self, params: dict[str, Any]) -> None:
        self.rate = self.param("rate", 10.0)  # the new rate, from the next scan on
        if self.loop is not None:
            self.loop.hz = self.rate

    def scan(self) -> None:
        self.seq += 1
        if self.faults.active(FaultMode.OUT_OF_RANGE):
            ranges = [OUT_OF_RANGE] * BEAMS
        else:  # a wall that slowly comes and goes
            ranges = [round(2.0 + math.sin(i * 0.2 + self.seq * 0.05), 3) for i in range(BEAMS)]
        self.publish("scan", scan(self.seq, ranges))


def main() -> None:
    Lidar.main()


if __name__ == "__main__":
    main()
