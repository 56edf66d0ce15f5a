"""A process that writes to a knowledge base until it is killed (for the crash test).

Each iteration is one transaction (a goal, a fact, a fault and an event); after
the commit it prints the goal's id, so the parent knows what was committed.
"""

from __future__ import annotations

import sys

from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact


def main() -> None:
    kb = KnowledgeBase(sys.argv[1])
    kb.register_component("lidar", 10)
    i = 0
    while True:
        i += 1
        with kb.transaction():
            goal = kb.add_goal(f"(picture_taken p{i})", priority=i % 5)
            kb.set_fact(Fact("visited", (f"p{i}",)))
            kb.record_fault("lidar", f"fault {i}", max_faults=10**9)
            kb.log_event("TICK", "writer", {"i": i})
        print(goal.id, flush=True)


if __name__ == "__main__":
    main()
