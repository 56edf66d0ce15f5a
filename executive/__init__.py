"""dura's executive: high level, task executor, runtime, bus and CLI.

Its packages are layers: an upper one imports a lower one, never the reverse
(``docs/explanation/architecture.md`` says which may import which;
``tests/test_layers.py`` checks).

- :mod:`.bus` — the bottom layer: the Zenoh session, keys, payloads, each service's API
  declared once;
- :mod:`.sdk` — what a component author imports;
- :mod:`.ros2` — ROS 2 over DDS;
- :mod:`.bags` — recordings: ROS 2 bags and dura's MCAP files, read and written;
  :mod:`.bag_replay` — a recording routed to a robot's monitoring, ready to replay
  (``dura replay``, the ``dura_replay`` fixture);
- :mod:`.runtime` — component processes: the launcher, host agents, translators;
- :mod:`.tasks` — the task executor;
- :mod:`.planning` — the high level: goals, plans and their execution;
- :mod:`.fleet` — fleets: one plan for several robots, each step run by its own robot
  (``dura fleet run``), over the high level of :mod:`.planning`;
- :mod:`.dashboard` — the live web page and the pictures;
- :mod:`.testing` — the pytest fixtures and the robot harness;
- :mod:`.executive` — the composition root: the executive process, and a group of its
  services in a process of its own; :mod:`.service_groups` — one builder per group of
  services, used by both;
- :mod:`.cli` — the ``dura`` command;
- :mod:`.lsp` — ``dura lsp``, the language server for PDDL, robot descriptions and rules;
- :mod:`.fast_start` — every trick that makes dura's processes start fast, measured (it
  imports nothing of dura: the command line and the planner worker both use it);
- :mod:`.moved` — the names of the documented API that moved, forwarded to their new
  place with a DeprecationWarning: :mod:`.component` (now :mod:`executive.sdk`),
  :mod:`.harness` (:mod:`executive.testing.harness`), :mod:`.launcher` and
  :mod:`.translator` (in :mod:`executive.runtime`), ``executive.bus.Bus`` and
  ``executive.bus.Message``.

Beside it, :mod:`monitoring` sits on the bus and :mod:`knowledge` under everything.
"""

from __future__ import annotations

__version__ = "0.2.0"
