"""The messages of services, actions and lifecycle nodes on the wire: dura's bytes are
rosbags' bytes, the request header is rmw_cyclonedds' (client id, sequence number
before the message), and the stand-in nodes' hand-written types agree with both."""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import pytest

from examples.ros2.nodes import interfaces as kit
from executive.ros2.cdr import CdrError
from executive.ros2.service_client import endpoint_id, unwrap, wrap
from executive.ros2.types import TypeLibrary
from knowledge.ros2_messages import message_store
from tests.conftest import ROOT

MSGS = ROOT / "examples" / "ros2" / "msgs"
GUID, SEQ = 0xFEDCBA9876543210, 42
NAV = "nav2_msgs/action/NavigateToPose"


@pytest.fixture(scope="module")
def library() -> TypeLibrary:
    return TypeLibrary(message_store("jazzy", [Path(MSGS)]), "jazzy")


def _uuid(n: int) -> tuple[dict[str, Any], kit.UUID]:
    return {"uuid": list(range(n, n + 16))}, kit.UUID(uuid=list(range(n, n + 16)))


def _stamped() -> tuple[dict[str, Any], kit.PoseStamped]:
    values = {
        "header": {"stamp": {"sec": 3, "nanosec": 4}, "frame_id": "map"},
        "pose": {"position": {"x": 4.0, "y": 3.0, "z": 0.0},
                 "orientation": {"x": 0.0, "y": 0.0, "z": 0.7071, "w": 0.7071}},
    }  # fmt: skip
    message = kit.PoseStamped(
        header=kit.Header(stamp=kit.Time(sec=3, nanosec=4), frame_id="map"),
        pose=kit.Pose(
            position=kit.Point(x=4.0, y=3.0),
            orientation=kit.Quaternion(z=0.7071, w=0.7071),
        ),
    )
    return values, message


def plain_messages() -> dict[str, tuple[dict[str, Any], Any]]:
    """Topics' messages: each as dura's dict and as the stand-ins' object."""
    uuid, uuid_k = _uuid(1)
    info = {"goal_id": uuid, "stamp": {"sec": 5, "nanosec": 6}}
    info_k = kit.GoalInfo(goal_id=uuid_k, stamp=kit.Time(sec=5, nanosec=6))
    pose, pose_k = _stamped()
    feedback = {"current_pose": pose, "navigation_time": {"sec": 1, "nanosec": 2},
                "estimated_time_remaining": {"sec": 3, "nanosec": 0},
                "number_of_recoveries": 2, "distance_remaining": 2.5}  # fmt: skip
    feedback_k = kit.NavigateToPose_Feedback(
        current_pose=pose_k, navigation_time=kit.Duration(sec=1, nanosec=2),
        estimated_time_remaining=kit.Duration(sec=3), number_of_recoveries=2,
        distance_remaining=2.5,
    )  # fmt: skip
    state = {"id": 3, "label": "active"}
    return {
        "action_msgs/msg/GoalStatusArray": (
            {"status_list": [{"goal_info": info, "status": 4}]},
            kit.GoalStatusArray(status_list=[kit.GoalStatus(goal_info=info_k, status=4)]),
        ),
        f"{NAV}_FeedbackMessage": (
            {"goal_id": uuid, "feedback": feedback},
            kit.NavigateToPose_FeedbackMessage(goal_id=uuid_k, feedback=feedback_k),
        ),
        "lifecycle_msgs/msg/TransitionEvent": (
            {"timestamp": 123456789, "transition": {"id": 3, "label": "activate"},
             "start_state": {"id": 13, "label": "activating"}, "goal_state": state},
            kit.TransitionEvent(
                timestamp=123456789, transition=kit.Transition(id=3, label="activate"),
                start_state=kit.State(id=13, label="activating"),
                goal_state=kit.State(id=3, label="active"),
            ),
        ),
        "std_msgs/msg/String": ({"data": "(visited lab)"}, kit.String(data="(visited lab)")),
    }  # fmt: skip


def requests_and_replies() -> dict[str, tuple[dict[str, Any], type[Any], dict[str, Any]]]:
    """Services' messages: dura's dict, the stand-ins' class, its fields (no header)."""
    uuid, uuid_k = _uuid(9)
    info_k = kit.GoalInfo(goal_id=uuid_k, stamp=kit.Time(sec=7, nanosec=8))
    info = {"goal_id": uuid, "stamp": {"sec": 7, "nanosec": 8}}
    pose, pose_k = _stamped()
    return {
        f"{NAV}_SendGoal_Request": (
            {"goal_id": uuid, "goal": {"pose": pose, "behavior_tree": "bt.xml"}},
            kit.NavigateToPose_SendGoal_Request,
            {"goal_id": uuid_k,
             "goal": kit.NavigateToPose_Goal(pose=pose_k, behavior_tree="bt.xml")},
        ),
        f"{NAV}_SendGoal_Response": (
            {"accepted": True, "stamp": {"sec": 9, "nanosec": 10}},
            kit.NavigateToPose_SendGoal_Response,
            {"accepted": True, "stamp": kit.Time(sec=9, nanosec=10)},
        ),
        f"{NAV}_GetResult_Request": (
            {"goal_id": uuid}, kit.NavigateToPose_GetResult_Request, {"goal_id": uuid_k},
        ),
        f"{NAV}_GetResult_Response": (
            {"status": 6, "result": {"error_code": 9003, "error_msg": "no scan for 8.0 s"}},
            kit.NavigateToPose_GetResult_Response,
            {"status": 6, "result": kit.NavigateToPose_Result(error_code=9003,
                                                              error_msg="no scan for 8.0 s")},
        ),
        "action_msgs/srv/CancelGoal_Request": (
            {"goal_info": info}, kit.CancelGoal_Request, {"goal_info": info_k},
        ),
        "action_msgs/srv/CancelGoal_Response": (
            {"return_code": 0, "goals_canceling": [info]},
            kit.CancelGoal_Response, {"return_code": 0, "goals_canceling": [info_k]},
        ),
        "lifecycle_msgs/srv/ChangeState_Request": (
            {"transition": {"id": 1, "label": "configure"}},
            kit.ChangeState_Request, {"transition": kit.Transition(id=1, label="configure")},
        ),
        "lifecycle_msgs/srv/ChangeState_Response": (
            {"success": True}, kit.ChangeState_Response, {"success": True},
        ),
        "lifecycle_msgs/srv/GetState_Request": (
            {"structure_needs_at_least_one_member": 0}, kit.GetState_Request, {},
        ),
        "lifecycle_msgs/srv/GetState_Response": (
            {"current_state": {"id": 2, "label": "inactive"}},
            kit.GetState_Response, {"current_state": kit.State(id=2, label="inactive")},
        ),
        "std_srvs/srv/Trigger_Request": (
            {"structure_needs_at_least_one_member": 0}, kit.Trigger_Request, {},
        ),
        "std_srvs/srv/Trigger_Response": (
            {"success": False, "message": "no match with the map"},
            kit.Trigger_Response, {"success": False, "message": "no match with the map"},
        ),
    }  # fmt: skip


def rosbags_bytes(library: TypeLibrary, name: str, values: dict[str, Any]) -> bytes:
    """Serialise a message with rosbags, from rosbags' own reading of dura's bytes."""
    store = library.store
    ours = library.create(name, values).serialize()
    return bytes(store.serialize_cdr(store.deserialize_cdr(ours, name), name))


def test_action_topics_and_lifecycle_events_are_byte_identical_to_rosbags_and_the_stand_ins(
    library: TypeLibrary,
) -> None:
    for name, (values, stand_in) in plain_messages().items():
        ours = library.create(name, values).serialize()
        assert ours == rosbags_bytes(library, name, values), name
        assert ours == stand_in.serialize(), name
        assert library.idl(name).__idl_typename__ == stand_in.__idl_typename__, name  # type: ignore[attr-defined]


def test_requests_and_replies_carry_rmw_cyclonedds_header_before_rosbags_bytes(
    library: TypeLibrary,
) -> None:
    for name, (values, stand_in, fields) in requests_and_replies().items():
        reference = rosbags_bytes(library, name, values)
        header = struct.pack("<Qq", GUID, SEQ)
        expected = reference[:4] + header + reference[4:]
        ours = wrap(library.create(name, values).serialize(), GUID, SEQ)
        assert ours == expected, name
        assert stand_in(guid_=GUID, seq_=SEQ, **fields).serialize() == expected, name
        wrapped = library.wrapped(name)
        assert wrapped.__idl_typename__ == stand_in.__idl_typename__, name  # type: ignore[attr-defined]
        message = library.create(name, values)
        members = {f: getattr(message, f) for f, _ in library.fields(name)}
        assert wrapped(guid_=GUID, seq_=SEQ, **members).serialize() == expected, name
        assert unwrap(expected) == (GUID, SEQ, reference), name
        assert library.decoder(name)(unwrap(expected)[2]) == library.decoder(name)(reference)


def test_a_header_in_big_endian_is_read_in_big_endian(library: TypeLibrary) -> None:
    name = "std_srvs/srv/Trigger_Response"
    store = library.store
    message = store.deserialize_cdr(
        library.create(name, {"success": True, "message": "ok"}).serialize(), name
    )
    big = bytes(store.serialize_cdr(message, name, little_endian=False))
    guid, seq, body = unwrap(big[:4] + struct.pack(">Qq", GUID, SEQ) + big[4:])
    assert (guid, seq) == (GUID, SEQ)
    assert library.decoder(name)(body) == {"success": True, "message": "ok"}


def test_a_reply_too_short_for_its_header_is_a_cdr_error() -> None:
    with pytest.raises(CdrError, match="too short for a request header"):
        unwrap(b"\x00\x01\x00\x00" + bytes(8))
    with pytest.raises(CdrError, match="not plain CDR"):
        unwrap(b"\x00\x07\x00\x00" + bytes(20))


def test_client_ids_are_written_as_rmw_cyclonedds_writes_them() -> None:
    assert endpoint_id(bytes([1, 2, 0x1F, 0] + [0] * 12)) == "01.2.1f.0.0.0.0.0.0.0.0.0.0.0.0.0"
