"""The built-in observer types, one module each (see :mod:`monitoring.observer`).

- :mod:`.component` (alias ``activated``) — are the nodes running?
- :mod:`.resources` — CPU and memory of nodes, from the resource monitor;
- :mod:`.frequency` (alias ``hz``) — how often a topic's publishers send;
- :mod:`.timeout` — a watchdog on a topic;
- :mod:`.timestamp` — how old messages are when they arrive;
- :mod:`.timing` — the delay from a message on one topic to the next on another;
- :mod:`.scores` (alias ``value``) — a numeric field of a topic's messages;
- :mod:`.movement` (alias ``velocity``) — two motion sources that must agree.
"""
