"""Fleets: one temporal plan for several robots, each step run by the robot it names.

A fleet (``fleet.yaml``) has a domain with a type for robots and a list of robots,
each with its own ``dura run`` (task executor, components, monitoring, its own
integrity goals). ``dura fleet run fleet.yaml`` runs the fleet's high level — the
executive's own :class:`~executive.planning.high_level.HighLevel`, on the fleet's
domain, goals and knowledge base, served on the fleet's own bus for operators — and
runs each plan step on the task executor of the robot the step names, over that
robot's bus (the step port of :mod:`executive.bus.api.steps`), logged in as the
``fleet`` role (:mod:`executive.bus.security`). A robot whose executive vanishes, or
whose steps keep failing, is unavailable: no plan gives it a step
(:mod:`executive.planning.unavailable`) until it is back.

- :mod:`.description` — the fleet description as typed data, read with ``file:line``;
- :mod:`.validation` — the checks against the domain and each robot's description
  (``dura validate fleet.yaml``);
- :mod:`.robot_link` — one robot as the fleet reaches it: its bus session and its task
  executor as a runner of steps, and whether it is there;
- :mod:`.availability` — which robots can act now, and why the others cannot;
- :mod:`.robot_facts` — a robot's own facts (where it is, its battery) in the fleet's
  world;
- :mod:`.fleet_tasks` — the fleet's runner of steps: each step to its robot's link;
- :mod:`.fleet` — the fleet's process: its bus, knowledge base, links and high level.
"""
