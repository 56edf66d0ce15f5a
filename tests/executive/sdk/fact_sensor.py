"""A component that changes the robot's world when it starts: it unsets the fact in its
parameter ``unset`` and sets the one in ``set``; with ``later`` (seconds), it sets the fact
in ``timed`` that many seconds from now, as a timed fact."""

from __future__ import annotations

import time

from executive.sdk import Functionality


class FactSensor(Functionality):
    def on_start(self) -> None:
        self.unset_fact(self.param("unset", "(photographable lab)"))
        self.set_fact(self.param("set", "(photographable lab)"))
        later = self.param("later", 0.0)
        if later:
            self.set_fact(self.param("timed", "(photographable dock)"), at=time.time() + later)


if __name__ == "__main__":
    FactSensor.main()
