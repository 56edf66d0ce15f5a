"""Turns ``image`` into a lidar-like ``scan_filtered`` (the alternative to lidar + filter).

The scan keeps the stamp of the image it came from.
"""

from __future__ import annotations

from components.scan import BEAMS, OUT_OF_RANGE, clip, scan
from executive.sdk import FaultMode, Functionality, Message


class CamToLidar(Functionality):
    def on_start(self) -> None:
        self.subscribe("image", self.convert)

    def convert(self, message: Message) -> None:
        brightness = message.payload.get("brightness")
        if not isinstance(brightness, (int, float)):
            self.log.warning("image without a brightness dropped")
            return
        distance = OUT_OF_RANGE
        if not self.faults.active(FaultMode.OUT_OF_RANGE):
            distance = clip(1.0 + float(brightness) / 64.0)  # brighter is farther
        self.publish(
            "scan_filtered", scan(message.payload.get("seq", 0), [distance] * BEAMS, message.stamp)
        )


def main() -> None:
    CamToLidar.main()


if __name__ == "__main__":
    main()
