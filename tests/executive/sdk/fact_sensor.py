"""A component that changes the robot's world when it starts: it unsets the fact in its
parameter ``unset`` and sets the one in ``set``."""

from __future__ import annotations

from executive.sdk import Functionality


class FactSensor(Functionality):
    def on_start(self) -> None:
        self.unset_fact(self.param("unset", "(photographable lab)"))
        self.set_fact(self.param("set", "(photographable lab)"))


if __name__ == "__main__":
    FactSensor.main()
