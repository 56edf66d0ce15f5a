"""``dura demo --ros2``: the patrol robot of ``examples/ros2`` end to end, over ROS 2.

Its drivers are ROS 2 nodes (stand-ins on Cyclone DDS): dura launches them, drives the
managed navigator through its lifecycle, runs the plan's steps as a ROS 2 service call
(relocalize) and ROS 2 action goals (NavigateToPose, the goal poses from the places'
properties). The goal comes in over ROS 2, as ``ros2 topic pub /dura/goals`` would
send it. While the robot drives, the lidar driver stops publishing (its test hook, a
ROS 2 service): the observers on ``/scan`` see it, the diagnosis names lidar (which
publishes ``/scan``, as ROS 2 discovery told), a repair rule restarts it, the
navigation goal is cancelled for the pause and sent again, and the patrol ends.

DDS stays on loopback in a domain picked at random, so the demo never meets a real
robot on the network. Loaded only for ``--ros2``: Cyclone DDS is imported here.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import queue
import random
import tempfile
import time
from pathlib import Path
from typing import Any

from executive.bus.api.planning import StatusReply
from executive.bus.keys import DIAGNOSES, EVENTS
from executive.bus.schema import plain
from executive.cli.demo import summary
from executive.cli.demo_timeline import Timeline, replans
from executive.cli.output import print_json
from executive.ros2.names import dds_topic
from executive.ros2.participant import Participant
from executive.ros2.qos import dds_qos
from executive.ros2.service_client import ServiceClient
from executive.ros2.types import TypeLibrary
from executive.testing.harness import RobotProcess, robot_variant
from knowledge.errors import DuraError
from knowledge.records import Goal, GoalState
from knowledge.ros2_messages import standard_store
from knowledge.ros2_spec import PROFILES

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "ros2" / "robot.yaml"
GOAL = "(and (visited lab) (visited office) (robot_at dock))"
TIMEOUT = 90.0  # seconds for the whole run
LOOPBACK = """\
<CycloneDDS xmlns="https://cdds.io/config">
  <Domain id="any">
    <General>
      <Interfaces><NetworkInterface address="127.0.0.1" multicast="false"/></Interfaces>
      <AllowMulticast>false</AllowMulticast>
    </General>
    <Discovery>
      <ParticipantIndex>auto</ParticipantIndex>
      <MaxAutoParticipantIndex>60</MaxAutoParticipantIndex>
      <Peers><Peer address="127.0.0.1"/></Peers>
    </Discovery>
  </Domain>
</CycloneDDS>
"""


def run(args: argparse.Namespace) -> int:
    if not EXAMPLE.is_file():
        raise DuraError(f"the example robot is missing: {EXAMPLE} (run from a dura checkout)")
    if args.keep is not None:
        args.keep.mkdir(parents=True, exist_ok=True)
        return _demo(args, args.keep.resolve())
    with tempfile.TemporaryDirectory(prefix="dura-demo-ros2-") as folder:
        return _demo(args, Path(folder))


def _demo(args: argparse.Namespace, folder: Path) -> int:
    timeline = Timeline(quiet=args.json, everything=args.all_events)
    try:
        goals, status, arrays = _scenario(folder, timeline)
    finally:
        timeline.close()
    ok = all(g.state is GoalState.ACHIEVED for g in goals)
    elapsed = time.time() - timeline.start
    if args.json:
        print_json(
            {"ok": ok, "elapsed": round(elapsed, 2), "goals": plain(goals),
             "faults": plain(status.faults), "plans": timeline.plans,
             "replans": len(replans(timeline.events)), "events": plain(timeline.events),
             "diagnoses": timeline.diagnoses, "ros2_diagnostic_arrays": arrays}
        )  # fmt: skip
        return 0 if ok else 1
    summary(goals, status, timeline, elapsed)
    print(f"ROS 2 tools saw {arrays} DiagnosticArrays on /diagnostics", flush=True)
    return 0 if ok else 1


def _scenario(folder: Path, timeline: Timeline) -> tuple[list[Goal], StatusReply, int]:
    """Run the patrol on a robot in ``folder``: the goals, the status and how many
    DiagnosticArrays ROS 2 heard."""
    say = timeline.say
    domain = random.SystemRandom().randint(1, 230)
    config = folder / "cyclonedds.xml"
    config.write_text(LOOPBACK)
    before = os.environ.get("CYCLONEDDS_URI")
    os.environ["CYCLONEDDS_URI"] = config.as_uri()  # the executive and its nodes inherit it
    try:
        description = robot_variant(EXAMPLE, folder / "robot", {"ros2": {"domain_id": domain}})
        say("DEMO", f"starting the executive of the ROS 2 patrol robot in {folder} "
            f"(DDS domain {domain})")  # fmt: skip
        with (
            RobotProcess(description, folder / "run") as robot,
            Participant(domain, name="demo") as participant,
            contextlib.ExitStack() as closing,
        ):
            timeline.use(robot.kb_path)
            robot.bus.subscribe(EVENTS, timeline.on_event)
            robot.bus.subscribe(DIAGNOSES, timeline.on_diagnoses)
            ros = _Ros2Side(participant)
            closing.callback(ros.close)
            reply = ros.submit(GOAL)
            if not reply.get("accepted"):
                raise DuraError(f"demo: the goal from ROS 2 was refused: {reply.get('reason')}")
            say("ROS 2 GOAL", f"goal {reply['goal']['id']} from /dura/goals: {GOAL}")
            timeline.wait("START", "move_to")
            time.sleep(1.5)  # let it drive a little
            say("INJECT", "the lidar driver stops publishing /scan (/lidar/inject_fault)")
            ros.stall_lidar()
            timeline.wait("FAULT", "lidar", timeout=30)
            goals = _wait_for_goals(robot)
            status = robot.status()
            arrays = ros.diagnostics_heard()
    finally:
        if before is None:
            os.environ.pop("CYCLONEDDS_URI", None)
        else:
            os.environ["CYCLONEDDS_URI"] = before
    return goals, status, arrays


def _wait_for_goals(robot: RobotProcess) -> list[Goal]:
    deadline = time.monotonic() + TIMEOUT
    while time.monotonic() < deadline:
        goals = robot.goals()
        if goals and not any(g.state.is_open for g in goals):
            return goals
        time.sleep(0.2)
    return robot.goals()


class _Ros2Side:
    """What a ROS 2 user does in the demo: submit a goal, trip the lidar, watch /diagnostics."""

    def __init__(self, participant: Participant) -> None:
        self.participant = participant
        self.library = TypeLibrary(standard_store("jazzy"), "jazzy")
        string = self.library.idl("std_msgs/msg/String")
        qos = dds_qos(PROFILES["default"])
        self._replies: queue.Queue[dict[str, Any]] = queue.Queue()
        self._arrays = 0
        decode = self.library.decoder("std_msgs/msg/String")

        def replied(samples: list[Any], received: float) -> None:
            for data, info in samples:
                if info.valid_data:
                    self._replies.put(json.loads(decode(data)["data"]))

        def diagnosed(samples: list[Any], received: float) -> None:
            self._arrays += sum(1 for _, info in samples if info.valid_data)

        self._endpoints: list[Any] = [
            participant.reader(dds_topic("/dura/goals/replies"), string, qos, replied),
            participant.reader(
                dds_topic("/diagnostics"),
                self.library.idl("diagnostic_msgs/msg/DiagnosticArray"),
                qos,
                diagnosed,
            ),
        ]
        self._goals = participant.writer(dds_topic("/dura/goals"), string, qos)
        self._endpoints.append(self._goals)
        self._lidar = ServiceClient(
            participant, self.library, "/lidar/inject_fault", "std_srvs/srv/Trigger"
        )

    def submit(self, expression: str, timeout: float = 20.0) -> dict[str, Any]:
        """Publish a goal on /dura/goals once dura reads it; dura's reply."""
        deadline = time.monotonic() + timeout
        while self._goals.matched() == 0:
            if time.monotonic() > deadline:
                raise DuraError("demo: dura does not read /dura/goals")
            time.sleep(0.05)
        self._goals.write(self.library.create("std_msgs/msg/String", {"data": expression}))
        try:
            return self._replies.get(timeout=max(0.1, deadline - time.monotonic()))
        except queue.Empty:
            raise DuraError("demo: no reply on /dura/goals/replies") from None

    def stall_lidar(self) -> None:
        if not self._lidar.wait(10.0):
            raise DuraError("demo: the lidar node serves no /lidar/inject_fault")
        self._lidar.call(timeout=5.0)

    def diagnostics_heard(self) -> int:
        return self._arrays

    def close(self) -> None:
        self._lidar.close()
        for endpoint in self._endpoints:
            endpoint.close()
