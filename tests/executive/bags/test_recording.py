"""Recordings of dura's bus traffic: MCAP with JSON schemas that MCAP tools and
``dura replay`` read back, rotated by size."""

from __future__ import annotations

import contextlib
import json
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.records import Message as McapMessage
from mcap.stream_reader import StreamReader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from executive.bags.bag import Route
from executive.bags.reader import open_bag
from executive.bags.recording import Recorder, rotated
from executive.bags.schemas import SCHEMAS
from executive.bus.keys import DIAGNOSES, OBSERVATIONS, RESOURCES, component, topic
from executive.bus.message import Message, encode
from executive.bus.payloads import (
    ComponentState,
    DiagnosisInfo,
    NodeInfo,
    ObservationInfo,
    ResourceInfo,
)
from executive.bus.states import Lifecycle
from executive.ros2.message import RosMessage
from tests.conftest import wait_for
from tests.executive.bags.recorded import scan

T0 = 1_700_000_000.0


def message(key: str, payload: dict[str, object], caller: str, t: float) -> Message:
    return Message(key, encode(payload), caller, t - 0.001, t)


def test_a_recording_is_mcap_with_a_json_schema_per_payload_and_a_channel_per_publisher(
    tmp_path: Path,
) -> None:
    path = tmp_path / "run.mcap"
    with Recorder(path, "usecase") as recorder:
        recorder.write(message(topic("scan"), {"stamp": T0, "ranges": [1.0]}, "lidar", T0))
        recorder.write(message(topic("scan"), {"stamp": T0}, "cam_to_lidar", T0 + 0.1))
        state = ComponentState("lidar", Lifecycle.READY, stamp=T0)
        recorder.write(message(component("lidar", "state"), state.to_payload(), "executive", T0))
        assert not recorder.write(message("component/lidar/cmd", {}, "cli", T0))  # not recorded
    with path.open("rb") as f:
        reader = make_reader(f)
        assert reader.get_header().profile == "dura"
        (metadata,) = reader.iter_metadata()
        assert (metadata.name, metadata.metadata["robot"]) == ("dura", "usecase")
        records = list(reader.iter_messages())
    channels = [(c.topic, c.metadata.get("caller_id"), s.name) for s, c, _ in records]
    assert channels == [
        ("topic/scan", "lidar", "dura.TopicMessage"),
        ("component/lidar/state", "executive", "dura.ComponentState"),
        ("topic/scan", "cam_to_lidar", "dura.TopicMessage"),
    ]
    _, _, first = records[0]
    assert (first.log_time, first.publish_time) == (round(T0 * 1e9), round((T0 - 0.001) * 1e9))
    assert json.loads(first.data) == {"stamp": T0, "ranges": [1.0]}
    assert records[1][0].encoding == "jsonschema" and records[1][1].message_encoding == "json"


def test_the_schemas_name_every_field_of_the_payloads(tmp_path: Path) -> None:
    payloads = {
        "dura.Observation": ObservationInfo("frequency", ("scan",), 1).to_payload(),
        "dura.Diagnosis": DiagnosisInfo("DIAGNOSED", (("lidar",),)).to_payload(),
        "dura.Resources": ResourceInfo("h", (NodeInfo("lidar", 1, "h", 1.0, 2),)).to_payload(),
        "dura.ComponentState": ComponentState("lidar", Lifecycle.READY).to_payload(),
    }
    for name, payload in payloads.items():
        schema = SCHEMAS[name]
        assert set(payload) <= set(schema["properties"]), name
        assert set(schema["required"]) <= set(payload), name
    assert SCHEMAS["dura.ComponentState"]["properties"]["state"]["enum"][1] == "ready"
    assert SCHEMAS["dura.Observation"]["properties"]["values"]["type"] == "object"


def test_a_recording_reads_back_as_the_messages_it_recorded(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    with Recorder(path, "usecase") as recorder:
        for k in range(5):
            recorder.write(message(topic("scan"), {"stamp": T0 + k}, "lidar", T0 + k))
        recorder.write(message(OBSERVATIONS, {"type": "frequency"}, "executive", T0 + 5))
        recorder.write(message(RESOURCES, {"hostname": "h", "nodes": []}, "executive", T0 + 5))
    with open_bag(path) as bag:
        assert (bag.format, bag.robot, bag.keys_are_bus_keys) == (
            "dura recording (mcap)",
            "usecase",
            True,
        )
        assert [t.name for t in bag.topics] == [OBSERVATIONS, RESOURCES, "topic/scan"]
        messages = list(bag.messages({"topic/scan": Route(topic("scan"))}))
    assert [(m.key, m.caller_id, m.received, m.payload["stamp"]) for m in messages] == [
        (topic("scan"), "lidar", T0 + k, T0 + k) for k in range(5)
    ]
    assert messages[0].sent == T0 - 0.001


def test_a_recording_keeps_the_times_of_its_messages_to_the_nanosecond(tmp_path: Path) -> None:
    # epoch times in ns that float seconds cannot hold (they are 240 ns apart there)
    times = [1_700_000_000_046_666_662 + k * 100_000_001 for k in range(20)]
    path = tmp_path / "run.mcap"
    with Recorder(path, "usecase") as recorder:
        for t in times:
            recorder.write(Message.at_ns(topic("scan"), b"{}", "lidar", t - 1, t))
    with path.open("rb") as f:  # read without dura
        written = [(m.publish_time, m.log_time) for _, _, m in make_reader(f).iter_messages()]
    assert written == [(t - 1, t) for t in times]
    with open_bag(path) as bag:
        read = [
            (m.sent_ns, m.received_ns) for m in bag.messages({"topic/scan": Route("topic/scan")})
        ]
    assert read == written


def test_a_recording_is_rotated_by_size_and_each_file_begins_with_the_component_states(
    tmp_path: Path,
) -> None:
    path = tmp_path / "run.mcap"
    state = ComponentState("lidar", Lifecycle.READY, stamp=T0).to_payload()
    noise = {"stamp": T0, "ranges": [float(i) for i in range(2000)]}  # poorly compressible
    with Recorder(path, "usecase", max_size=64 * 1024, keep=2) as recorder:
        recorder.write(message(component("lidar", "state"), state, "executive", T0))
        for k in range(400):
            noise["seq"] = k
            recorder.write(message(topic("scan"), noise, "lidar", T0 + k / 10))
        assert recorder.files > 3
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.1.mcap", "run.2.mcap", "run.mcap"]
    for file in (path, rotated(path, 1), rotated(path, 2)):
        assert file.stat().st_size < 64 * 1024 + 32 * 1024
        with open_bag(file) as bag:
            routes = {name.name: Route(name.name) for name in bag.topics}
            first = next(bag.messages(routes))
        assert first.key == "component/lidar/state" and first.payload["state"] == "ready"


def test_an_existing_recording_is_rotated_away_not_overwritten(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    Recorder(path, "usecase").close()
    before = path.read_bytes()
    Recorder(path, "usecase").close()
    assert rotated(path, 1).read_bytes() == before


def test_a_diagnosis_payload_is_recorded_under_its_key(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    diagnosis = DiagnosisInfo("DIAGNOSED", (("lidar",),), stamp=T0).to_payload()
    with Recorder(path, "usecase") as recorder:
        recorder.write(message(DIAGNOSES, diagnosis, "executive", T0))
    with open_bag(path) as bag:
        (recorded,) = bag.messages({DIAGNOSES: Route(DIAGNOSES)})
    assert DiagnosisInfo.from_payload(recorded.payload).diagnoses == (("lidar",),)


@pytest.mark.timeout(120)  # a recorder that never flushes never says so
def test_a_recorder_killed_at_any_moment_leaves_a_file_that_replays_up_to_its_last_flush(
    tmp_path: Path,
) -> None:
    rounds = random.Random(30)
    for round_ in range(5):
        path = tmp_path / f"killed{round_}.mcap"
        child = subprocess.Popen(
            [sys.executable, "-m", "tests.executive.bags.recorder_child", str(path), "0.3"],
            stdout=subprocess.PIPE,
            text=True,
        )
        assert child.stdout is not None
        lines = []
        wanted = rounds.randint(1, 4)  # killed after that many flushes, at a random moment
        try:
            while len(lines) < wanted:
                lines.append(child.stdout.readline())
            time.sleep(rounds.uniform(0.0, 0.3))
        finally:
            child.send_signal(signal.SIGKILL)
        rest, _ = child.communicate()
        flushed = int((lines + rest.splitlines())[-1].split()[1])
        assert flushed > 0
        # read without dura: the mcap library, record by record, up to the cut
        with path.open("rb") as f:
            independent = []
            with contextlib.suppress(Exception):
                for record in StreamReader(f).records:
                    if isinstance(record, McapMessage):
                        independent.append(json.loads(record.data)["k"])
        assert independent[:flushed] == list(range(flushed))
        with open_bag(path) as bag:
            routes = {"topic/scan": Route("topic/scan")}
            replayed = [m.payload["k"] for m in bag.messages(routes)]
            assert len(bag.notes) <= 1  # cut off, said in one line (unless it ended whole)
        assert replayed == independent  # all the whole chunks hold, in order
        result = subprocess.run(
            [sys.executable, "-m", "executive.cli", "record", "--repair", str(path), "--json"],
            capture_output=True, text=True, check=True,
        )  # fmt: skip
        assert json.loads(result.stdout)["messages"] == len(replayed)
        with path.open("rb") as f:  # whole now: its summary says so
            reader = make_reader(f)
            summary = reader.get_summary()
            assert summary is not None and summary.statistics is not None
            assert summary.statistics.message_count == len(replayed)
            assert [json.loads(m.data)["k"] for _, _, m in reader.iter_messages()] == replayed


def test_repair_leaves_a_whole_file_as_it_is_and_refuses_what_is_not_mcap(tmp_path: Path) -> None:
    path = tmp_path / "whole.mcap"
    with Recorder(path, "usecase") as recorder:
        recorder.write(message(topic("scan"), {"stamp": T0}, "lidar", T0))
    before = path.read_bytes()
    command = [sys.executable, "-m", "executive.cli", "record", "--repair"]
    result = subprocess.run([*command, str(path)], capture_output=True, text=True, check=True)
    assert result.stdout == f"dura: {path} is whole (1 message)\n"
    assert path.read_bytes() == before
    (tmp_path / "notes.mcap").write_text("hello")
    result = subprocess.run(
        [*command, str(tmp_path / "notes.mcap")], capture_output=True, text=True, check=False
    )
    assert result.returncode == 1 and "Traceback" not in result.stderr
    assert result.stderr == (
        f"dura: {tmp_path / 'notes.mcap'}: truncated or corrupt MCAP (it does not start as MCAP "
        "does)\n"
    )


def test_a_ros2_message_is_recorded_as_cdr_with_its_ros2msg_schema_that_rosbags_reads(
    tmp_path: Path,
) -> None:
    store = get_typestore(Stores.ROS2_JAZZY)
    scan_type = "sensor_msgs/msg/LaserScan"
    raw = scan(round(T0 * 1e9))
    path = tmp_path / "run.mcap"
    with Recorder(
        path, "usecase", ros2_definition=lambda t: store.generate_msgdef(t, ros_version=2)[0]
    ) as recorder:
        ros = RosMessage(topic("scan"), raw, "lidar", T0 - 0.01, T0, type=scan_type)
        recorder.write(ros)
        recorder.write(message(topic("odom"), {"stamp": T0}, "odometry", T0 + 0.1))
    with path.open("rb") as f:
        records = list(make_reader(f).iter_messages())
    (schema, channel, record), (json_schema, json_channel, _) = records
    assert (schema.name, schema.encoding, channel.message_encoding) == (
        scan_type, "ros2msg", "cdr"
    )  # fmt: skip
    assert (json_schema.encoding, json_channel.message_encoding) == ("jsonschema", "json")
    assert record.data == raw
    # rosbags reads the message from the file's own definition alone
    reader_store = get_typestore(Stores.EMPTY)
    reader_store.register(get_types_from_msg(schema.data.decode(), schema.name))
    decoded = reader_store.deserialize_cdr(record.data, scan_type)
    assert decoded.header.frame_id == "laser" and list(decoded.ranges[:2]) == [2.0, 2.0]
    with open_bag(path) as bag:
        replayed = next(bag.messages({"topic/scan": Route("topic/scan")}))
        assert replayed.payload["header"]["frame_id"] == "laser"
        assert (replayed.caller_id, replayed.received, replayed.sent) == ("lidar", T0, T0 - 0.01)


def test_a_recording_cut_anywhere_replays_a_prefix_of_what_it_recorded(tmp_path: Path) -> None:
    path = tmp_path / "whole.mcap"
    written = []
    with Recorder(path, "usecase", flush_every=3600.0) as recorder:
        for k in range(300):
            recorder.write(
                message(topic("scan"), {"stamp": T0 + k / 10, "k": k}, "lidar", T0 + k / 10)
            )
            written.append(k)
            if k % 50 == 49:
                recorder.flush()  # six whole chunks, as six seconds of recording
    data = path.read_bytes()
    routes = {"topic/scan": Route("topic/scan")}
    previous = 0
    for cut in range(40, len(data), max(1, len(data) // 97)):  # after the header: anywhere
        (tmp_path / "cut.mcap").write_bytes(data[:cut])
        with open_bag(tmp_path / "cut.mcap") as bag:
            read = [m.payload["k"] for m in bag.messages(routes)]
            assert len(bag.notes) == 1 and "cut off" in bag.notes[0]
        assert read == written[: len(read)] and len(read) % 50 == 0  # whole chunks only
        assert len(read) >= previous
        previous = len(read)
    assert previous == 300  # cut in the summary: every chunk is whole


def test_what_was_recorded_is_on_disk_within_a_flush_even_when_the_bus_goes_quiet(
    tmp_path: Path,
) -> None:
    path = tmp_path / "quiet.mcap"
    with Recorder(path, "usecase", flush_every=0.2) as recorder:
        for k in range(5):
            recorder.write(message(topic("scan"), {"stamp": T0 + k}, "lidar", T0 + k))
        assert wait_for(lambda: recorder.flushed == 5, 10)  # nothing written since
        with open_bag(path) as bag:  # still recording: read as a file cut off
            assert [
                m.payload["stamp"] for m in bag.messages({"topic/scan": Route("topic/scan")})
            ] == [T0 + k for k in range(5)]
            assert "cut off" in bag.notes[0]
