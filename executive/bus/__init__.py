"""The bus: the bottom layer of the executive.

It owns the Zenoh session and what every service agrees on. It imports nothing of dura
but :mod:`knowledge`.

- :mod:`.session` — one Zenoh session under ``dura/<robot>/``: publish, subscribe,
  requests, liveliness, and waiting for a subscriber; :mod:`.message` — what travels on
  it: JSON objects within limits, and the :class:`~.message.Message` a handler gets;
  :mod:`.polled` — a subscription drained by its taker, arrivals on the taker's clock;
- :mod:`.security` — per-robot credentials and Zenoh's access control;
- :mod:`.keys` — the key expressions, and the environment of a component process;
- :mod:`.payloads` — what is published on those keys, as typed frozen dataclasses;
  :mod:`.reports` — the records services report (execution, planning, tasks, components,
  diagnoses);
- :mod:`.schema` — payload dataclasses read from JSON by their annotations;
- :mod:`.verb` — a request declared once: key, request and reply types;
  :mod:`.api` — each service's verbs, one module per service;
- :mod:`.states` — the states and verbs of components and their goals;
- :mod:`.event_kinds` — the kinds of event the knowledge base logs;
  :mod:`.event_text` — an event as one readable line; :mod:`.wording` — counts,
  numbers, durations and values as every view writes them;
- :mod:`.undecodable` — messages whose payload does not decode, counted per topic;
- :mod:`.clock` — robot time, possibly faster than the wall clock; :mod:`.timers` —
  every timer of a process on one thread (a step's timeout, a goal's deadline, a retry);
- :mod:`.topic_source` — topics whose messages do not travel on the bus (ROS 2's);
- :mod:`.service` — the executive's services and their one lifecycle (that of a ROS 2
  managed node), and what each gets (:class:`~.service.Context`);
  :mod:`.lifecycle_manager` — the driver of a process's services: configure and activate
  in order, deactivate and shut down in reverse;
- :mod:`.event_relay` — the events every process logs, on the bus for all and handed to
  the followers of each process;
- :mod:`.worker` — the one thread that touches an object's state; :mod:`.helpers` —
  reused threads for work that may wait (threaded requests, component starts).
"""

from __future__ import annotations

from executive.moved import forward_names

# ``executive.bus.Bus`` and ``executive.bus.Message``, documented before the bus became a
# package, keep working with a DeprecationWarning naming their new place.
__getattr__ = forward_names(__name__)
