"""The bus between two real processes: pub/sub with caller ids, request/reply, errors."""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest
import zenoh

from executive.bus.keys import listened_key
from executive.bus.message import Message
from executive.bus.session import Bus, check_name, session_config
from knowledge.errors import BusError
from tests.conftest import ROOT, wait_for


@pytest.fixture
def executive_bus(endpoint: str) -> Iterator[Bus]:
    with Bus("testbot", name="executive", endpoint=endpoint, listen=True) as bus:
        yield bus


@pytest.fixture
def peer(executive_bus: Bus) -> Iterator[subprocess.Popen[str]]:
    process = subprocess.Popen(
        [sys.executable, "-m", "tests.executive.bus.bus_peer", "testbot", executive_bus.endpoint],
        stdout=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    )
    assert process.stdout is not None
    assert process.stdout.readline().strip() == "ready"
    # Its queryables reach the router a moment after it says so: wait until they answer.
    assert wait_for(lambda: _answers(executive_bus), 10.0)
    yield process
    try:
        executive_bus.request("test/stop", timeout=2)
    except BusError:
        process.kill()
    process.wait(10)
    process.stdout.close()


def _answers(bus: Bus) -> bool:
    try:
        bus.request("test/echo", timeout=0.5)
    except BusError:
        return False
    return True


def test_a_request_to_another_process_gets_its_reply(executive_bus: Bus, peer: object) -> None:
    reply = executive_bus.request("test/echo", {"x": [1, 2]})
    assert reply == {"echo": {"x": [1, 2]}, "from": "peer"}


def test_an_error_in_the_other_process_comes_back_as_its_message(
    executive_bus: Bus, peer: object
) -> None:
    with pytest.raises(BusError, match=r"^refused: because$"):
        executive_bus.request("test/echo", {"fail": "because"})


def test_messages_from_another_process_carry_its_caller_id_and_stamps(
    executive_bus: Bus, peer: object
) -> None:
    got: list[Message] = []
    executive_bus.subscribe("topic/chatter", got.append)
    # A new subscription reaches the publisher a moment later: wait until one arrives.
    assert wait_for(lambda: executive_bus.request("test/chatter", {"count": 1}) and got, 10.0)
    assert executive_bus.request("test/chatter", {"count": 50, "run": "main"}) == {"sent": 50}
    assert wait_for(lambda: len([m for m in got if m.payload["run"] == "main"]) == 50)
    main = [m for m in got if m.payload["run"] == "main"]
    assert [m.payload["i"] for m in main] == list(range(50))
    first = main[0]
    assert first.caller_id == "peer" and first.key == "topic/chatter"
    assert first.stamp is not None and first.sent is not None
    assert abs(first.sent - first.stamp) < 1.0 and first.received >= first.stamp


def test_the_routers_large_messages_take_no_shared_memory_pool(
    executive_bus: Bus, peer: object
) -> None:
    """Zenoh puts a message above 3 KiB to a process on the same machine in a shared
    memory pool of 16 MiB, all of it resident from the first such message; the
    executive's control plane (its events and replies) goes without one."""
    executive_bus.request("test/listen", {"key": "topic/large"})
    assert executive_bus.wait_for_subscriber("topic/large", timeout=10)

    def heard_another() -> bool:  # a burst of large messages may be dropped: one at a time
        executive_bus.publish("topic/large", {"x": "a" * 64_000})
        return bool(executive_bus.request("test/heard", {"key": "topic/large"})["count"] >= 20)

    assert wait_for(heard_another, 20.0)
    assert _shared_memory_kib() < 1024


def _shared_memory_kib() -> int:
    """Resident KiB of this process's mappings of Zenoh's shared memory files."""
    total, zenoh_file = 0, False
    for line in Path("/proc/self/smaps").read_text().splitlines():
        fields = line.split()
        if "-" in fields[0] and ":" in fields[3]:  # a mapping's first line
            zenoh_file = fields[-1].endswith(".zenoh")
        elif fields[0] == "Rss:" and zenoh_file:
            total += int(fields[1])
    return total


def test_a_publisher_waits_until_a_subscriber_in_another_process_listens(
    executive_bus: Bus, endpoint: str, peer: object
) -> None:
    with Bus("testbot", name="talker", endpoint=endpoint) as talker:
        assert not talker.wait_for_subscriber("topic/news", timeout=0.2)  # nobody listens
        executive_bus.request("test/listen", {"key": "topic/news"})
        assert talker.wait_for_subscriber("topic/news", timeout=10)
        talker.publish("topic/news", {"n": 1})  # at once and once: it must arrive
        assert wait_for(
            lambda: executive_bus.request("test/heard", {"key": "topic/news"})["count"] == 1
        )


def test_a_malformed_payload_is_dropped_and_the_subscriber_lives_on(
    executive_bus: Bus, endpoint: str
) -> None:
    got: list[Message] = []
    executive_bus.subscribe("topic/data", got.append)
    with zenoh.open(session_config(connect=(endpoint,))) as raw:
        for payload in (b"not json", b"[1, 2]", b'{"ok": 1}'):
            raw.put("dura/testbot/from/raw/topic/data", payload)
        # from one session to one subscriber in order: the first two came before the last
        assert wait_for(lambda: any(m.raw == b'{"ok": 1}' for m in got))
    assert [m.payload for m in got] == [{"ok": 1}]


def test_a_failing_handler_does_not_stop_the_subscription(
    executive_bus: Bus, endpoint: str
) -> None:
    got: list[int] = []

    def handler(message: Message) -> None:
        if message.payload["i"] == 0:
            raise RuntimeError("boom")
        got.append(message.payload["i"])

    executive_bus.subscribe("topic/x", handler)
    with Bus("testbot", name="other", endpoint=endpoint) as other:
        other.publish("topic/x", {"i": 0})
        other.publish("topic/x", {"i": 1})
        assert wait_for(lambda: got == [1])


def test_a_request_nobody_serves_times_out_with_a_clear_error(executive_bus: Bus) -> None:
    with pytest.raises(BusError, match=r"no answer on dura/testbot/nobody within 0.3 s"):
        executive_bus.request("nobody", timeout=0.3)


def test_connecting_without_an_executive_fails_at_once(endpoint: str) -> None:
    started = time.monotonic()
    with pytest.raises(BusError, match=f"no executive for robot 'testbot' at {endpoint}"):
        Bus("testbot", endpoint=endpoint)
    assert time.monotonic() - started < 5


def test_a_second_executive_cannot_listen_on_the_same_endpoint(executive_bus: Bus) -> None:
    with pytest.raises(BusError, match="is an executive already running"):
        Bus("testbot", endpoint=executive_bus.endpoint, listen=True)


def test_liveliness_tells_when_a_process_vanishes(executive_bus: Bus, endpoint: str) -> None:
    changes: list[tuple[str, bool]] = []
    lock = threading.Lock()

    def on_change(key: str, alive: bool) -> None:
        with lock:
            changes.append((key, alive))

    executive_bus.watch_alive("alive/**", on_change)
    other = Bus("testbot", name="lidar", endpoint=endpoint)
    other.declare_alive("alive/lidar")
    assert wait_for(lambda: ("alive/lidar", True) in changes)
    other.close()
    assert wait_for(lambda: ("alive/lidar", False) in changes)


@pytest.mark.parametrize("name", ["a*b", "x y", "", "a$b", "a//b"])
def test_names_that_are_not_valid_keys_are_refused(name: str) -> None:
    with pytest.raises(BusError, match="invalid"):
        check_name(name)


def test_a_polled_message_waits_for_its_taker_and_arrives_on_the_takers_clock(
    executive_bus: Bus, endpoint: str
) -> None:
    polled = executive_bus.poll("topic/data")
    with zenoh.open(session_config(connect=(endpoint,))) as far:  # its clock 2 s behind
        behind = datetime.now(UTC) - timedelta(seconds=2)
        stamp = zenoh.Timestamp(behind, zenoh.TimestampId(bytes(range(1, 17))))
        before = time.time_ns()
        far.put("dura/testbot/from/far/topic/data", b'{"i": 0}', timestamp=stamp)
        got: list[Message] = []
        assert wait_for(lambda: bool(got.extend(polled.drain()) or got))
    [message] = got
    assert (message.caller_id, message.payload) == ("far", {"i": 0})
    assert message.sent_ns is not None and message.sent_ns < before - 1_000_000_000
    assert message.received_ns >= before  # not 2 s ago: the sender's clock does not count
    polled.undeclare()


@pytest.mark.parametrize("polled", [False, True], ids=["subscribed", "polled"])
def test_the_executive_hears_a_topic_on_keys_no_component_declares_and_only_that_topic(
    executive_bus: Bus, endpoint: str, polled: bool
) -> None:
    """Its subscriptions match ``from/**/...``: what they match of other topics (a
    topic named ``x/topic/data``, or ``topic/data`` of a ``topic/*``) is not theirs."""
    exact: list[Message] = []
    each: list[Message] = []
    if polled:
        queues = [executive_bus.poll("topic/data"), executive_bus.poll("topic/*")]
    else:
        executive_bus.subscribe("topic/data", exact.append)
        executive_bus.subscribe("topic/*", each.append)
    with zenoh.open(session_config(connect=(endpoint,))) as raw:
        for key in ("from/s/x/topic/data", "from/s/topic/topic/data", "from/s/topic/data"):
            raw.put(f"dura/testbot/{key}", f'{{"key": "{key}"}}'.encode())
        if polled:
            assert wait_for(lambda: bool(exact.extend(queues[0].drain()) or exact))
            time.sleep(0.2)  # the other two came first, from the same session: a margin
            exact.extend(queues[0].drain())
            each.extend(queues[1].drain())
        else:
            assert wait_for(lambda: exact and each)
            time.sleep(0.2)
    assert [(m.key, m.caller_id) for m in exact] == [("topic/data", "s")]
    assert [(m.key, m.caller_id) for m in each] == [("topic/data", "s")]


def test_a_component_and_the_executive_never_subscribe_the_same_key_expression() -> None:
    """Zenoh's router (1.10) keeps a closed session's state while another session
    subscribes the wildcard key expression it subscribed, or one under it: a component, which
    comes and goes at every start, must share neither with the executive."""
    for key in ("topic/scan", "topic/camera/image", "topic/*", "topic/**"):
        theirs = zenoh.KeyExpr(listened_key(key))
        ours = zenoh.KeyExpr(listened_key(key, component=False))
        assert str(theirs) != str(ours)
        assert not str(ours).startswith(f"{theirs}/")
        assert ours.includes(theirs)  # the executive hears all the component hears
