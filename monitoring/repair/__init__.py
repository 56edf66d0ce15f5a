"""Repair rules (thesis 5.3, 6.3.4): what to do when observations and diagnoses say so.

It owns the rules, when each fired, and the actions running. Pure parts, testable
without processes, then the service:

- :mod:`.rule` — rules in the thesis schema, read from YAML with the line of every key;
- :mod:`.engine` with ``rules.lp`` — which rules fire, given the newest observations
  and diagnoses (windows and cool-downs in Python, the decision in clingo);
- :mod:`.action` — the extension point: an action, what it is told of the firing, and
  the registry of types (entry-point group ``dura.actions``);
- :mod:`.actions` — the built-in actions, one module each;
- :mod:`.rule_service` — the service: observations and diagnoses in from the bus,
  actions run on worker threads, firings logged in the knowledge base.

It may import :mod:`executive.bus` and :mod:`knowledge`.
"""
