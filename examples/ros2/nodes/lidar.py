"""A stand-in laser scanner: node ``/lidar`` publishes ``sensor_msgs/LaserScan`` on ``/scan``.

Parameters (``DURA_PARAMS``): ``rate`` (Hz, default 10). The service
``/lidar/inject_fault`` (``std_srvs/srv/Trigger``) makes it stop publishing while it
keeps running, as a driver whose device stopped answering: only dura's observers can
tell.
"""

from __future__ import annotations

import threading
from typing import Any

from . import interfaces as ros
from .rosnode import Node, now, params


class Lidar(Node):
    def __init__(self, domain_id: int | None = None, rate: float = 10.0) -> None:
        super().__init__("lidar", domain_id=domain_id)
        self.rate = rate
        self.stalled = threading.Event()
        self.scans = self.publisher("/scan", ros.LaserScan, reliable=False, depth=5)
        self.service("/lidar/inject_fault", ros.Trigger_Request, ros.Trigger_Response, self.stall)
        self._loop = threading.Thread(target=self._publish, daemon=True, name="scan")

    def start(self) -> None:
        super().start()
        self._loop.start()

    def stall(self, request: Any) -> dict[str, Any]:
        self.stalled.set()
        return {"success": True, "message": "the lidar stopped publishing"}

    def _publish(self) -> None:
        while not self._stop.wait(1.0 / self.rate):
            if not self.stalled.is_set():
                self.scans.write(ros.LaserScan(
                    header=ros.Header(stamp=now(), frame_id="laser"), angle_min=-1.57,
                    angle_max=1.57, angle_increment=0.785, scan_time=1.0 / self.rate,
                    range_min=0.1, range_max=10.0, ranges=[2.0, 2.5, 3.0, 2.5, 2.0],
                ))  # fmt: skip


def main() -> None:
    Lidar(rate=float(params().get("rate", 10.0))).run_until_stopped()


if __name__ == "__main__":
    main()
