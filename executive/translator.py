"""Moved to :mod:`executive.runtime.translator`: every name of this module is found there,
and ``python -m executive.translator`` still runs a translator. It keeps working with a
DeprecationWarning naming the new place until dura 0.3.0 (:mod:`executive.moved`)."""

from __future__ import annotations

from executive.moved import forward, resolve, warn

__getattr__ = forward("executive.translator")

if __name__ == "__main__":
    warn("python -m executive.translator", "python -m executive.runtime.translator", 2)
    resolve("executive.runtime.translator.main")()
