"""Recordings: ROS 2 bags and dura's own MCAP recordings, read and written.

:func:`executive.bags.reader.open_bag` opens a rosbag2 (MCAP or sqlite3 storage) or an
MCAP file and yields its messages as bus messages (:mod:`executive.bags.bag`: topics,
routes to a robot's topics, caller ids), ROS 2 messages decoded to plain dicts when
read (:mod:`executive.bags.ros_messages`). :mod:`executive.bags.recording` writes a
robot's bus traffic to MCAP with JSON schemas (:mod:`executive.bags.schemas`), rotated
by size. The offline replay itself is :mod:`monitoring.replay`; ``dura replay``
composes the two.
"""
