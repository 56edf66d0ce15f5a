"""A shared registry of diagnosis models with their expected diagnoses.

Each case is a model, the newest observations, whether OK observations exonerate,
and the expected status and minimal diagnoses. The engine, the CLI and the brute-force
reference are all checked against it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import yaml

from executive.bus.payloads import ObservationInfo
from monitoring.diagnosis.model import ModelObserver, Node, SystemDescription

# (type, resources, observation, caller ids)
Obs = tuple[str, tuple[str, ...], int, tuple[str, ...]]


def obs(kind: str, *resources: str, value: int = -1, callerids: tuple[str, ...] = ()) -> Obs:
    return (kind, resources, value, callerids)


def ok(kind: str, *resources: str, callerids: tuple[str, ...] = ()) -> Obs:
    return obs(kind, *resources, value=0, callerids=callerids)


@dataclass(frozen=True)
class Case:
    name: str
    nodes: tuple[tuple[str, tuple[str, ...], tuple[str, ...]], ...]  # name, sub, pub
    observers: tuple[
        tuple[str, tuple[str, ...], tuple[str, ...]], ...
    ]  # type, resources, callerids
    observations: tuple[Obs, ...]
    expected: tuple[tuple[str, ...], ...]
    status: str = "DIAGNOSED"
    exonerate: bool = False
    max_card: int | None = None
    conflicts: tuple[str, ...] = field(default=())

    @property
    def model(self) -> SystemDescription:
        return SystemDescription(
            tuple(Node(n, sub, pub) for n, sub, pub in self.nodes),
            tuple(ModelObserver.make(t, r, c) for t, r, c in self.observers),
        )

    @property
    def infos(self) -> list[ObservationInfo]:
        return [ObservationInfo(t, r, v, callerids=c) for t, r, v, c in self.observations]

    def write(self, folder: Path) -> tuple[Path, Path]:
        """MODEL.yaml and OBS.yaml for the command line."""
        model = folder / "model.yaml"
        model.write_text(
            yaml.safe_dump(
                {
                    "nodes": [
                        {"name": n, "sub_topic": list(s), "pub_topic": list(p)}
                        for n, s, p in self.nodes
                    ],
                    "observers": [
                        {"type": t, "resource": list(r), **({"callerids": list(c)} if c else {})}
                        for t, r, c in self.observers
                    ],
                }
            )
        )
        observations = folder / "obs.yaml"
        observations.write_text(
            yaml.safe_dump(
                {
                    "observations": [
                        {
                            "type": t,
                            "resource": list(r),
                            "observation": v,
                            **({"callerids": list(c)} if c else {}),
                        }
                        for t, r, v, c in self.observations
                    ]
                }
            )
        )
        return model, observations


# Thesis Figure 5.16: N1, N2 publish m1, m2; N3 turns them into m3; N4 turns m3 into m4.
THESIS_NODES = (
    ("N1", (), ("m1",)),
    ("N2", (), ("m2",)),
    ("N3", ("m1", "m2"), ("m3",)),
    ("N4", ("m3",), ("m4",)),
)
THESIS_OBSERVERS = (
    ("frequency", ("m1",), ()),
    ("frequency", ("m2",), ()),
    ("frequency", ("m3",), ()),
    ("resources", ("N3",), ()),
    ("component", ("N4",), ()),
    ("hz", ("m4",), ()),
    ("timing", ("m1", "m2"), ()),
)

# A cycle fed by a source: S -> s -> A -> a -> B -> b -> A.
CYCLE_NODES = (("S", (), ("s",)), ("A", ("s", "b"), ("a",)), ("B", ("a",), ("b",)))
CYCLE_OBSERVERS = (("frequency", ("s",), ()), ("frequency", ("a",), ()), ("frequency", ("b",), ()))

# Two publishers of one topic, told apart by caller ids; P1 depends on X.
CALLER_NODES = (
    ("X", (), ("x",)),
    ("P1", ("x",), ("t",)),
    ("P2", (), ("t",)),
    ("C", ("t",), ("c",)),
)
CALLER_OBSERVERS = (
    ("frequency", ("t",), ("P1",)),
    ("frequency", ("t",), ("P2",)),
    ("frequency", ("t",), ()),
    ("frequency", ("x",), ()),
    ("timeout", ("c",), ()),
)

# Wheel odometry and an IMU compared by a movement observer.
MOVE_NODES = (
    ("base", ("cmd",), ("odom",)),
    ("imu", (), ("imu",)),
    ("planner", ("odom",), ("cmd",)),
)
MOVE_OBSERVERS = (
    ("movement", ("odom", "imu"), ()),
    ("velocity", ("odom", "imu", "move_to"), ()),
    ("frequency", ("odom",), ()),
    ("frequency", ("imu",), ()),
)

CASES = (
    Case(
        "thesis: nothing failed", THESIS_NODES, THESIS_OBSERVERS, (ok("frequency", "m3"),), (), "OK"
    ),
    Case(
        "thesis: m3 fails, any upstream node explains it",
        THESIS_NODES,
        THESIS_OBSERVERS,
        (obs("frequency", "m3"),),
        (("N1",), ("N2",), ("N3",)),
    ),
    Case(
        "thesis: m3 and m4 fail, N4 is never needed",
        THESIS_NODES,
        THESIS_OBSERVERS,
        (obs("frequency", "m3"), obs("hz", "m4")),
        (("N1",), ("N2",), ("N3",)),
    ),
    Case(
        "thesis: resources of N3 blame N3 or its inputs",
        THESIS_NODES,
        THESIS_OBSERVERS,
        (obs("resources", "N3"),),
        (("N1",), ("N2",), ("N3",)),
    ),
    Case(
        "thesis: component N4 blames N4 only",
        THESIS_NODES,
        THESIS_OBSERVERS,
        (obs("component", "N4"), ok("hz", "m4")),
        (("N4",),),
    ),
    Case(
        "thesis: two independent faults need two nodes",
        THESIS_NODES,
        THESIS_OBSERVERS,
        (obs("component", "N4"), obs("frequency", "m3")),
        (("N1", "N4"), ("N2", "N4"), ("N3", "N4")),
    ),
    Case(
        "thesis: a size bound below every diagnosis lists none",
        THESIS_NODES,
        THESIS_OBSERVERS,
        (obs("component", "N4"), obs("frequency", "m3")),
        (),
        max_card=1,
    ),
    Case(
        "thesis: OK inputs exonerate nothing by default",
        THESIS_NODES,
        THESIS_OBSERVERS,
        (ok("frequency", "m1"), ok("frequency", "m2"), obs("frequency", "m3")),
        (("N1",), ("N2",), ("N3",)),
    ),
    Case(
        "thesis: OK inputs exonerate their publishers with exoneration on",
        THESIS_NODES,
        THESIS_OBSERVERS,
        (ok("frequency", "m1"), ok("frequency", "m2"), obs("frequency", "m3")),
        (("N3",),),
        exonerate=True,
    ),
    Case(
        "thesis: an OK output does not stop an abnormal input upstream",
        THESIS_NODES,
        THESIS_OBSERVERS,
        (obs("frequency", "m3"), ok("hz", "m4"), ok("frequency", "m1")),
        (("N2",), ("N3",)),
        exonerate=True,
    ),
    Case(
        "thesis: an OK node observation never exonerates",
        THESIS_NODES,
        THESIS_OBSERVERS,
        (ok("resources", "N3"), ok("component", "N4"), obs("hz", "m4")),
        (("N1",), ("N2",), ("N3",), ("N4",)),
        exonerate=True,
    ),
    Case(
        "thesis: timing blames either topic",
        THESIS_NODES,
        THESIS_OBSERVERS,
        (obs("timing", "m1", "m2"),),
        (("N1",), ("N2",)),
    ),
    Case(
        "thesis: a fault and an OK verdict on the same topic are inconsistent",
        THESIS_NODES,
        THESIS_OBSERVERS,
        (obs("timing", "m1", "m2"), ok("frequency", "m1"), ok("frequency", "m2"), ok("hz", "m4")),
        (),
        "INCONSISTENT",
        exonerate=True,
        conflicts=("frequency[m1]", "frequency[m2]", "timing[m1, m2]"),
    ),
    Case(
        "cycle: the cycle never explains itself",
        CYCLE_NODES,
        CYCLE_OBSERVERS,
        (obs("frequency", "a"),),
        (("A",), ("B",), ("S",)),
    ),
    Case(
        "cycle: exonerated feeds leave the node itself",
        CYCLE_NODES,
        CYCLE_OBSERVERS,
        (obs("frequency", "a"), ok("frequency", "b"), ok("frequency", "s")),
        (("A",),),
        exonerate=True,
    ),
    Case(
        "cycle: a fault inside the cycle reaches around it",
        CYCLE_NODES,
        CYCLE_OBSERVERS,
        (obs("frequency", "a"), obs("frequency", "b"), ok("frequency", "s")),
        (("A",), ("B",)),
        exonerate=True,
    ),
    Case(
        "caller ids: a failing publisher group blames only its publishers",
        CALLER_NODES,
        CALLER_OBSERVERS,
        (obs("frequency", "t", callerids=("P1",)),),
        (("P1",), ("X",)),
    ),
    Case(
        "caller ids: the other publisher's group blames the other publisher",
        CALLER_NODES,
        CALLER_OBSERVERS,
        (obs("frequency", "t", callerids=("P2",)), ok("frequency", "t", callerids=("P1",))),
        (("P2",),),
        exonerate=True,
    ),
    Case(
        "caller ids: an OK group exonerates only its publisher",
        CALLER_NODES,
        CALLER_OBSERVERS,
        (obs("timeout", "c"), ok("frequency", "t", callerids=("P1",)), ok("frequency", "x")),
        (("C",), ("P2",)),
        exonerate=True,
    ),
    Case(
        "movement: either motion source or the movement itself",
        MOVE_NODES,
        MOVE_OBSERVERS,
        (obs("velocity", "odom", "imu"),),
        (("base",), ("imu",), ("planner",), ("velocity",)),
    ),
    Case(
        "movement: good sources leave the behavior that slipped",
        MOVE_NODES,
        MOVE_OBSERVERS,
        (
            obs("movement", "odom", "imu", "move_to"),
            ok("frequency", "odom"),
            ok("frequency", "imu"),
        ),
        (("move_to",),),
        exonerate=True,
    ),
    Case(
        "minimal at node level: a node downstream of a faulty one is not added",
        (("n1", (), ("t1",)), ("n2", (), ("t2",)), ("n3", ("t1",), ("t3",))),
        (("frequency", ("t1",), ()), ("frequency", ("t3",), ()), ("frequency", ("t2",), ())),
        (obs("frequency", "t1"), obs("frequency", "t3")),
        (("n1",),),
    ),
)
