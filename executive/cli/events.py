"""``dura events [--follow] [--db FILE]``: the execution trace of a robot, live or from its
knowledge base file."""

from __future__ import annotations

import argparse
import json
import queue
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from executive.bus.api import planning as api
from executive.bus.event_text import line
from executive.bus.keys import EVENTS
from executive.bus.message import Message
from executive.bus.payloads import read_event
from executive.bus.schema import plain
from executive.bus.session import Bus
from executive.cli import exits_at_once
from executive.cli.arguments import count, event_kind
from executive.cli.client import add_client_options, connect
from executive.cli.output import add_json_flag, print_json

if TYPE_CHECKING:
    from knowledge.records import Event

PAGE = 1000  # events read at a time when catching up


def register(sub: Any) -> None:
    events = sub.add_parser(
        "events",
        help="the execution trace: goals, plans, dispatches, faults, repairs",
        description="Print the newest events of the knowledge base's log; with --follow, "
        "keep printing them as they happen until Ctrl-C. --db reads the log from a knowledge "
        "base file instead (a stopped robot's; a running robot's file may be read too).",
    )
    events.add_argument(
        "-n", "--lines", type=count, default=30, metavar="N", help="how many past events (30)"
    )
    events.add_argument(
        "--kind",
        type=event_kind,
        metavar="KIND",
        help="only events of this kind (e.g. FAIL, TASK_FAILED, COMPONENT_READY)",
    )
    events.add_argument("--follow", action="store_true", help="keep printing new events")
    events.add_argument(
        "--db", type=Path, metavar="FILE", help="read this knowledge base file, not a robot"
    )
    events.set_defaults(run=run_events, parser=events)
    exits_at_once(events)
    add_client_options(events)
    add_json_flag(events)


def run_events(args: argparse.Namespace) -> int:
    if args.db is not None:
        if args.robot is not None or args.endpoint is not None:
            args.parser.error("--db reads a file; --robot and --endpoint ask an executive")
        return _events_from_file(args)
    arrived: queue.Queue[Event] = queue.Queue()
    newest: list[Event] = []
    with connect(args) as bus:
        if args.follow:  # before the history, so that nothing falls between the two: the
            # stream has every event logged after the newest one read here
            bus.subscribe(EVENTS, lambda m: _arrived(m, arrived))
            newest = api.EVENTS.call(bus, api.EventQuery(limit=1)).events
        past = api.newest_events(bus, args.lines, args.kind)
        if args.json and not args.follow:
            print_json({"events": plain(past)})
            return 0
        for event in past:
            _show(event, args.json)
        if args.follow:
            _follow(bus, arrived, max((e.id for e in newest + past), default=0), args)
    return 0


POLL = 0.25  # seconds between two reads of a followed knowledge base file


def _events_from_file(args: argparse.Namespace) -> int:
    """``dura events --db FILE``: the log as the knowledge base file holds it; with
    ``--follow``, read it again every ``POLL`` seconds (readers never block a writer)."""
    from knowledge.knowledge_base import KnowledgeBase  # sqlite3: only with --db

    with KnowledgeBase(args.db, readonly=True) as kb:
        past = kb.events(limit=args.lines, kind=args.kind)
        if args.json and not args.follow:
            print_json({"events": plain(past)})
            return 0
        for event in past:
            _show(event, args.json)
        if not args.follow:
            return 0
        newest = kb.events(limit=1)
        last = max([e.id for e in past] + [e.id for e in newest], default=0)
        while True:
            time.sleep(POLL)
            for event in kb.events(after=last, limit=PAGE, oldest=True):
                last = event.id
                _print_followed(event, args)


def _follow(bus: Bus, arrived: queue.Queue[Event], last: int, args: argparse.Namespace) -> None:
    """Print events as they come, in order and without a gap: an event that arrives
    after a gap (the bus dropped some, or they came before the subscription) is
    preceded by the missing ones, read from the knowledge base by sequence number."""
    while True:
        try:
            event = arrived.get(timeout=0.5)
        except queue.Empty:
            continue
        number = event.id
        if number <= last:
            continue
        while last < number - 1:
            page = api.EVENTS.call(bus, api.EventQuery(after=last, limit=PAGE, oldest=True))
            missing = [e for e in page.events if e.id < number]
            if not missing:
                break  # not stored yet: the stream's own copies come later
            for old in missing:
                _print_followed(old, args)
            last = missing[-1].id
        _print_followed(event, args)
        last = number


def _print_followed(event: Event, args: argparse.Namespace) -> None:
    if not args.kind or event.kind == args.kind:
        _show(event, args.json)


def _arrived(message: Message, arrived: queue.Queue[Event]) -> None:
    event = read_event(message.payload)
    if event is not None:
        arrived.put(event)


def _show(event: Event, as_json: bool) -> None:
    print(json.dumps(plain(event), sort_keys=True) if as_json else line(event), flush=True)
