"""dura's executive: high level, task executor, runtime, bus and CLI."""

from __future__ import annotations

__version__ = "0.1.0"
