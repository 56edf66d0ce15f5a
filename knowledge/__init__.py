"""dura's knowledge: robot descriptions, PDDL domains and the knowledge base.

The bottom layer: it imports nothing else of dura, and every other package may import
it.

- :mod:`.description` — the robot description as typed, frozen data;
- :mod:`.typed_reader` — the one reader of typed data: robot descriptions, observer
  configurations, rules and bus payloads, each declared once as annotated frozen
  dataclasses (:mod:`.conventions`: the markers of ``Annotated``; :mod:`.field_plan`:
  how each field is read, worked out once per class; :mod:`.value_source`: where values
  come from, and how a problem is worded and placed);
- :mod:`.robot` — reading it from YAML (:mod:`.yamlsource`: YAML documents with the line
  of every value, bounded in size, depth and aliases);
- :mod:`.ros2_spec`, :mod:`.ros2_components` — a description's ``ros2:`` section and its
  ROS 2 programs as components; :mod:`.ros2_messages` — ROS 2 message definitions (with
  the services bundled in ``ros2_interfaces/``);
- :mod:`.sensing_spec` — the ``sensing:`` section: facts and values read from topics;
- :mod:`.validation` — a description cross-checked, and with its domain
  (:mod:`.finding`: a problem found at a file and line);
- :mod:`.availability` — which functionalities can still run, given the permanent
  faults;
- :mod:`.domain` — temporal PDDL read with unified-planning, the domain's signatures
  (:mod:`.pddl_errors`: the reader's errors worded as ``file:line:col: reason``);
- :mod:`.sources` — where input text comes from: the file, or an editor's unsaved buffer
  (``dura lsp``);
- :mod:`.knowledge_base` — the knowledge base, one SQLite file per robot: its tables
  (:mod:`.tables`), its migrations (:mod:`.schema`), whether it is sound and its repair
  (:mod:`.health`);
- :mod:`.records` — what it stores, as typed frozen records; :mod:`.transitions` — the
  states of goals, plans and tasks and the changes allowed; :mod:`.record_class` — how
  every record class of dura is made (frozen, and cheap to define);
- :mod:`.asp` — the one adapter of clingo;
- :mod:`.errors` — :class:`~.errors.DuraError` and its subclasses.
"""
