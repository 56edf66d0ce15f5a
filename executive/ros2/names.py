"""ROS 2 names on the DDS wire, as the rmw layers for DDS (rmw_cyclonedds, rmw_fastrtps) map them.

- A topic ``/scan`` is the DDS topic ``rt/scan``.
- A service ``/add`` is two DDS topics: requests on ``rq/addRequest``, replies on
  ``rr/addReply``.
- An action ``/navigate`` is three services ``/navigate/_action/{send_goal,
  cancel_goal, get_result}`` and two topics ``/navigate/_action/{feedback, status}``.
- A message type ``sensor_msgs/msg/LaserScan`` is the DDS type
  ``sensor_msgs::msg::dds_::LaserScan_`` (services: ``..::srv::dds_::Name_Request_``).
- A node is ``/namespace/name``; as a caller id (how observers name publishers) it
  loses its leading slash: ``namespace/name``, or ``name`` in the root namespace.
"""

from __future__ import annotations

from dataclasses import dataclass

TOPIC_PREFIX = "rt"
REQUEST_PREFIX = "rq"
REPLY_PREFIX = "rr"
DISCOVERY_TOPIC = "ros_discovery_info"  # ROS 2's own graph topic, without a prefix
DISCOVERY_TYPE = "rmw_dds_common/msg/ParticipantEntitiesInfo"


def dds_topic(topic: str) -> str:
    """Name a ROS 2 topic on DDS: ``/scan`` -> ``rt/scan``."""
    return f"{TOPIC_PREFIX}/{topic.lstrip('/')}"


def ros_topic(dds_name: str) -> str | None:
    """Name a DDS topic in ROS 2: ``rt/scan`` -> ``/scan`` (``None``: not a ROS 2 topic)."""
    prefix, _, rest = dds_name.partition("/")
    return "/" + rest if prefix == TOPIC_PREFIX and rest else None


def request_topic(service: str) -> str:
    """Name the requests of a service on DDS: ``/add`` -> ``rq/addRequest``."""
    return f"{REQUEST_PREFIX}/{service.lstrip('/')}Request"


def reply_topic(service: str) -> str:
    """Name the replies of a service on DDS: ``/add`` -> ``rr/addReply``."""
    return f"{REPLY_PREFIX}/{service.lstrip('/')}Reply"


def service_of(dds_name: str) -> str | None:
    """Name the service of a request or reply DDS topic: ``rq/addRequest`` -> ``/add``."""
    prefix, _, rest = dds_name.partition("/")
    suffix = {REQUEST_PREFIX: "Request", REPLY_PREFIX: "Reply"}.get(prefix)
    if suffix is None or not rest.endswith(suffix) or len(rest) == len(suffix):
        return None
    return "/" + rest[: -len(suffix)]


@dataclass(frozen=True)
class ActionNames:
    """The services and topics (ROS 2 names) that make up one action."""

    send_goal: str
    cancel_goal: str
    get_result: str
    feedback: str
    status: str


def action_names(action: str) -> ActionNames:
    """Name an action's services and topics: ``/navigate/_action/send_goal`` ..."""
    base = "/" + action.strip("/") + "/_action/"
    return ActionNames(
        send_goal=base + "send_goal",
        cancel_goal=base + "cancel_goal",
        get_result=base + "get_result",
        feedback=base + "feedback",
        status=base + "status",
    )


def dds_type(ros_type: str) -> str:
    """Name a message type on DDS: ``std_msgs/msg/String`` -> ``std_msgs::msg::dds_::String_``."""
    package, kind, name = ros_type.split("/")
    return f"{package}::{kind}::dds_::{name}_"


def ros_type(dds_name: str) -> str | None:
    """Name a DDS type in ROS 2: ``std_msgs::msg::dds_::String_`` -> ``std_msgs/msg/String``.

    ``None`` for a type name that does not follow ROS 2's convention.
    """
    parts = dds_name.split("::")
    if len(parts) != 4 or parts[2] != "dds_" or not parts[3].endswith("_") or len(parts[3]) < 2:
        return None
    return f"{parts[0]}/{parts[1]}/{parts[3][:-1]}"


def node_name(namespace: str, name: str) -> str:
    """Qualify a node's name with its namespace: ``/robot1`` + ``lidar`` -> ``/robot1/lidar``."""
    namespace = namespace.strip("/")
    return f"/{namespace}/{name}" if namespace else f"/{name}"


def caller_id(node: str) -> str:
    """Name a node as observers name publishers: ``/robot1/lidar`` -> ``robot1/lidar``."""
    return node.strip("/")
