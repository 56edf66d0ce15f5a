"""A simulated camera: a small stamped image summary at ``rate`` Hz (default 15)."""

from __future__ import annotations

import math
from typing import Any

from executive.sdk import FaultMode, Functionality

WIDTH, HEIGHT = 64, 48


class Cam(Functionality):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.rate = self.param("rate", 15.0)
        self.seq = 0

    def on_start(self) -> None:
        self.at_rate(self.rate, self.capture)

    def capture(self) -> None:
        self.seq += 1
        brightness = round(128 + 60 * math.sin(self.seq * 0.1), 2)  # 0..255
        if self.faults.active(FaultMode.OUT_OF_RANGE):
            brightness = -1.0
        self.publish(
            "image",
            {
                "seq": self.seq,
                "width": WIDTH,
                "height": HEIGHT,
                "encoding": "mono8",
                "brightness": brightness,
            },
        )


def main() -> None:
    Cam.main()


if __name__ == "__main__":
    main()
