"""Consistency-based diagnosis (thesis 5.2.3, 6.3): which components are faulty, given
what the observers saw.

It owns the diagnosis model and the newest observation of every observer. Pure parts,
testable without processes, then the service:

- :mod:`.model` — the system description: nodes, topics and observers, changed as
  components start and stop (a refused update changes nothing);
- :mod:`.engine` — the newest observations against the model, in clingo: every
  subset-minimal diagnosis;
- :mod:`.hitting_sets` with ``diagnosis.lp`` — minimal hitting sets of the conflicts;
- :mod:`.result` — what a diagnosis finds: a status and the sets of faulty candidates;
- :mod:`.learning` — the model learns its observers from their observations;
- :mod:`.timed` — when to diagnose and what to publish, on a clock someone else drives
  (the offline replay's);
- :mod:`.reader` — a model and observations read from YAML (``dura diagnose``);
- :mod:`.diagnosis_service` — the service: observations in, diagnoses out, model
  updates served on the bus.

It may import :mod:`executive.bus` and :mod:`knowledge`.
"""
