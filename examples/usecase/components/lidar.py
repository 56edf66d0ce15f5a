"""A simulated lidar: a stamped scan at ``rate`` Hz (default 10)."""

from __future__ import annotations

import math
from typing import Any

from components.scan import BEAMS, OUT_OF_RANGE, scan
from executive.sdk import FaultMode, Functionality


class Lidar(Functionality):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.rate = self.param("rate", 10.0)
        self.seq = 0

    def on_start(self) -> None:
        self.at_rate(self.rate, self.scan)

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
