"""Stand-in ROS 2 nodes of the example robot, written with Cyclone DDS (no ROS installation).

Each module is a program (``python -m nodes.lidar``) that behaves on the wire as the
ROS 2 node it stands in for; :mod:`.rosnode` is their small kit of ROS 2 conventions.
"""
