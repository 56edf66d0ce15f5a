"""The values the bus API leaves free-form, named once: what a component's or a
behavior's author decides, or what a user writes that its service reads itself. Every
other field of a request or reply is a typed record.

- :data:`Value` — one value a component's author chose: a parameter's, an
  achievement's, a fault option's;
- :data:`Params` — a component's parameters by name (the robot description's
  ``params``), and a behavior's achievements;
- :data:`GoalFields` — a behavior's goal, field by field;
- :data:`Result` — what a behavior returned (or why it failed);
- :data:`ObserverConfig` — an observer entry as written (the thesis/tug schema), read
  by the observer manager.

(An event's ``data`` is free-form too: :class:`knowledge.records.Event`.)
"""

from __future__ import annotations

from typing import Any, TypeAlias

Value: TypeAlias = Any
Params: TypeAlias = dict[str, Value]
GoalFields: TypeAlias = dict[str, Value]
Result: TypeAlias = Any
ObserverConfig: TypeAlias = Any
