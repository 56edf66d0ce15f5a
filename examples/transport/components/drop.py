"""Puts the crate down: opens the gripper."""

from __future__ import annotations

from components.grip import GripAction


class Drop(GripAction):
    close = False


def main() -> None:
    Drop.main()


if __name__ == "__main__":
    main()
