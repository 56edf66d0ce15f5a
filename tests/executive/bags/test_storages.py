"""Every rosbag2 bag ``rosbags`` reads, read as the same bag: sqlite3 as each ROS 2
distribution wrote it, MCAP, split into several files, compressed per file or per
message; each checked message by message against the same bag in plain MCAP and
against what ``rosbags`` itself reads from the files."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml
from rosbags.rosbag2 import Reader

from executive.bags.bag import routes
from executive.bags.reader import open_bag
from executive.testing.replay import replay_bag
from knowledge.description import RobotDescription
from knowledge.errors import BagError
from knowledge.robot import load_robot
from tests.conftest import USECASE
from tests.executive.bags.recorded import (
    SQLITE3_SCHEMAS,
    T0,
    as_written_by,
    scan_times,
    write_scan_bag,
    write_split_bag,
)

EDGES = [T0 * 10**9 + 123_456_789, *[T0 * 10**9 + k * 10**8 + 987 for k in range(2, 200)]]


@pytest.fixture(scope="module")
def robot() -> RobotDescription:
    return load_robot(USECASE)


def read(path: Path, robot: RobotDescription) -> tuple[tuple[int, int, int], list[Any]]:
    """The bag's window and count, and its messages as (key, caller, received, bytes)."""
    with open_bag(path) as bag:
        messages = [
            (m.key, m.caller_id, m.received, m.raw, m.payload["header"]["stamp"])
            for m in bag.messages(routes(bag, robot))
        ]
        return (bag.start_ns, bag.end_ns, bag.count), messages


def rosbags_files(folder: Path) -> list[tuple[int, bytes]]:
    """What ``rosbags`` reads from each storage file of a bag on its own."""
    found = []
    for file in sorted([*folder.glob("*.db3"), *folder.glob("*.mcap")]):
        with Reader(file) as reader:
            found += [(t, bytes(raw)) for _, t, raw in reader.messages()]
    return sorted(found)


@pytest.mark.parametrize("distribution", list(SQLITE3_SCHEMAS))
def test_a_sqlite3_bag_of_each_distribution_reads_as_the_same_bag_in_mcap(
    tmp_path: Path, robot: RobotDescription, distribution: str
) -> None:
    mcap = write_scan_bag(tmp_path / "mcap", "mcap", times=EDGES)
    sqlite3 = as_written_by(write_scan_bag(tmp_path / "db", "sqlite3", times=EDGES), distribution)
    expected = read(mcap, robot)
    assert expected[0] == (EDGES[0], EDGES[-1], len(EDGES))  # integer ns, from the messages
    assert read(sqlite3, robot) == expected
    assert [(r, raw) for _, _, r, raw, _ in expected[1]] == [
        (t / 1e9, raw) for t, raw in rosbags_files(sqlite3)
    ]  # the times and the bytes as rosbags reads them


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
@pytest.mark.parametrize("compression", ["file", "message"])
def test_a_compressed_bag_reads_as_the_same_bag_uncompressed(
    tmp_path: Path, robot: RobotDescription, storage: str, compression: str
) -> None:
    plain = write_scan_bag(tmp_path / "plain", "mcap", times=EDGES)
    packed = write_scan_bag(tmp_path / "packed", storage, times=EDGES, compression=compression)
    assert read(packed, robot) == read(plain, robot)


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_split_bag_reads_as_one_in_order(
    tmp_path: Path, robot: RobotDescription, storage: str
) -> None:
    plain = write_scan_bag(tmp_path / "plain", "mcap", times=EDGES)
    split = write_split_bag(tmp_path / "split", storage, [EDGES[:70], EDGES[70:140], EDGES[140:]])
    assert len([*split.glob("*.db3"), *split.glob("*.mcap")]) == 3
    assert read(split, robot) == read(plain, robot)
    assert [(r, raw) for _, _, r, raw, _ in read(split, robot)[1]] == [
        (t / 1e9, raw) for t, raw in rosbags_files(split)
    ]


def test_the_first_and_last_message_of_an_epoch_bag_are_replayed(tmp_path: Path) -> None:
    for storage in ("mcap", "sqlite3"):
        bag = write_scan_bag(tmp_path / storage, storage, times=EDGES)
        timeline = replay_bag(bag, USECASE)
        assert timeline.messages == len(EDGES), storage


def test_a_bag_and_its_conversion_give_the_same_timeline(tmp_path: Path) -> None:
    times = scan_times()
    mcap = replay_bag(write_scan_bag(tmp_path / "mcap", "mcap", times=times), USECASE)
    for distribution in SQLITE3_SCHEMAS:
        folder = write_scan_bag(tmp_path / distribution, "sqlite3", times=times)
        timeline = replay_bag(as_written_by(folder, distribution), USECASE)
        assert timeline.to_payload() == mcap.to_payload(), distribution


@pytest.mark.parametrize(
    ("change", "reason"),
    [
        ({"version": 10}, "metadata version 10: dura reads 1 to 9"),
        (
            {"compression_mode": "file", "compression_format": "lz4"},
            "compressed with 'lz4': dura reads zstd only",
        ),
        ({"storage_identifier": "bagz"}, "storage 'bagz': dura reads sqlite3 and mcap"),
    ],
)
def test_metadata_dura_cannot_read_is_one_line_naming_the_file(
    tmp_path: Path, change: dict[str, Any], reason: str
) -> None:
    folder = write_scan_bag(tmp_path / "bag", "sqlite3", times=EDGES[:3])
    metadata = folder / "metadata.yaml"
    info = yaml.safe_load(metadata.read_text())
    info["rosbag2_bagfile_information"].update(change)
    metadata.write_text(yaml.safe_dump(info))
    with pytest.raises(BagError) as error:
        open_bag(folder)
    assert str(error.value) == f"{metadata}: {reason}"


# an epoch time whose seconds, as floats, round so that 0.5 s after a message looks longer
ROUNDED = T0 * 10**9 + 46_666_662


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_silence_of_exactly_the_timeout_is_no_timeout_whatever_the_epoch_time(
    tmp_path: Path, storage: str
) -> None:
    # scans at 10 Hz to 9.8 s, one more at 9.875 s, then silence until 12 s: the timeout
    # observer (0.5 s, 8 Hz from 2 s on) loops at 10.375 s, exactly 0.5 s after the
    # last scan: in integer ns that is no timeout yet; the next loop, 10.5 s, is one
    scan = [ROUNDED + k * 10**8 for k in range(99)] + [ROUNDED + 9_875_000_000]
    times = scan + [ROUNDED + k * 10**8 for k in range(120, 140)]
    timeline = replay_bag(write_scan_bag(tmp_path / storage, storage, times=times), USECASE)
    changes = [(e.time, e.info.observation_msg) for e in timeline.observations("lidar/1")]
    assert changes == [(2.0, "ok"), (10.5, "timeout"), (12.125, "ok")]
    ok = next(e for e in timeline.observations("lidar/1") if e.time == 2.0)
    assert ok.values["silence"] == pytest.approx(0.1)
    assert (timeline.begin, timeline.end, timeline.messages) == (0.0, 13.9, len(times))
