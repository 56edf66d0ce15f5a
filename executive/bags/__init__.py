"""Recordings: ROS 2 bags and dura's own MCAP recordings, read and written.

It may import :mod:`executive.bus`, ROS 2's message and decoder
(:mod:`executive.ros2.message`, :mod:`executive.ros2.cdr`) and :mod:`knowledge`. The
offline replay itself is :mod:`monitoring.replay`; ``dura replay`` composes the two.

- :mod:`.reader` — :func:`~.reader.open_bag`: open a recording, whatever it is;
- :mod:`.bag` — an opened recording: its topics, its messages as bus messages, and how
  its topics map to a robot's;
- :mod:`.mcap_bag` — MCAP files: rosbag2's MCAP storage and dura's recordings, whole or cut off;
- :mod:`.rosbag2_bag` — rosbag2's sqlite3 storage, file by file, and its zstd compression;
- :mod:`.ros_messages` — a bag's ROS 2 messages as the plain dicts observers read;
- :mod:`.message` — a recording's messages as bus messages that count themselves when
  their payload does not decode;
- :mod:`.recording` — a robot's bus traffic written to MCAP, rotated by size;
- :mod:`.export` — a recording's ROS 2 topics written as a rosbag2 bag;
- :mod:`.schemas` — JSON schemas of the recorded payloads, made from their dataclasses.
"""
