"""ROS 2 over DDS: dura joins a robot's ROS 2 graph with no ROS installation.

It speaks ROS 2's own wire conventions through Cyclone DDS (:mod:`names`, :mod:`qos`,
:mod:`types`, :mod:`cdr`, :mod:`participant`), learns the graph from ROS 2's discovery
topic (:mod:`discovery`), feeds ROS 2 topics to dura's observers (:mod:`topics`) and
publishes dura's state to ROS 2 (:mod:`state`). :mod:`link` opens the parts a robot's
``ros2:`` section needs, for the composition root.
"""
