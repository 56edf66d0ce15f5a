"""Messages of a recording that do not decode (CDR cut short or garbage, bad JSON, a
payload of the wrong shape, bytes that do not decompress) are counted per topic with
the first reason, and the replay goes on without them."""

from __future__ import annotations

import contextlib
import sqlite3
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.writer import Writer as McapWriter

from executive.bus.keys import DIAGNOSES, OBSERVATIONS, component, topic
from executive.bus.message import encode
from executive.bus.payloads import ComponentState
from executive.bus.states import Lifecycle
from executive.bus.undecodable import Undecodable, UndecodableMessages
from executive.testing.replay import replay_bag
from knowledge.errors import QUOTED
from tests.conftest import USECASE
from tests.executive.bags.recorded import (
    BROKEN,
    CUT_SHORT,
    T0,
    record,
    stamped_robot,
    write_scan_bag,
)


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_scans_that_do_not_decode_are_counted_with_the_first_reason_and_the_replay_goes_on(
    tmp_path: Path, storage: str
) -> None:
    robot = stamped_robot(tmp_path / "robot")
    good = replay_bag(write_scan_bag(tmp_path / "good", storage), robot)
    timeline = replay_bag(write_scan_bag(tmp_path / "bag", storage, broken=BROKEN), robot)
    assert timeline.undecodable == (Undecodable("/scan", 3, CUT_SHORT),)
    assert timeline.messages == good.messages == 180  # replayed, for their times
    assert timeline.entries == good.entries
    assert good.undecodable == ()


def spoil(bag: Path, storage: str, index: int, data: bytes) -> None:
    """Replace the bytes of the bag's ``index``-th message (from 0)."""
    if storage == "sqlite3":
        with contextlib.closing(sqlite3.connect(next(bag.glob("*.db3")))) as db, db:
            db.execute("UPDATE messages SET data = ? WHERE id = ?", (data, index + 1))
        return
    (path,) = bag.glob("*.mcap")
    with path.open("rb") as f:
        reader = make_reader(f)
        header, summary = reader.get_header(), reader.get_summary()
        assert summary is not None
        metadata = list(reader.iter_metadata())
        records = [m for _, _, m in reader.iter_messages(log_time_order=True)]
    with path.open("wb") as f:
        writer = McapWriter(f)
        writer.start(header.profile, header.library)
        for record in metadata:
            writer.add_metadata(record.name, record.metadata)
        for schema in summary.schemas.values():
            writer.register_schema(schema.name, schema.encoding, schema.data)
        for channel in summary.channels.values():
            writer.register_channel(
                channel.topic, channel.message_encoding, channel.schema_id, channel.metadata
            )
        for k, m in enumerate(records):
            writer.add_message(m.channel_id, m.log_time, data if k == index else m.data,
                               m.publish_time, m.sequence)  # fmt: skip
        writer.finish()


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_scan_that_does_not_decompress_is_counted_as_it_is_read_and_replayed_for_its_time(
    tmp_path: Path, storage: str
) -> None:
    plain = replay_bag(write_scan_bag(tmp_path / "plain", storage), USECASE)
    bag = write_scan_bag(tmp_path / "bag", storage, compression="message")
    spoil(bag, storage, 5, b"\x00\x11\x22\x33\x44\x55\x66")
    timeline = replay_bag(bag, USECASE)  # frequency and timeout: nothing decodes the scans
    ((found,),) = [timeline.undecodable]
    assert (found.topic, found.count) == ("/scan", 1)
    assert found.reason.startswith("cannot decompress it (ZstdError: ")
    assert (timeline.messages, timeline.entries) == (plain.messages, plain.entries)


def test_a_recordings_bad_json_and_payloads_of_the_wrong_shape_are_counted_per_key(
    tmp_path: Path,
) -> None:
    state = component("lidar", "state")
    ready = encode(ComponentState("lidar", Lifecycle.READY, stamp=T0).to_payload())
    wrong_state = encode({"component": "lidar", "state": "x" * 5000})
    scans = [(topic("scan"), encode({"stamp": T0 + k / 10}), "lidar", k / 10) for k in range(100)]
    scans[10] = (topic("scan"), b"{not json", "lidar", 1.0)
    scans[20] = (topic("scan"), b"[1, 2]", "lidar", 2.0)
    scans[30] = (topic("scan"), b"\xff\xfe", "lidar", 3.0)
    path = record(
        tmp_path / "run.mcap",
        [
            (state, ready, "executive", 0.0),
            *scans,
            (state, wrong_state, "executive", 5.0),
            (DIAGNOSES, b"{", "executive", 6.0),
            (OBSERVATIONS, encode({"observer": "lidar/0"}), "executive", 6.5),
        ],
    )
    timeline = replay_bag(path, stamped_robot(tmp_path / "robot"))
    found = {u.topic: (u.count, u.reason) for u in timeline.undecodable}
    assert set(found) == {"topic/scan", state, DIAGNOSES, OBSERVATIONS}
    assert found["topic/scan"] == (
        3,
        "topic/scan: malformed payload (not JSON: Expecting property name enclosed in double "
        "quotes: line 1 column 2 (char 1))",
    )
    assert found[DIAGNOSES][0] == 1 and "malformed payload (not JSON" in found[DIAGNOSES][1]
    assert found[OBSERVATIONS] == (1, "not an observation (KeyError: 'stamp')")
    count, reason = found[state]
    assert count == 1
    assert reason.startswith("not a component state (ValueError: ")
    assert reason.endswith(" more characters)")  # the state quoted in part
    assert len(reason) < QUOTED + 30
    assert timeline.messages == 103  # the state, the scans and the diagnosis: all replayed
    assert [e.describe() for e in timeline.observations()] == [
        "lidar/0 timestamp scan: ok (1) [age 0]; age 0 s over 5 messages"
    ]


def test_the_first_reason_of_a_topic_is_one_short_line() -> None:
    counted = UndecodableMessages()
    counted.add("topic/scan", "not JSON:\n" + "x" * 1000)
    counted.add("topic/scan", "a second reason is not kept")
    ((found,),) = [counted.topics()]
    assert (found.topic, found.count) == ("topic/scan", 2)
    assert found.reason == f"not JSON: {'x' * (QUOTED - 10)}... (810 more characters)"
