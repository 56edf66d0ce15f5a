"""The runtime: component processes, on this computer or another's host agent.

It owns the launcher and the component processes. It may import :mod:`executive.bus`,
:mod:`executive.sdk`, :mod:`executive.ros2` (the host of ROS 2 programs only) and
:mod:`knowledge`.

- :mod:`.launcher` — the one facade the task executor and the executive use, over the
  parts below;
- :mod:`.processes` — the launcher thread that forks, pumps and reaps component
  processes (:mod:`.spawn`: children that die with their parent; :mod:`.logfile`: their
  logs, rotated);
- :mod:`.supervisor` — the head of a component's process group: the whole tree ends;
- :mod:`.component_lifecycle` — starting, stopping and commanding components
  (:mod:`.states`: their states, published, logged and told);
- :mod:`.process_host` — where a process runs: here, or on another computer through its
  host agent (:mod:`.remote_host`);
- :mod:`.host_agent` — the host agent (``dura host``) on that other computer;
- :mod:`.behavior_goals` — goals sent to behaviors, their feedback and results;
- :mod:`.component_api` — the launcher's bus API for the command line;
- :mod:`.run_lock` — one executive per knowledge base, and what a killed one left;
- :mod:`.native_heap` — the C heap of a long-running process: few arenas, trimmed,
  no caches of freed blocks per thread;
- :mod:`.translator` — lifecycle commands for programs not written with the SDK (the
  plug-ins that come with dura in :mod:`.translators`);
- :mod:`.ros2_launch` — a ROS 2 program started under a host of dura's
  (:mod:`.ros2_host`, in its own process; :mod:`.ros2_goals`: a behavior's goals as
  ROS 2 actions or service calls).
"""
