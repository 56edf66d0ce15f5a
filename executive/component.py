"""Moved to :mod:`executive.sdk`: every name of this module is found there. It keeps working
with a DeprecationWarning naming the new place until dura 0.3.0 (:mod:`executive.moved`)."""

from __future__ import annotations

from executive.moved import forward

__getattr__ = forward(__name__)
