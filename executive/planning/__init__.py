"""The high level (thesis 5.1.2): goals, plans and their execution.

It owns the goals and plans: the goal planner, oversubscription, planner engines in
their worker process, problem building, PDDL expressions, partial-order plans, the
plan executer and integrity goals. It may import :mod:`executive.bus` and
:mod:`knowledge`; it never imports the task executor (steps run through the
:class:`~executive.planning.plan_executer.TaskRunner` port).
"""
