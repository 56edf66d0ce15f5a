"""The runtime: component processes on this machine.

It owns the launcher, a facade (:mod:`.launcher`) over three concerns: the launcher
thread that forks, pumps and reaps component processes (:mod:`.processes`, with
:mod:`.spawn` and :mod:`.logfile`); their lifecycle commands and states
(:mod:`.lifecycle`, :mod:`.states`); and the goal protocol of behaviors
(:mod:`.behavior_goals`). It also owns the component API on the bus
(:mod:`.component_api`) and the translators that carry lifecycle commands to programs
not written with the SDK (:mod:`.translator`, :mod:`.translators`), and the host of
ROS 2 programs (:mod:`.ros2_launch` for the launcher, :mod:`.ros2_host` and
:mod:`.ros2_goals` in the host's process). It may import :mod:`executive.bus`,
:mod:`executive.sdk`, :mod:`executive.ros2` (the host only) and :mod:`knowledge`.
"""
