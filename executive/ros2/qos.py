"""ROS 2 QoS profiles as Cyclone DDS QoS, set the way rmw_cyclonedds sets them.

A :class:`~knowledge.ros2_spec.QosProfile` (the robot description's; the named
profiles are in :data:`knowledge.ros2_spec.PROFILES`) becomes DDS policies: history
keep last N (or keep all), reliable (blocking without bound when the history is full)
or best effort, volatile or transient local (with a durability service keeping the
same history, which late joiners get), automatic liveliness without a lease, no
auto-dispose, and XCDR1, the only data representation ROS 2 offers.
"""

from __future__ import annotations

from cyclonedds.core import Policy, Qos
from cyclonedds.util import duration

from knowledge.ros2_spec import QosProfile

# What rmw_dds_common's graph topic uses (rmw_cyclonedds, creating a node's context).
DISCOVERY = QosProfile(reliability="reliable", durability="transient_local", depth=1)
DISCOVERY_READER = QosProfile(
    reliability="reliable", durability="transient_local", history="keep_all", depth=1
)
# What rcl_action gives an action's status topic (the rest of an action: the defaults).
ACTION_STATUS = QosProfile(durability="transient_local", depth=1)
_UNLIMITED = -1


def dds_qos(
    profile: QosProfile,
    *,
    depth: int | None = None,
    ignore_local: bool = False,
    user_data: bytes = b"",
) -> Qos:
    """Make the DDS QoS of a ROS 2 endpoint with this profile.

    Args:
        profile: the ROS 2 policies.
        depth: a deeper history than the profile's (a reader's own affair: it changes
            nothing a publisher sees).
        ignore_local: ignore what this participant itself publishes.
        user_data: ``key=value;`` pairs, as rmw_cyclonedds marks the two halves of a
            service client or server (``clientid=...;``).
    """
    history = (
        Policy.History.KeepAll
        if profile.history == "keep_all"
        else Policy.History.KeepLast(max(profile.depth, depth or 0))
    )
    policies = [
        history,
        Policy.Reliability.Reliable(max_blocking_time=duration(infinite=True))
        if profile.reliability == "reliable"
        else Policy.Reliability.BestEffort,
        Policy.Liveliness.Automatic(lease_duration=duration(infinite=True)),
        Policy.WriterDataLifecycle(autodispose=False),
        Policy.DataRepresentation(use_cdrv0_representation=True),
    ]
    if profile.durability == "transient_local":
        policies.append(Policy.Durability.TransientLocal)
        policies.append(
            Policy.DurabilityService(
                cleanup_delay=0,
                history=history,
                max_samples=_UNLIMITED,
                max_instances=_UNLIMITED,
                max_samples_per_instance=_UNLIMITED,
            )
        )
    else:
        policies.append(Policy.Durability.Volatile)
    if ignore_local:
        policies.append(Policy.IgnoreLocal.Participant)
    if user_data:
        policies.append(Policy.Userdata(data=user_data))
    return Qos(*policies)
