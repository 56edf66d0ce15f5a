"""``dura replay`` as a user runs it: bags written with ``rosbags`` (MCAP and sqlite3)
through the use-case robot's real observers, diagnosis (clingo) and repair rules."""

from __future__ import annotations

import io
import json
import time
from collections.abc import Callable
from pathlib import Path
from subprocess import CompletedProcess

import pytest

from executive.bus.keys import component, topic
from executive.bus.message import Message, encode
from executive.bus.payloads import ComponentState
from executive.bus.states import Lifecycle
from executive.cli import replay as replay_command
from executive.testing.harness import robot_variant
from monitoring.timeline import Timeline
from tests.conftest import USECASE
from tests.executive.bags.recorded import (
    BROKEN,
    CUT_SHORT,
    T0,
    record,
    scan_times,
    stamped_robot,
    write_scan_bag,
    write_unknown_type_bag,
)

Dura = Callable[..., CompletedProcess[str]]


def replay(dura: Dura, bag: Path, *args: str) -> CompletedProcess[str]:
    return dura("replay", str(bag), "--robot", str(USECASE), *args)


def timeline(result: CompletedProcess[str]) -> list[tuple[float, str, str]]:
    assert result.returncode == 0, result.stderr
    found = []
    for entry in json.loads(result.stdout)["timeline"]:
        what = {
            "observation": lambda e: f"{e['observer']} {e['type']} {e['observation_msg']}",
            "diagnosis": lambda e: f"{e['status']} {e['diagnoses']}",
            "repair": lambda e: f"{e['rule']}: {e['action']}",
        }[entry["kind"]](entry)
        found.append((entry["time"], entry["kind"], what))
    return found


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_lidar_that_stops_for_two_seconds_is_observed_diagnosed_and_would_be_restarted_at_the_bags_times(
    dura: Dura, tmp_path: Path, storage: str
) -> None:
    result = replay(dura, write_scan_bag(tmp_path / "bag", storage), "--json")
    assert timeline(result) == [
        (2.0, "observation", "lidar/0 frequency ok"),
        (2.0, "observation", "lidar/1 timeout ok"),
        (10.5, "observation", "lidar/0 frequency stopped"),  # 0.6 s after the last scan at 9.9
        (10.5, "observation", "lidar/1 timeout timeout"),
        (10.52, "diagnosis", "DIAGNOSED [['lidar']]"),  # settled 20 ms, as live
        (10.52, "repair", "restart_lidar: restart lidar"),
        (12.125, "observation", "lidar/1 timeout ok"),  # the first 8 Hz loop after 12.0
        (12.5, "observation", "lidar/0 frequency ok"),
        (12.52, "diagnosis", "OK []"),
    ]
    summary = json.loads(result.stdout)["summary"]
    assert summary["diagnoses"] == [
        {"diagnosis": ["lidar"], "total": 2.0, "periods": [[10.52, 12.52]], "held_at_end": False}
    ]
    assert json.loads(result.stdout)["origin"] == T0


def test_replaying_the_same_bag_twice_prints_the_same(dura: Dura, tmp_path: Path) -> None:
    bag = write_scan_bag(tmp_path / "bag")
    first, second = replay(dura, bag), replay(dura, bag)
    assert first.returncode == 0, first.stderr
    assert first.stdout == second.stdout
    lines = first.stdout.splitlines()
    assert (
        lines[0]
        == f"{bag}: rosbag2 (mcap), 19.900 s, 180 messages; robot 'usecase'; /scan → scan (from lidar)"
    )
    assert (
        "   10.520  diagnosis    DIAGNOSED: lidar (failed: frequency[scan]; timeout[scan])" in lines
    )
    assert (
        "   10.520  repair       rule restart_lidar would restart lidar (possibly faulty: lidar)"
        in lines
    )
    assert lines[-3:] == [
        "summary: 19.900 s replayed, 180 messages",
        "  diagnosis lidar: held 2.000 s (10.520-12.520)",
        "  rule restart_lidar would restart lidar: 1 time (10.520)",
    ]
    json_first, json_second = replay(dura, bag, "--json"), replay(dura, bag, "--json")
    assert json_first.stdout == json_second.stdout


def test_a_window_and_a_map_replay_part_of_a_bag_under_another_name(
    dura: Dura, tmp_path: Path
) -> None:
    bag = write_scan_bag(tmp_path / "bag", topic="/front/scan")
    result = replay(dura, bag, "--map", "/front/scan=scan", "--from", "8", "--to", "11", "--json")
    assert timeline(result)[:2] == [
        (10.0, "observation", "lidar/0 frequency ok"),  # start-up: 2 s after the window opens
        (10.0, "observation", "lidar/1 timeout ok"),
    ]
    data = json.loads(result.stdout)
    assert (data["begin"], data["end"]) == (8.0, 11.0)
    assert data["routes"] == {"/front/scan": {"key": "topic/scan", "caller": "lidar"}}


def test_at_a_rate_the_bag_takes_its_time(dura: Dura, tmp_path: Path) -> None:
    bag = write_scan_bag(tmp_path / "bag", times=scan_times(None, 3.0))
    began = time.monotonic()
    paced = replay(dura, bag, "--rate", "2", "--json")
    took = time.monotonic() - began
    assert took >= 1.45  # 2.9 s of bag at twice its speed (plus the start of Python)
    assert timeline(paced) == timeline(replay(dura, bag, "--json"))


def cut(bag: Path, keep: float) -> Path:
    (source,) = bag.glob("bag.*")
    target = bag.parent / f"cut{source.suffix}"
    data = source.read_bytes()
    target.write_bytes(data[: int(len(data) * keep)])
    return target


BAD = {
    "truncated mcap": (
        lambda p: cut(write_scan_bag(p / "bag"), 0.00005),  # not even its header is whole
        (),
        "truncated or corrupt",
    ),
    "truncated sqlite3": (
        lambda p: cut(write_scan_bag(p / "bag", "sqlite3"), 0.5),
        (),
        "truncated or corrupt",
    ),
    "no topic of the robot": (
        lambda p: write_scan_bag(p / "bag", topic="/front/scan"),
        (),
        "none of its topics (/front/scan) is a topic of robot 'usecase'",
    ),
    "a map of a topic the bag lacks": (
        lambda p: write_scan_bag(p / "bag"),
        ("--map", "/rear/scan=scan"),
        "no topic '/rear/scan' to map",
    ),
}


@pytest.mark.parametrize("case", BAD, ids=list(BAD))
def test_bad_input_is_one_line_naming_the_file_and_the_reason(
    dura: Dura, tmp_path: Path, case: str
) -> None:
    make, args, reason = BAD[case]
    path = make(tmp_path)
    result = replay(dura, path, *args)
    assert result.returncode == 1
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.stderr
    assert result.stderr.startswith(f"dura: {path}: ")
    assert reason in result.stderr


def test_a_topic_of_a_type_nobody_defines_feeds_the_observers_that_do_not_decode(
    dura: Dura, tmp_path: Path
) -> None:
    known = replay(dura, write_scan_bag(tmp_path / "known", "sqlite3"), "--json")
    result = replay(dura, write_unknown_type_bag(tmp_path / "bag", scan_times()), "--json")
    assert timeline(result) == timeline(known)  # frequency and timeout: times only
    payload = json.loads(result.stdout)
    assert payload["counts"] == {
        "in_bag": 180, "routed": 180, "replayed": 180, "outside_window": 0, "not_routed": 0,
        "not_routed_topics": [],
    }  # fmt: skip
    assert payload["notes"] == []  # nothing had to decode them


def test_progress_shows_on_a_terminal_after_a_while_and_is_cleared_at_the_end(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(replay_command, "PROGRESS_AFTER", 0.0)
    monkeypatch.setattr(replay_command, "PROGRESS_EVERY", 0.0)
    out = io.StringIO()
    messages = [Message("topic/scan", b"{}", "lidar", None, T0 + k) for k in range(5)]
    progress = replay_command.Progress(out, T0, T0 + 4)
    assert list(progress.wrap(messages)) == messages
    shown = out.getvalue()
    assert "\r  replayed 2.0 of 4.0 s (50%)" in shown
    assert shown.endswith("\r\033[K")


def test_the_dura_replay_fixture_pins_a_bags_diagnoses_in_a_test(
    dura_replay: Callable[..., Timeline], tmp_path: Path
) -> None:
    timeline = dura_replay(write_scan_bag(tmp_path / "bag"), USECASE)
    assert timeline.diagnosed() == [("lidar",)]
    assert [(r.time, r.action) for r in timeline.repairs()] == [(10.52, "restart lidar")]
    (hold,) = timeline.holds()
    assert hold.periods == ((10.52, 12.52),)


def test_an_observer_that_must_decode_an_unknown_type_is_reported_once_in_one_line(
    dura: Dura, tmp_path: Path
) -> None:
    timestamp = {"type": "timestamp", "topics": [{"name": "scan", "filter": {"type": "mean", "window_size": 5}, "states": [
        {"state": "ok", "number": 1, "age": {"type": "less_than", "less_than": 0.5}}]}]}  # fmt: skip
    robot = robot_variant(
        USECASE, tmp_path / "robot", {"functionalities": {"lidar": {"observers": [timestamp]}}}
    )
    bag = write_unknown_type_bag(tmp_path / "bag", scan_times())
    result = dura("replay", str(bag), "--robot", str(robot))
    assert result.returncode == 0, result.stderr
    notes = [line for line in result.stdout.splitlines() if "note:" in line]
    assert notes == [
        f"  note: {bag}: topic '/scan' not decoded: its type 'acme_msgs/msg/Sweep' is unknown "
        "(the bag does not define it, rosbags' latest types do not know it; --types DIR reads "
        ".msg files)"
    ]
    assert "summary: 19.900 s replayed, 180 messages" in result.stdout
    (counted,) = [line for line in result.stdout.splitlines() if "undecodable:" in line]
    assert counted.startswith(  # those the timestamp observer read: not after its last loop
        "  undecodable: /scan: 170 messages (the first: cannot decode a message from lidar: "
        "its type 'acme_msgs/msg/Sweep' is unknown"
    )


# the keys of `dura replay --json` before undecodable messages were reported (public API)
JSON_KEYS = {"bag", "format", "robot", "routes", "origin", "begin", "end", "messages",
             "timeline", "summary", "recorded", "skipped", "counts", "notes", "live"}  # fmt: skip


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_scans_that_do_not_decode_are_reported_per_topic_and_the_verdict_stands(
    dura: Dura, tmp_path: Path, storage: str
) -> None:
    robot = stamped_robot(tmp_path / "robot")
    good = dura("replay", str(write_scan_bag(tmp_path / "good", storage)), "--robot", str(robot),
                "--json")  # fmt: skip
    bag = write_scan_bag(tmp_path / "bag", storage, broken=BROKEN)
    result = dura("replay", str(bag), "--robot", str(robot), "--json")
    assert result.returncode == 0, result.stderr
    payload, expected = json.loads(result.stdout), json.loads(good.stdout)
    assert set(payload) == JSON_KEYS | {"undecodable"}
    assert payload["undecodable"] == [{"topic": "/scan", "count": 3, "reason": CUT_SHORT}]
    assert expected["undecodable"] == []
    assert (payload["timeline"], payload["counts"]) == (expected["timeline"], expected["counts"])
    printed = dura("replay", str(bag), "--robot", str(robot))
    assert printed.returncode == 0, printed.stderr
    assert printed.stdout.splitlines()[-3:] == [
        "summary: 19.900 s replayed, 180 messages",
        f"  undecodable: /scan: 3 messages (the first: {CUT_SHORT})",
        "  nothing was diagnosed",
    ]


def test_a_recordings_undecodable_messages_are_reported_per_key(dura: Dura, tmp_path: Path) -> None:
    state = component("lidar", "state")
    ready = encode(ComponentState("lidar", Lifecycle.READY, stamp=T0).to_payload())
    rows = [(state, ready, "executive", 0.0)]
    rows += [(topic("scan"), encode({"stamp": T0 + k / 10}), "lidar", k / 10) for k in range(50)]
    rows += [(topic("scan"), b'{"stamp": ', "lidar", 2.5), (state, b"{}", "executive", 3.0)]
    path = record(tmp_path / "run.mcap", rows)
    result = dura("replay", str(path), "--robot", str(stamped_robot(tmp_path / "robot")), "--json")
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["undecodable"] == [
        {"topic": state, "count": 1, "reason": "not a component state (KeyError: 'component')"},
        {
            "topic": "topic/scan",
            "count": 1,
            "reason": "topic/scan: malformed payload (not JSON: Expecting value: line 1 column 11 "
            "(char 10))",
        },
    ]
