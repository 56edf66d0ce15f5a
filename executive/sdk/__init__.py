"""The component SDK: what a component author imports.

    from executive.sdk import Functionality, Behavior, GoalFailed

An author subclasses :class:`Functionality` or :class:`Behavior` and overrides the
``on_*`` hooks (and ``execute``). It may import :mod:`executive.bus` and
:mod:`knowledge`.

- :mod:`.component` — what every component has: the ``on_*`` hooks and the helpers an
  author calls (publish, subscribe, parameters, facts, rates); :class:`Functionality`;
- :mod:`.behavior` — :class:`Behavior`: ``execute`` and its helpers;
- :mod:`.framework` — the framework side of a component process: lifecycle commands,
  the main loop (an author never calls it);
- :mod:`.goal` — a behavior's goals, one at a time, each on a thread of its own
  (:class:`GoalFailed`: impossible in the world, the planner plans again;
  :class:`GoalTimedOut`: a fault; :class:`GoalCancelled`);
- :mod:`.fault_injection` — a component made to misbehave on purpose, for tests.
"""

from __future__ import annotations

from executive.bus.message import Message
from executive.sdk.behavior import Behavior
from executive.sdk.component import Functionality, Rate
from executive.sdk.fault_injection import FaultMode
from executive.sdk.goal import GoalCancelled, GoalFailed, GoalTimedOut

__all__ = [
    "Behavior",
    "FaultMode",
    "Functionality",
    "GoalCancelled",
    "GoalFailed",
    "GoalTimedOut",
    "Message",
    "Rate",
]
