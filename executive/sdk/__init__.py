"""The component SDK: what a component author imports.

    from executive.sdk import Functionality, Behavior, GoalFailed

An author subclasses :class:`Functionality` or :class:`Behavior` and overrides the
``on_*`` hooks (and ``execute``); :mod:`.component` and :mod:`.behavior` hold those and
the helpers an author calls. The framework side of a component process (taking
lifecycle commands, the main loop, running goals) is :mod:`.framework` and
:mod:`.goal`; fault injection for tests is :mod:`.fault_injection`. It may import
:mod:`executive.bus` and :mod:`knowledge`.
"""

from __future__ import annotations

from executive.bus.session import Message
from executive.sdk.behavior import Behavior
from executive.sdk.component import Functionality, Rate
from executive.sdk.fault_injection import FaultMode
from executive.sdk.goal import GoalCancelled, GoalFailed

__all__ = [
    "Behavior",
    "FaultMode",
    "Functionality",
    "GoalCancelled",
    "GoalFailed",
    "Message",
    "Rate",
]
