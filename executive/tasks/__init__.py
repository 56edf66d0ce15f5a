"""The task executor (thesis 5.1.3): tasks on scheduled system configurations.

It owns the tasks and the running system configuration. It may import
:mod:`executive.bus`, :mod:`executive.runtime`, the plan executor's port in
:mod:`executive.planning` and :mod:`knowledge`.

Pure parts, testable without processes:

- :mod:`.task` — a task: its phases, why it ended, its state and views;
- :mod:`.decisions` — from requests, faults and availability to a schedule and the
  configuration changes that carry it out;
- :mod:`.scheduler` with ``schedule.lp`` — system configurations placed in time, by
  clingo (:mod:`.schedule`: what it is asked and answers; :mod:`.cancellation`: why a
  request cannot be scheduled);
- :mod:`.configuration` — which functionalities serve which tasks, and how to change
  that;
- :mod:`.faults` — fault counting and what each fault means;
- :mod:`.arguments` — the objects a task started by hand names, checked.

Parts that act, on the executor's one worker thread:

- :mod:`.ledger` — the tasks and their record in the knowledge base;
- :mod:`.configurator` — configuration changes carried out on the launcher;
- :mod:`.supervision` — behaviors started, sent their goal, watched to their result;
- :mod:`.fault_handling` — what :mod:`.faults` decides, done;
- :mod:`.enactment` — the decisions carried out;
- :mod:`.diagnosis_model` — the diagnosis model told which components run;
- :mod:`.parameters` — component parameters at run time, checked, stored and handed
  over;
- :mod:`.executor` — the service with its bus API (:mod:`.snapshot`: what its status
  queries answer from);
- :mod:`.plan_tasks` — plan steps run as tasks, the plan executor's runner
  (:mod:`.step_service`: the same for a high level in another process, over the bus).
"""
