"""The high level (thesis 5.1.2): goals, plans and their execution.

It owns the goals and plans. It may import :mod:`executive.bus` and :mod:`knowledge`;
it never imports the task executor (steps run through the
:class:`~executive.planning.task_runner.TaskRunner` port).

- :mod:`.high_level` — the service: a small shell over :mod:`.warm_up` (the planner
  loads the domain in the background), :mod:`.goal_api` and :mod:`.world_api` (the verbs
  of :mod:`executive.bus.api.planning`) and :mod:`.deliberation` (the parts below at
  work: goal planner, plan executor, integrity goals with :mod:`.integrity_loop` and
  :mod:`.blocked_tasks`, sensing);
- :mod:`.goals` — goals as the planner reads them (:class:`~.goals.Refusal` for the rest);
- :mod:`.goal_planner` — planning rounds; the one writer of goal and plan states
  (:mod:`.goal_keeper` and :mod:`.goal_watch`: unreachable goals looked at again,
  maintenance goals re-posted, when the world changes);
- :mod:`.oversubscription` — the best subset of goals by priority, and why the others
  are unreachable (:mod:`.reachability`: what no action can make true);
- :mod:`.planner` (client), :mod:`.planner_worker` (process) and :mod:`.planner_jobs`
  (its jobs, with unified-planning) — the engines; :mod:`.engine_choice` — which
  engine supports a problem (``auto``), or why none does; :mod:`.portfolio` — several
  engines at once;
- :mod:`.problem` — unified-planning problems from the domain and the knowledge base
  (with timed facts); :mod:`.metric` — what a plan optimises; :mod:`.unavailable` —
  objects that cannot act now (a fleet's lost robots) left out of every step;
- :mod:`.expression` — ground PDDL expressions: nodes, evaluation, reading; names and
  fact patterns;
- :mod:`.stn`, :mod:`.partial_order` — plans as partial orders of steps;
- :mod:`.plan_executor` — runs a plan (:mod:`.plan_run` its steps, :mod:`.step_run` one
  step, :mod:`.task_runner` the port, :mod:`.state_change` what it reports,
  :mod:`.recovery` after a crash, :mod:`.look_ahead` the rest of the plan checked when
  facts change; :mod:`.bus_tasks` the port over the bus, for ``dura run --only
  planning``);
- :mod:`.integrity` — goals that keep the robot going;
- :mod:`.sensing` — facts and values kept in step with topics (the ``sensing:`` rules);
  :mod:`.timed_facts` — facts that take effect later, applied when their time comes;
- :mod:`.dry_run` — what the planner would do now; :mod:`.domain_check` — diagnostics
  for domain authors; :mod:`.domain_description` — the domain as ``dura domain show``
  gives it.
"""
