"""dura's monitoring: observers, resource monitor, diagnosis and repair (thesis 5.2, 5.3).

It keeps the robot alive: observers watch every running component and topic, the
diagnosis names the faulty components, repair rules act. It may import
:mod:`executive.bus` and :mod:`knowledge`, nothing else of dura.

- :mod:`.observer` — the extension point: an observer's configuration, lifecycle,
  results and the registry of types; :mod:`.observers` — the built-in types;
- :mod:`.observer_config` — observer configurations from robot descriptions, observers
  files and bus requests, read by :mod:`knowledge.typed_reader` with their lines;
- :mod:`.caller_groups` — topics watched per caller-id group;
- :mod:`.filter`, :mod:`.check`, :mod:`.state` — measurements smoothed, checked
  against a hypothesis, classified into named states (:mod:`.t_distribution` for the
  Student's t check; :mod:`.field_path` for a number inside a payload);
- :mod:`.robot_time` — the times observers measure, scaled as the robot's clock;
- :mod:`.observer_manager` — runs every observer, changeable at run time
  (:mod:`.observer_api`: its bus API);
- :mod:`.resource_monitor` — CPU and memory of each component's process tree;
- :mod:`.diagnosis` — consistency-based diagnosis in clingo;
- :mod:`.repair` — repair rules and their actions;
- :mod:`.replay`, :mod:`.timeline` — recorded messages through the observers, diagnosis
  and rules, with the recording's time as the clock, and what that replay saw.
"""
