"""Fixtures of the monitoring tests: the runtime tests' (component processes import tests.*)."""

from tests.executive.conftest import tests_importable

__all__ = ["tests_importable"]
