"""Bus logins: what the executive's Zenoh router keeps of components that logged in and left.

    python -m tests.benchmarks.bus_logins [--logins N] [--together K] [--warm-up N]

Four routers of the use case's bus (its access control, its credentials) run side by
side, each in a process of its own:

- with the C heap as glibc sets it up (the baseline of the heap);
- with the heap as ``dura run`` has it: malloc's arenas capped, and trimmed before each
  sample as its trimmer does every 30 s (:mod:`executive.runtime.native_heap`);
- as ``dura run`` has it, and subscribed to every topic as the executive's observers
  are, but on the key expressions the components subscribe (the baseline of the keys:
  as dura did before 0.2.0);
- the same on the executive's own key expressions, as ``dura run`` has them now
  (:func:`executive.bus.keys.listened_key`).

Short-lived client processes log in as the use case's components, ``--together`` at a
time (the executive starts a configuration's components at once), and do what a
component does on the bus: a liveliness token, a watch of the executive's, its
subscriptions, a command queryable, a message on each topic it publishes; then they
close the bus and end. Each login goes to the three routers in turn. After a warm-up (a
tenth of the logins, or ``--warm-up``), and at the end once the routers are idle, each
router's anonymous resident memory and malloc's bytes in use are sampled; the table
gives their growth per login.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from executive.bus import keys, security
from executive.bus.session import Bus
from executive.testing.harness import free_endpoint
from knowledge.robot import load_robot
from tests.benchmarks import heap_probe
from tests.conftest import USECASE

VARIANTS = ("glibc's defaults", "dura run's heap", "+ topics, components' keys",
            "+ topics, own keys (dura run)")  # fmt: skip
IDLE = 5.0  # seconds the routers are left alone before the last sample


def router(variant: int, endpoint: str, folder: Path) -> None:
    """A router of the use case's bus; prints its memory for every line on stdin."""
    from executive.runtime.native_heap import limit_arenas, trim

    if variant > 0:
        limit_arenas()
    topics = variant >= 2
    robot = load_robot(USECASE, domain=False)
    credentials = security.read_credentials(folder / "bus.json")
    access = security.access_control(robot.name, robot.components, topics=security.topics_of(robot))
    dictionary = security.dictionary(credentials, folder / f"dictionary{variant}")
    with Bus(robot.name, name="executive", endpoint=endpoint, listen=True,
             login=credentials.login(security.EXECUTIVE), dictionary=dictionary,
             access=access, component=variant == 2) as bus:  # fmt: skip
        bus.declare_alive(keys.EXECUTIVE_ALIVE)
        observed = {t for spec in robot.components.values() for t in spec.publishes}
        polled = [bus.poll(keys.topic(t)) for t in sorted(observed) if topics]
        print("ready", flush=True)
        for _ in sys.stdin:
            for queue in polled:
                queue.drain()
            if variant > 0:
                trim()
            print(json.dumps({"anonymous": _anonymous(), "in_use": _in_use()}), flush=True)


def client(endpoints: list[str], folder: Path, component: str, instance: str) -> None:
    """One component's login to each router in turn, as a component uses the bus."""
    robot = load_robot(USECASE, domain=False)
    spec = robot.components[component]
    login = security.read_credentials(folder / "bus.json").login(security.component_user(component))
    for endpoint in endpoints:
        with Bus(robot.name, name=component, endpoint=endpoint, login=login,
                 component=True) as bus:  # fmt: skip
            bus.declare_alive(keys.component_alive(component, instance))
            bus.watch_alive(keys.EXECUTIVE_ALIVE, lambda *_: None)
            for name in spec.subscribes:
                bus.subscribe(keys.topic(name), lambda *_: None)
            bus.serve(keys.component(component, "cmd"), lambda *_: None)
            for name in spec.publishes:
                bus.publish(keys.topic(name), {"data": 1})
    os._exit(0)


def _anonymous() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("RssAnon:"):
            return int(line.split()[1])
    return 0


def _in_use() -> int:
    heap = heap_probe.malloc()
    return 0 if heap is None else heap[0] >> 10


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--logins", type=int, default=400, help="component logins")
    parser.add_argument("--together", type=int, default=4, help="clients at a time")
    parser.add_argument("--warm-up", type=int, help="logins before measuring (a tenth)")
    parser.add_argument("--role", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.role:  # a router or a client of this benchmark
        role, *rest = args.role
        if role == "router":
            router(int(rest[0]), rest[1], Path(rest[2]))
        else:
            client(rest[2:], Path(rest[0]), rest[1], str(os.getpid()))
        return
    robot = load_robot(USECASE, domain=False)
    components = sorted(robot.components)
    me = [sys.executable, "-m", "tests.benchmarks.bus_logins", "--role"]
    with tempfile.TemporaryDirectory(prefix="dura-logins-") as name:
        folder = Path(name)
        security.ensure_credentials(folder / "bus.json", robot.name, components)
        endpoints = [free_endpoint() for _ in VARIANTS]
        routers = [subprocess.Popen([*me, "router", str(i), endpoint, name], text=True,
                                    stdin=subprocess.PIPE, stdout=subprocess.PIPE)
                   for i, endpoint in enumerate(endpoints)]  # fmt: skip
        try:
            for r in routers:
                assert r.stdout is not None and r.stdout.readline().strip() == "ready"
            warm_up = args.warm_up if args.warm_up is not None else max(1, args.logins // 10)
            began = time.monotonic()
            running: list[subprocess.Popen[bytes]] = []
            first: list[dict[str, int]] = []
            for n in range(args.logins + warm_up):
                if n == warm_up:
                    _settle(running)
                    first = _sample(routers)
                component = components[n % len(components)]
                running.append(subprocess.Popen([*me, "client", name, component, *endpoints]))
                while len(running) >= args.together:
                    running.pop(0).wait()
                if n % 50 == 0:
                    print(f"\r{n}/{args.logins + warm_up} logins", end="", file=sys.stderr)
            print(file=sys.stderr)
            _settle(running)
            last = _sample(routers)
        finally:
            for r in routers:
                r.kill()
                r.wait()
    print(f"{args.logins} component logins after a warm-up of {warm_up}, {args.together} "
          f"at a time, {time.monotonic() - began:.0f} s, routers idle {IDLE:g} s at the end")  # fmt: skip
    print(f"{'router heap':<30} {'anonymous KiB':>14} {'per login':>10} "
          f"{'malloc in use KiB':>18} {'per login':>10}")  # fmt: skip
    for variant, a, b in zip(VARIANTS, first, last, strict=True):
        grown, used = b["anonymous"] - a["anonymous"], b["in_use"] - a["in_use"]
        print(f"{variant:<30} {a['anonymous']:>6} -> {b['anonymous']:<5} "
              f"{grown / args.logins:>+10.2f} {a['in_use']:>8} -> {b['in_use']:<6} "
              f"{used / args.logins:>+10.2f}")  # fmt: skip


def _settle(running: list[subprocess.Popen[bytes]]) -> None:
    for process in running:
        process.wait()
    running.clear()
    time.sleep(IDLE)


def _sample(routers: list[subprocess.Popen[str]]) -> list[dict[str, int]]:
    out = []
    for r in routers:
        assert r.stdin is not None and r.stdout is not None
        r.stdin.write("sample\n")
        r.stdin.flush()
        out.append(json.loads(r.stdout.readline()))
    return out


if __name__ == "__main__":
    main()
