"""Each service's bus API, declared once (one module per service).

- :mod:`.planning` — goals, plans, the world's facts and objects, events, status (the
  high level);
- :mod:`.tasks` — tasks, the schedule, faults and resets of components (the task
  executor);
- :mod:`.components` — component processes: list, start, stop, logs, achievements (the
  launcher);
- :mod:`.component_commands` — the lifecycle commands each component process serves
  (the launcher sends them, the SDK answers);
- :mod:`.hosts` — component processes on another computer: started, signalled, their
  logs read (a host agent serves them, the launcher calls them);
- :mod:`.parameters` — component parameters at run time (the task executor);
- :mod:`.monitoring` — observers at run time and the diagnosis model;
- :mod:`.steps` — plan steps run on the task executor for a high level in another
  process (the task executor's side serves them);
- :mod:`.free_form` — the few values left free-form (what a component's author
  decides: parameters, a behavior's goal and result; an observer entry as written).

A declaration is a :class:`~executive.bus.verb.Verb`: its key, its request and reply
types (:class:`~executive.bus.schema.Payload` dataclasses) and how long a caller waits.
Replies carry typed records (:mod:`knowledge.records`, :mod:`executive.bus.reports`).
The services serve them, and the CLI, the test harness, the dashboard, the rule engine
and the component SDK call them, through these constants.
"""
