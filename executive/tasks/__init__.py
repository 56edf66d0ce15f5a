"""The task executor (thesis 5.1.3): tasks on scheduled system configurations.

It owns the tasks and the running system configuration. Pure parts, testable without
processes: the task model (``task``), the decisions (``decisions``: requests, faults
and availability to a schedule and configuration changes), the scheduler (clingo,
``scheduler`` with ``schedule.lp``, ``schedule``, ``cancellation``), configurations
(``configuration``) and fault decisions (``faults``). Parts that act, on the
executor's one worker thread: the ledger of tasks (``ledger``), configuration changes
on the launcher (``configurator``), the diagnosis model (``diagnosis_model``),
supervision of behaviors (``supervision``), fault handling (``fault_handling``), the
decisions carried out (``enactment``); the service with its bus API and status snapshot
(``executor``, ``snapshot``); and the adapter that runs plan steps as tasks
(``plan_tasks``), also for a high level in another process over the bus
(``step_service``). It may import :mod:`executive.bus`, :mod:`executive.runtime`, the
plan executor's port in :mod:`executive.planning` and :mod:`knowledge`.
"""
