"""The task executor (thesis 5.1.3): tasks on scheduled system configurations.

It owns the tasks and the running system configuration: the scheduler (clingo,
``schedule.lp``), configuration changes, fault handling and the supervision of running
behaviors, and the adapter that runs plan steps as tasks. It may import
:mod:`executive.bus`, :mod:`executive.runtime`, the plan executer's port in
:mod:`executive.planning` and :mod:`knowledge`.
"""
