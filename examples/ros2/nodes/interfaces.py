"""The ROS 2 message types the stand-in nodes use, written out as rosidl generates them
for DDS (Jazzy's definitions): type names ``pkg::msg::dds_::Name_``, ``T[N]`` arrays,
``T[]`` sequences.

A service's request and reply carry rmw_cyclonedds' request header before their
fields: the client's id ``guid_`` (uint64) and the sequence number ``seq_`` (int64).
"""

# No "from __future__ import annotations": Cyclone DDS reads these annotations as types.
from dataclasses import dataclass, field

from cyclonedds.idl import IdlStruct
from cyclonedds.idl import types as t


def _zeros(n: int) -> "list[float]":
    return [0.0] * n


# --- builtin_interfaces, std_msgs, geometry_msgs, sensor_msgs, nav_msgs -------------


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: t.int32 = 0
    nanosec: t.uint32 = 0


@dataclass
class Duration(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    sec: t.int32 = 0
    nanosec: t.uint32 = 0


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@dataclass
class String(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str = ""


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0
    w: t.float64 = 1.0


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass
class PoseStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    header: Header = field(default_factory=Header)
    pose: Pose = field(default_factory=Pose)


@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@dataclass
class PoseWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    pose: Pose = field(default_factory=Pose)
    covariance: t.array[t.float64, 36] = field(default_factory=lambda: _zeros(36))


@dataclass
class TwistWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::TwistWithCovariance_"):
    twist: Twist = field(default_factory=Twist)
    covariance: t.array[t.float64, 36] = field(default_factory=lambda: _zeros(36))


@dataclass
class Odometry(IdlStruct, typename="nav_msgs::msg::dds_::Odometry_"):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)
    twist: TwistWithCovariance = field(default_factory=TwistWithCovariance)


@dataclass
class LaserScan(IdlStruct, typename="sensor_msgs::msg::dds_::LaserScan_"):
    header: Header = field(default_factory=Header)
    angle_min: t.float32 = 0.0
    angle_max: t.float32 = 0.0
    angle_increment: t.float32 = 0.0
    time_increment: t.float32 = 0.0
    scan_time: t.float32 = 0.0
    range_min: t.float32 = 0.0
    range_max: t.float32 = 0.0
    ranges: t.sequence[t.float32] = field(default_factory=list)
    intensities: t.sequence[t.float32] = field(default_factory=list)


# --- the ROS 2 graph (rmw_dds_common) ------------------------------------------------


@dataclass
class Gid(IdlStruct, typename="rmw_dds_common::msg::dds_::Gid_"):
    data: t.array[t.uint8, 16] = field(default_factory=lambda: [0] * 16)


@dataclass
class NodeEntitiesInfo(IdlStruct, typename="rmw_dds_common::msg::dds_::NodeEntitiesInfo_"):
    node_namespace: t.bounded_str[256] = "/"
    node_name: t.bounded_str[256] = ""
    reader_gid_seq: t.sequence[Gid] = field(default_factory=list)
    writer_gid_seq: t.sequence[Gid] = field(default_factory=list)


@dataclass
class ParticipantEntitiesInfo(
    IdlStruct, typename="rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"
):
    gid: Gid = field(default_factory=Gid)
    node_entities_info_seq: t.sequence[NodeEntitiesInfo] = field(default_factory=list)


# --- actions (unique_identifier_msgs, action_msgs) ----------------------------------


@dataclass
class UUID(IdlStruct, typename="unique_identifier_msgs::msg::dds_::UUID_"):
    uuid: t.array[t.uint8, 16] = field(default_factory=lambda: [0] * 16)


@dataclass
class GoalInfo(IdlStruct, typename="action_msgs::msg::dds_::GoalInfo_"):
    goal_id: UUID = field(default_factory=UUID)
    stamp: Time = field(default_factory=Time)


@dataclass
class GoalStatus(IdlStruct, typename="action_msgs::msg::dds_::GoalStatus_"):
    goal_info: GoalInfo = field(default_factory=GoalInfo)
    status: t.int8 = 0


@dataclass
class GoalStatusArray(IdlStruct, typename="action_msgs::msg::dds_::GoalStatusArray_"):
    status_list: t.sequence[GoalStatus] = field(default_factory=list)


@dataclass
class CancelGoal_Request(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Request_"):
    guid_: t.uint64 = 0
    seq_: t.int64 = 0
    goal_info: GoalInfo = field(default_factory=GoalInfo)


@dataclass
class CancelGoal_Response(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Response_"):
    guid_: t.uint64 = 0
    seq_: t.int64 = 0
    return_code: t.int8 = 0
    goals_canceling: t.sequence[GoalInfo] = field(default_factory=list)


# --- nav2_msgs/action/NavigateToPose (Jazzy) ----------------------------------------

_NAV = "nav2_msgs::action::dds_::NavigateToPose_"


@dataclass
class NavigateToPose_Goal(IdlStruct, typename=_NAV + "Goal_"):
    pose: PoseStamped = field(default_factory=PoseStamped)
    behavior_tree: str = ""


@dataclass
class NavigateToPose_Result(IdlStruct, typename=_NAV + "Result_"):
    error_code: t.uint16 = 0
    error_msg: str = ""


@dataclass
class NavigateToPose_Feedback(IdlStruct, typename=_NAV + "Feedback_"):
    current_pose: PoseStamped = field(default_factory=PoseStamped)
    navigation_time: Duration = field(default_factory=Duration)
    estimated_time_remaining: Duration = field(default_factory=Duration)
    number_of_recoveries: t.int16 = 0
    distance_remaining: t.float32 = 0.0


@dataclass
class NavigateToPose_SendGoal_Request(IdlStruct, typename=_NAV + "SendGoal_Request_"):
    guid_: t.uint64 = 0
    seq_: t.int64 = 0
    goal_id: UUID = field(default_factory=UUID)
    goal: NavigateToPose_Goal = field(default_factory=NavigateToPose_Goal)


@dataclass
class NavigateToPose_SendGoal_Response(IdlStruct, typename=_NAV + "SendGoal_Response_"):
    guid_: t.uint64 = 0
    seq_: t.int64 = 0
    accepted: bool = False
    stamp: Time = field(default_factory=Time)


@dataclass
class NavigateToPose_GetResult_Request(IdlStruct, typename=_NAV + "GetResult_Request_"):
    guid_: t.uint64 = 0
    seq_: t.int64 = 0
    goal_id: UUID = field(default_factory=UUID)


@dataclass
class NavigateToPose_GetResult_Response(IdlStruct, typename=_NAV + "GetResult_Response_"):
    guid_: t.uint64 = 0
    seq_: t.int64 = 0
    status: t.int8 = 0
    result: NavigateToPose_Result = field(default_factory=NavigateToPose_Result)


@dataclass
class NavigateToPose_FeedbackMessage(IdlStruct, typename=_NAV + "FeedbackMessage_"):
    goal_id: UUID = field(default_factory=UUID)
    feedback: NavigateToPose_Feedback = field(default_factory=NavigateToPose_Feedback)


# --- lifecycle_msgs -----------------------------------------------------------------


@dataclass
class State(IdlStruct, typename="lifecycle_msgs::msg::dds_::State_"):
    id: t.uint8 = 0
    label: str = ""


@dataclass
class Transition(IdlStruct, typename="lifecycle_msgs::msg::dds_::Transition_"):
    id: t.uint8 = 0
    label: str = ""


@dataclass
class TransitionEvent(IdlStruct, typename="lifecycle_msgs::msg::dds_::TransitionEvent_"):
    timestamp: t.uint64 = 0
    transition: Transition = field(default_factory=Transition)
    start_state: State = field(default_factory=State)
    goal_state: State = field(default_factory=State)


@dataclass
class ChangeState_Request(IdlStruct, typename="lifecycle_msgs::srv::dds_::ChangeState_Request_"):
    guid_: t.uint64 = 0
    seq_: t.int64 = 0
    transition: Transition = field(default_factory=Transition)


@dataclass
class ChangeState_Response(IdlStruct, typename="lifecycle_msgs::srv::dds_::ChangeState_Response_"):
    guid_: t.uint64 = 0
    seq_: t.int64 = 0
    success: bool = False


@dataclass
class GetState_Request(IdlStruct, typename="lifecycle_msgs::srv::dds_::GetState_Request_"):
    guid_: t.uint64 = 0
    seq_: t.int64 = 0
    structure_needs_at_least_one_member: t.uint8 = 0


@dataclass
class GetState_Response(IdlStruct, typename="lifecycle_msgs::srv::dds_::GetState_Response_"):
    guid_: t.uint64 = 0
    seq_: t.int64 = 0
    current_state: State = field(default_factory=State)


# --- std_srvs ----------------------------------------------------------------------


@dataclass
class Trigger_Request(IdlStruct, typename="std_srvs::srv::dds_::Trigger_Request_"):
    guid_: t.uint64 = 0
    seq_: t.int64 = 0
    structure_needs_at_least_one_member: t.uint8 = 0


@dataclass
class Trigger_Response(IdlStruct, typename="std_srvs::srv::dds_::Trigger_Response_"):
    guid_: t.uint64 = 0
    seq_: t.int64 = 0
    success: bool = False
    message: str = ""
