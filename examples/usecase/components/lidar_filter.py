"""Filters ``scan`` into ``scan_filtered``: clipped to the sensor's range, median of three.

The filtered scan keeps the stamp of the scan it came from.
"""

from __future__ import annotations

from components.scan import BEAMS, OUT_OF_RANGE, clip, scan
from executive.sdk import FaultMode, Functionality, Message


def median3(values: list[float]) -> list[float]:
    """Each value replaced by the median of itself and its neighbours."""
    out = []
    for i in range(len(values)):
        window = sorted(values[max(0, i - 1) : i + 2])
        out.append(window[len(window) // 2])
    return out


class LidarFilter(Functionality):
    def on_start(self) -> None:
        self.subscribe("scan", self.filter)

    def filter(self, message: Message) -> None:
        raw = message.payload.get("ranges")
        if not isinstance(raw, list) or not all(isinstance(r, (int, float)) for r in raw):
            self.log.warning("scan without a list of ranges dropped")
            return
        if self.faults.active(FaultMode.OUT_OF_RANGE):
            ranges = [OUT_OF_RANGE] * BEAMS
        else:
            ranges = median3([clip(float(r)) for r in raw])
        seq = message.payload.get("seq", 0)
        self.publish("scan_filtered", scan(seq, ranges, message.stamp))


def main() -> None:
    LidarFilter.main()


if __name__ == "__main__":
    main()
