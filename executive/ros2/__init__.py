"""ROS 2 over DDS: dura joins a robot's ROS 2 graph with no ROS installation.

It speaks ROS 2's own wire conventions through Cyclone DDS (:mod:`names`, :mod:`qos`,
:mod:`types`, :mod:`cdr`, :mod:`participant`), learns the graph from ROS 2's discovery
topic (:mod:`discovery`), feeds ROS 2 topics to dura's observers (:mod:`topics`),
publishes dura's state to ROS 2 (:mod:`state`), takes goals from ROS 2 (:mod:`goals`)
and gives the diagnosis model the topics of the robot's ROS 2 nodes
(:mod:`graph_model`). It calls services with rmw_cyclonedds' request header
(:mod:`service`), sends goals to actions (:mod:`action`) and drives managed nodes
(:mod:`lifecycle`), for the host of ROS 2 programs in :mod:`executive.runtime`.
:mod:`link` opens the parts a robot's ``ros2:`` section needs, for the composition root.
"""
