"""``python -m executive.cli`` is ``dura``."""

from executive.cli import entry

entry()
