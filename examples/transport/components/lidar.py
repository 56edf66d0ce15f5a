"""A simulated lidar: eight beams around the robot at ``rate`` Hz (default 10)."""

from __future__ import annotations

import random
from typing import Any

from executive.sdk import Functionality


class Lidar(Functionality):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.rate = self.param("rate", 10.0)
        self.seq = 0

    def on_start(self) -> None:
        self.at_rate(self.rate, self.scan)

    def scan(self) -> None:
        self.seq += 1
        ranges = [round(1.5 + random.uniform(-0.05, 0.05), 3) for _ in range(8)]
        self.publish("scan", {"seq": self.seq, "ranges": ranges})


def main() -> None:
    Lidar.main()


if __name__ == "__main__":
    main()
