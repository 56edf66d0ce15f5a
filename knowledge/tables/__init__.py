"""The knowledge base's tables, one module per group of tables.

:class:`knowledge.knowledge_base.KnowledgeBase` combines them into the one object every
service uses.

- :mod:`.database` — the SQLite connection, migrations and transactions, under the
  others;
- :mod:`.events` — the execution trace, an append-only log;
- :mod:`.goals_and_plans` — goals and plans, with the state machines of both;
- :mod:`.tasks` — tasks and their results;
- :mod:`.world` — PDDL objects and facts;
- :mod:`.components` — ratings, fault counters and permanent faults, achievements,
  return values and parameters of components.
"""
