"""The component SDK: what a component author imports.

    from executive.sdk import Functionality, Behavior, GoalFailed

It owns the framework side of a component process (connecting to the bus, taking
lifecycle commands, rate loops, goals) and fault injection for tests. It may import
:mod:`executive.bus` and :mod:`knowledge`.
"""

from __future__ import annotations

from executive.bus.session import Message
from executive.sdk.component import Behavior, Functionality, GoalCancelled, GoalFailed
from executive.sdk.fault_injection import FaultMode

__all__ = ["Behavior", "FaultMode", "Functionality", "GoalCancelled", "GoalFailed", "Message"]
