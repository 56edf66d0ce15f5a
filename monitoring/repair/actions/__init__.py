"""The built-in repair actions, one module per rule ``type`` (see
:mod:`monitoring.repair.action`).

- :mod:`.restart` — restart a component through the task executor (a fault of it);
- :mod:`.fault` — mark a component faulty through the task executor;
- :mod:`.logentry` — write a line to a log file, or to dura's log (``log``);
- :mod:`.mail` — send a mail over SMTP;
- :mod:`.process` — run a process from an argv list, never through a shell;
- :mod:`.command` — send a command (any verb) to the executive;
- :mod:`.parameter` — change a parameter of a component;
- :mod:`.goal` — post a goal to the goal planner;
- :mod:`.executive` — what the actions that ask the executive share: one bus request.
"""
