"""Picks up a crate: closes the gripper on it."""

from __future__ import annotations

from components.grip import GripAction


class Pick(GripAction):
    close = True


def main() -> None:
    Pick.main()


if __name__ == "__main__":
    main()
