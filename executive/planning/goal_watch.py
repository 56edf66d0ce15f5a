"""Goals that keep up with the world: when to look at an unreachable goal again, and
which maintenance goals stopped holding.

Pure bookkeeping for the goal planner's thread (:mod:`executive.planning.goal_planner`),
which does the looking:

- An unreachable goal is looked at again only after the world changed in a way the
  plan does not explain (a fact or object set, a sensed fact, a component reset or
  repaired), and not sooner than its interval after the last look. Each look doubles
  the interval (``first`` up to ``longest``), also one that re-posts the goal (it may
  be unreachable again together with the others), so a fact that flaps cannot make
  the planner spin: ten flaps a second cost one look at first, then one every 2, 4,
  ... 60 seconds.
- A maintenance goal (``keep``) that is achieved is watched: it is re-posted as soon
  as it stops holding, but not twice within ``repost_interval`` seconds (a noisy fact
  would pause the plan again and again); a later look catches it then.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

from executive.planning.expression import Expression, WorldState
from knowledge.records import Goal, GoalState

FIRST_INTERVAL = 1.0  # seconds before an unreachable goal is looked at again, at first
LONGEST_INTERVAL = 60.0  # the longest interval between two looks
REPOST_INTERVAL = 2.0  # seconds between two re-posts of one maintenance goal


@dataclass
class _Look:
    """When an unreachable goal may be looked at again (monotonic seconds)."""

    interval: float
    next: float = 0.0
    changed: bool = False  # the world changed since the last look


@dataclass
class GoalWatch:
    """When to look again at unreachable goals, and which kept goals broke."""

    first: float = FIRST_INTERVAL
    longest: float = LONGEST_INTERVAL
    repost_interval: float = REPOST_INTERVAL
    _looks: dict[int, _Look] = field(default_factory=dict)
    _reposted: dict[int, float] = field(default_factory=dict)  # goal -> when (monotonic)

    # --- unreachable goals -------------------------------------------------------------

    def world_changed(self, unreachable: Iterable[int]) -> None:
        """Note a change outside the plan: every unreachable goal may be looked at."""
        for goal_id in unreachable:
            self._looks.setdefault(goal_id, _Look(self.first)).changed = True

    def due(self, unreachable: Iterable[int], now: float) -> tuple[list[int], float | None]:
        """Return the unreachable goals to look at now, and when the next other one is due."""
        ids = set(unreachable)
        now_due: list[int] = []
        later: float | None = None
        for goal_id in sorted(ids):
            look = self._looks.get(goal_id)
            if look is None or not look.changed:
                continue
            if look.next <= now:
                now_due.append(goal_id)
            else:
                later = look.next if later is None else min(later, look.next)
        return now_due, later

    def looked(self, goal_id: int, now: float) -> None:
        """Note a finished look at a goal: the next waits for a change and twice as long."""
        look = self._looks.setdefault(goal_id, _Look(self.first))
        look.changed = False
        look.next = now + look.interval
        look.interval = min(self.longest, look.interval * 2)

    # --- maintenance goals -----------------------------------------------------------

    def broken(
        self, goals: Iterable[Goal], expressions: dict[int, Expression], state: WorldState
    ) -> list[Goal]:
        """Return the achieved maintenance goals that no longer hold in ``state``."""
        return [
            g
            for g in goals
            if g.keep
            and g.state is GoalState.ACHIEVED
            and g.id in expressions
            and not state.holds(expressions[g.id])
        ]

    def may_repost(self, goal_id: int, now: float) -> float | None:
        """Return ``None`` if a broken maintenance goal may be re-posted now, else when."""
        last = self._reposted.get(goal_id)
        if last is None or now - last >= self.repost_interval:
            return None
        return last + self.repost_interval

    def reposted(self, goal_id: int, now: float) -> None:
        """Note that a maintenance goal was re-posted."""
        self._reposted[goal_id] = now
