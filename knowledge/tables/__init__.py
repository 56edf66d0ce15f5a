"""The knowledge base's tables, one module per group of tables.

:mod:`.database` owns the SQLite connection, migrations and transactions; each other
module adds the typed methods of one group of tables on top of it: :mod:`.events` (the
execution trace), :mod:`.goals` (goals and plans), :mod:`.tasks`, :mod:`.world` (PDDL
objects and facts) and :mod:`.components` (components, faults, achievements, return
values, parameters). :class:`knowledge.knowledge_base.KnowledgeBase` combines them into
the one object every service uses.
"""
