"""ROS 2 programs as components of the robot description: nodes, lifecycle nodes, and
the actions and services a behavior's goals go to.

A component's ``ros2:`` key says what dura knows of it as ROS 2::

    functionalities:
      lidar:
        command: [ros2, run, my_robot, lidar]    # any argv: the ROS 2 program
        ros2: {node: /lidar}                      # its node (dura's name for its topics)
      navigator:
        command: [python, -m, nodes.navigator]
        ros2: {node: /navigator, lifecycle: true} # a managed node: configure, activate, ...
    behaviors:
      navigate:                                   # no command: dura's action client
        ros2: {action: /navigate_to_pose, type: nav2_msgs/action/NavigateToPose}
      relocalize:
        ros2: {service: /odometry/reset, type: std_srvs/srv/Trigger, wait: 10}

The node's topics, for the diagnosis model, come from ROS 2 discovery; the node's caller
id on its topics is the component's name. A behavior with an ``action`` or a
``service`` runs each goal as one goal of the action or one call of the service; the
task's goal fields are the goal's (the request's) fields, by dotted path. ``wait`` is
how long a start waits for the server (default 5 s; within the ``startup_timeout``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated, Any

from knowledge.conventions import AtLeast, Check
from knowledge.description import FunctionalitySpec
from knowledge.errors import ConfigError, did_you_mean
from knowledge.ros2_messages import message_store
from knowledge.typed_reader import MISSING, Entry, Place, open_entry

if TYPE_CHECKING:
    from knowledge.description import RobotDescription
    from knowledge.finding import Report

CALLS = ("action", "service")
_NAMED = 2  # rosbags' Nodetype.NAME: a field that is a message
DEFAULT_WAIT = 5.0
_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


@dataclass(frozen=True)
class Ros2Call:
    """A ROS 2 action or service that a behavior's goals go to."""

    kind: str  # "action" or "service"
    name: str  # fully qualified: /navigate_to_pose
    type: str  # nav2_msgs/action/NavigateToPose, std_srvs/srv/Trigger
    wait: float = DEFAULT_WAIT  # seconds a start waits for the server

    @property
    def goal_type(self) -> str:
        """Name the message a goal fills: the action's ``_Goal``, the service's ``_Request``."""
        return f"{self.type}_{'Goal' if self.kind == 'action' else 'Request'}"

    @property
    def result_type(self) -> str:
        return f"{self.type}_{'Result' if self.kind == 'action' else 'Response'}"


@dataclass(frozen=True)
class Ros2ComponentSpec:
    """What dura knows of a component as ROS 2: its node, whether it is managed, its call."""

    node: str | None = None  # fully qualified: /namespace/name
    lifecycle: bool = False
    call: Ros2Call | None = None
    line: int = 0


def ros_name(name: str, what: str) -> str:
    """Qualify a ROS 2 node, action or service name (relative names are in the root).

    Raises:
        ConfigError: not a valid ROS 2 name.
    """
    full = name if name.startswith("/") else "/" + name
    if not full[1:] or not all(_TOKEN.fullmatch(t) for t in full[1:].split("/")):
        raise ConfigError(
            f"invalid ROS 2 {what} name '{name}' (tokens of letters, digits and '_', "
            "not starting with a digit, separated by single '/')"
        )
    return full


def interface_type(name: str, kind: str) -> str:
    """Normalise an action or service type: ``pkg/Name`` -> ``pkg/<kind>/Name``."""
    parts = name.strip("/").split("/")
    folder = "action" if kind == "action" else "srv"
    return f"{parts[0]}/{folder}/{parts[1]}" if len(parts) == 2 else "/".join(parts)


def _ros_name(what: str) -> Any:
    """A ROS 2 name of a kind (``node``, ``action``, ``service``), qualified."""

    def qualified(text: str, place: Place) -> Any:
        try:
            return ros_name(text, what)
        except ConfigError as e:
            place.entry.error(place.key, f"{place.entry.what}: {e}")
            return MISSING

    return Annotated[str, Check(qualified)]


def read_component_ros2(value: Any, place: Place) -> Any:
    """Read a component's ``ros2:`` key (the component's schema says its kind)."""
    s = open_entry(value, place.source, place.path, f"'ros2' of {place.entry.what}", place=place)
    if s is None:
        return MISSING
    node = s.read("node", _ros_name("node"), None)
    lifecycle = s.read("lifecycle", bool, False)
    calls = [c for c in CALLS if s.has(c)]
    if len(calls) > 1:
        s.error(calls[1], f"{s.what} has both an action and a service")
    call = _call(s, calls[0]) if calls else None
    if not calls and s.has("type"):
        s.known("type")
        s.error("type", f"'type' of {s.what} needs an 'action' or a 'service'")
    s.close()
    if lifecycle and node is None:
        s.error(None, f"{s.what}: a lifecycle node needs its 'node' name")
    schema = place.entry.schema
    if schema is not None and issubclass(schema, FunctionalitySpec):
        if call is not None:
            s.error(
                call.kind,
                f"{s.what}: a functionality takes no goals; an {call.kind} belongs to a behavior",
            )
            call = None
        if node is None:
            s.error(None, f"{s.what} needs the 'node' name of its program")
    elif call is None and node is not None:
        s.error(None, f"{s.what}: a ROS 2 behavior needs an 'action' or a 'service' for its goals")
    return Ros2ComponentSpec(node, lifecycle, call, s.line or 0)


def _call(s: Entry, kind: str) -> Ros2Call | None:
    name = s.read(kind, _ros_name(kind), None)
    kind_type = s.read("type", str, None, required=True)
    wait = s.read("wait", Annotated[float, AtLeast(0.0)], DEFAULT_WAIT)  # only with a call
    if name is None or kind_type is None:
        return None
    return Ros2Call(kind, name, interface_type(kind_type, kind), wait)


# --- checks against the robot's message definitions --------------------------------


def check_ros2_components(robot: RobotDescription, report: Report) -> None:
    """Check the components' ROS 2 parts: a ``ros2:`` section, known types, unique nodes,
    task goal fields that the goal type has, properties some object declares."""
    specs = {n: c.ros2 for n, c in robot.components.items() if c.ros2 is not None}
    for task in robot.tasks.values():
        for field, arg in task.goal.items():
            if arg.property is not None and not _declared(robot, arg.property):
                report.error(
                    task.lines.get(f"goal.{field}", task.line),
                    f"goal field '{field}' of task '{task.action}' takes property "
                    f"'{arg.property}', which no object under 'objects:' has",
                )
    if not specs:
        return
    if robot.ros2 is None:
        first = min(specs.values(), key=lambda s: s.line)
        report.error(
            first.line, "components declare ROS 2 parts, but the robot has no 'ros2:' section"
        )
        return
    nodes: dict[str, str] = {}
    for name, spec in specs.items():
        if spec.node is not None and spec.node in nodes:
            report.error(
                spec.line, f"'{name}' and '{nodes[spec.node]}' are both ROS 2 node {spec.node}"
            )
        elif spec.node is not None:
            nodes[spec.node] = name
    fielddefs = _fielddefs(robot)
    if fielddefs is None:
        return  # the ros2: section's own findings say why
    for name, spec in specs.items():
        call = spec.call
        if call is not None and call.goal_type not in fielddefs:
            known = sorted({t.rsplit("_", 1)[0] for t in fielddefs if f"/{_folder(call)}/" in t})
            report.error(
                spec.line,
                f"{robot.component(name).kind.value} '{name}': unknown ROS 2 {call.kind} type "
                f"'{call.type}'{did_you_mean(call.type, known)}",
            )
    for task in robot.tasks.values():
        behavior = robot.behaviors.get(task.behavior)
        call = behavior.ros2.call if behavior is not None and behavior.ros2 is not None else None
        if call is None or call.goal_type not in fielddefs:
            continue
        for field in task.goal:
            problem = field_problem(fielddefs, call.goal_type, field)
            if problem:
                report.error(
                    task.lines.get(f"goal.{field}", task.line),
                    f"goal field '{field}' of task '{task.action}': {problem}",
                )


def _folder(call: Ros2Call) -> str:
    return "action" if call.kind == "action" else "srv"


def _declared(robot: RobotDescription, path: str) -> bool:
    head = path.split(".", maxsplit=1)[0]
    return any(head in props for props in robot.objects.values())


def _fielddefs(robot: RobotDescription) -> dict[str, Any] | None:
    if robot.ros2 is None:
        return None
    try:
        return dict(message_store(robot.ros2.distribution, robot.ros2.messages).fielddefs)
    except ConfigError:
        return None


def field_problem(fielddefs: dict[str, Any], message: str, path: str) -> str:
    """Say why a dotted field path is not in a message type ("" if it is)."""
    kind: str | None = message
    done: list[str] = []
    for part in path.split("."):
        if kind is None:
            return f"'{'.'.join(done)}' is a value, not a message with fields"
        fields = dict(fielddefs[kind][1])
        if part not in fields:
            return (
                f"{kind} has no field '{part}' (it has {', '.join(fields)})"
                f"{did_you_mean(part, list(fields))}"
            )
        done.append(part)
        kind_of, details = fields[part]
        kind = details if kind_of == _NAMED else None  # arrays and sequences end the path
    return ""
