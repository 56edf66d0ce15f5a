"""ROS 2 over DDS: dura joins a robot's ROS 2 graph with no ROS installation.

It speaks ROS 2's own wire conventions through Cyclone DDS. It may import
:mod:`executive.bus` and :mod:`knowledge`.

- :mod:`.participant` — one Cyclone DDS participant and its receiving thread (the one
  adapter of Cyclone DDS);
- :mod:`.names`, :mod:`.qos` — ROS 2 names and QoS profiles as DDS has them;
- :mod:`.types`, :mod:`.cdr`, :mod:`.message` — message types and their decoders, CDR
  decoded to plain values, a message decoded only when a field is read;
- :mod:`.discovery` — the ROS 2 graph, from ROS 2's discovery topic;
- :mod:`.topics` — ROS 2 topics as a topic source for dura's observers;
- :mod:`.graph_model` — the topics of the robot's ROS 2 nodes for the diagnosis model;
- :mod:`.state` — dura's state out to ROS 2 (``/diagnostics``, ``/dura/events``);
- :mod:`.goal_topic` — goals from ROS 2 tools, on a topic;
- :mod:`.service_client`, :mod:`.action`, :mod:`.lifecycle_node` — clients of a
  service, of an action, and of a managed node's lifecycle services, for the host of
  ROS 2 programs in :mod:`executive.runtime`;
- :mod:`.link` — the parts a robot's ``ros2:`` section needs, opened for the
  composition root.
"""
