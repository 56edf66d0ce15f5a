"""Benchmark of the diagnosis engine against the thesis' method and a lower bound.

    python -m tests.benchmarks.diagnosis [--instances N] [--anchor-limit SECONDS]

Models: a chain of 20 nodes with 2 faults, and layered models of 20, 200, 1000 and
5000 nodes (six layers; each node subscribes 1-2 topics of the layer before it, from
nearby positions, and publishes one topic; a frequency observer on every topic).
Faults: 1-3 random nodes; every output of a faulty node is abnormal, and an abnormal
input makes a node's output abnormal with probability 0.7. Observations: failed where
abnormal, OK elsewhere (exoneration off, the thesis model).

Columns (milliseconds, median over the instances of a size; no time bound, so that
every diagnosis can be checked: a bound costs nothing until it runs out):
- model: the model update (``DiagnosisEngine.set_model``: checks and indexes; regions
  are grounded when a diagnosis needs them);
- observe: every observation arrives (``observe``, one call each);
- diagnose: the first diagnosis (all minimal diagnoses) of those observations: the
  conflicts of the failed ones (upstream cones), merged into classes, clingo's minimal
  hitting sets over them, expanded;
- re-diag: the same engine after one observation changed, for 10 random observations
  changed and changed back (cones are kept per model, the grounded hitting-set template
  per process);
- full: model + observe + diagnose, a diagnosis from scratch;
- HS-DAG: the tug implementation's method (Reiter's HS-tree as a DAG after Greiner),
  one fresh clingo control per DAG node for its consistency check (PyMBD used a SAT
  solver the same way); cut off after ``--anchor-limit`` seconds (shown as "> X");
- Berge: minimal hitting sets of the failed observations' upstream cones, computed
  directly (no solver): the lower bound.
Every method's diagnoses are checked against Berge's.

Last, a model with very many diagnoses (a root and 2**k alternatives) under a time
bound of 100 ms: how many diagnoses came back, and whether the smallest is among them.
"""

from __future__ import annotations

import argparse
import random
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

from executive.bus.payloads import ObservationInfo
from knowledge.asp import Asp, atom, facts
from monitoring.diagnosis.engine import DiagnosisEngine
from monitoring.diagnosis.model import ModelObserver, Node, SystemDescription
from monitoring.diagnosis.result import DiagnosisResult, Status

LAYERS = 6
PROPAGATION = 0.7
FLIPS = 10  # observations changed (and changed back) per instance for re-diagnosis


@dataclass
class Instance:
    name: str
    model: SystemDescription
    observations: list[ObservationInfo]
    faults: tuple[str, ...]


def chain(length: int, faults: int, seed: int) -> Instance:
    nodes = [Node("n0", (), ("t0",))]
    nodes += [Node(f"n{i}", (f"t{i - 1}",), (f"t{i}",)) for i in range(1, length)]
    return inject(f"chain {length}", nodes, faults, seed)


def layered(size: int, faults: int, seed: int) -> Instance:
    rng = random.Random(seed)
    width = max(2, size // LAYERS)
    nodes: list[Node] = []
    for layer in range(LAYERS):
        count = width if layer < LAYERS - 1 else size - width * (LAYERS - 1)
        for i in range(count):
            name = f"n{layer}_{i}"
            if layer == 0:
                nodes.append(Node(name, (), (f"t{layer}_{i}",)))
                continue
            center = i * width // max(count, 1)
            near = [j for j in range(center - 1, center + 2) if 0 <= j < width]
            inputs = rng.sample(near, k=min(len(near), rng.randint(1, 2)))
            subs = tuple(f"t{layer - 1}_{j}" for j in sorted(inputs))
            nodes.append(Node(name, subs, (f"t{layer}_{i}",)))
    return inject(f"layered {size}", nodes, faults, seed)


def inject(name: str, nodes: list[Node], faults: int, seed: int) -> Instance:
    """Faulty nodes, abnormal topics propagated downstream, observations of every topic."""
    rng = random.Random(seed * 7919 + faults)
    faulty = set(rng.sample([n.name for n in nodes], faults))
    abnormal: set[str] = set()
    for node in nodes:  # nodes are in topological order
        if node.name in faulty or (
            any(t in abnormal for t in node.sub_topic) and rng.random() < PROPAGATION
        ):
            abnormal.update(node.pub_topic)
    topics = [t for n in nodes for t in n.pub_topic]
    model = SystemDescription(
        tuple(nodes), tuple(ModelObserver.make("frequency", [t]) for t in topics)
    )
    observations = [
        ObservationInfo("frequency", (t,), -1 if t in abnormal else 0, stamp=1.0) for t in topics
    ]
    return Instance(name, model, observations, tuple(sorted(faulty)))


# --- lower bound: Berge's minimal hitting sets of upstream cones -----------------------


def cones(instance: Instance) -> list[frozenset[str]]:
    """The nodes upstream of (and publishing) each failed observation's topic."""
    model = instance.model
    memo: dict[str, frozenset[str]] = {}

    def cone(topic: str) -> frozenset[str]:
        if topic not in memo:
            memo[topic] = frozenset()  # a cycle contributes nothing new
            found: set[str] = set()
            for publisher in model.publishers(topic):
                found.add(publisher)
                node = model.node(publisher)
                for t in node.sub_topic if node else ():
                    found |= cone(t)
            memo[topic] = frozenset(found)
        return memo[topic]

    return [cone(o.resource[0]) for o in instance.observations if o.failed]


def berge(sets: list[frozenset[str]]) -> set[frozenset[str]]:
    """All minimal hitting sets, one set at a time (a new element must keep each old one's
    private set)."""
    edges = sorted(set(sets), key=len)
    edges = [e for e in edges if not any(o < e for o in edges)]
    hitting: list[frozenset[str]] = [frozenset()]
    for i, edge in enumerate(edges):
        earlier = edges[:i]
        grown: list[frozenset[str]] = []
        for h in hitting:
            if h & edge:
                grown.append(h)
                continue
            for s in edge:
                t = h | {s}
                if all(any(e & t == {x} for e in earlier) for x in h):
                    grown.append(t)
        hitting = list(set(grown))
    return set(hitting)


def lower_bound(instance: Instance) -> set[frozenset[str]]:
    return berge(cones(instance))


# --- the anchor: HS-DAG with one fresh solver call per node ---------------------------

# The thesis' clauses (5.1) with the observer clauses, as tug handed them to a SAT solver.
THEORY = """
{ ab_node(N) } :- node(N).
{ ab_topic(M) } :- topic(M).
:- ab_node(N), pub(N,M), not ab_topic(M).
source(M) :- pub(N,M), ab_node(N).
source(M) :- pub(N,M), sub(N,I), ab_topic(I).
:- ab_topic(M), not source(M).
:- failed(M), not ab_topic(M).
"""


class Cutoff(Exception):
    pass


def hs_dag(instance: Instance, limit: float) -> tuple[set[frozenset[str]], int]:
    """All minimal diagnoses by HS-DAG; returns them and the number of solver calls."""
    model = instance.model
    base = facts(
        [atom("node", n.name) for n in model.nodes]
        + [atom("topic", t) for n in model.nodes for t in n.pub_topic]
        + [atom("pub", n.name, t) for n in model.nodes for t in n.pub_topic]
        + [atom("sub", n.name, t) for n in model.nodes for t in n.sub_topic]
        + [atom("failed", o.resource[0]) for o in instance.observations if o.failed]
    )
    names = [n.name for n in model.nodes]
    deadline = time.perf_counter() + limit
    calls = 0

    def check(path: frozenset[str]) -> frozenset[str] | None:
        """A conflict among the nodes outside the path, or None if the path is a diagnosis."""
        nonlocal calls
        if time.perf_counter() > deadline:
            raise Cutoff
        calls += 1
        asp = Asp(["1"])
        asp.add(THEORY + base)
        asp.ground()
        assumptions = [(atom("ab_node", n), False) for n in names if n not in path]
        outcome = asp.solve(assumptions=assumptions)
        if outcome.satisfiable:
            return None
        return frozenset(str(s.arguments[0].string) for s in outcome.core)

    labels: dict[frozenset[str], frozenset[str] | None] = {}
    conflicts: list[frozenset[str]] = []
    found: set[frozenset[str]] = set()
    level: list[frozenset[str]] = [frozenset()]
    while level:
        following: dict[frozenset[str], None] = {}
        for path in level:
            if any(d <= path for d in found):
                continue  # closed: a diagnosis is already below it
            reused = next((c for c in conflicts if not c & path), None)
            label = reused if reused is not None else check(path)
            labels[path] = label
            if label is None:
                found.add(path)
                continue
            if reused is None:
                conflicts.append(label)
            for c in sorted(label):
                following.setdefault(path | {c})  # a path reached twice is one DAG node
        level = list(following)
    return {d for d in found if not any(o < d for o in found)}, calls


# --- running -----------------------------------------------------------------------------


def timed(function: Callable[[], object]) -> tuple[float, object]:
    start = time.perf_counter()
    value = function()
    return time.perf_counter() - start, value


def found_sets(result: DiagnosisResult) -> set[frozenset[str]]:
    """The diagnoses as sets; with nothing failed (OK) the empty set is the one diagnosis."""
    if result.status is Status.OK:
        return {frozenset()}
    return {frozenset(d) for d in result.diagnoses}


def clingo_first(
    instance: Instance,
) -> tuple[float, float, float, DiagnosisEngine, set[frozenset[str]]]:
    """Seconds to load the model, to take in every observation and to diagnose them;
    the engine; the diagnoses."""
    seconds_model, engine = timed(lambda: DiagnosisEngine(instance.model))
    assert isinstance(engine, DiagnosisEngine)

    def observe() -> None:
        for info in instance.observations:
            engine.observe(info)

    seconds_observe, _ = timed(observe)
    seconds_diagnose, result = timed(engine.diagnose)
    assert isinstance(result, DiagnosisResult)
    return seconds_model, seconds_observe, seconds_diagnose, engine, found_sets(result)


def rediagnose(
    instance: Instance, engine: DiagnosisEngine, expected: set[frozenset[str]], seed: int
) -> list[float]:
    """Change one observation and re-diagnose, then change it back and re-diagnose, for
    ``FLIPS`` random observations; the seconds of each re-diagnosis (each checked)."""
    rng = random.Random(seed)
    seconds: list[float] = []
    for flip in range(FLIPS):
        info = rng.choice(instance.observations)
        flipped = ObservationInfo(
            info.type, info.resource, 0 if info.failed else -1, stamp=2.0 + flip
        )
        changed = [flipped if o is info else o for o in instance.observations]
        wanted = lower_bound(Instance(instance.name, instance.model, changed, instance.faults))
        back = ObservationInfo(info.type, info.resource, info.observation, stamp=2.5 + flip)
        for observation, answer in ((flipped, wanted), (back, expected)):
            engine.observe(observation)
            took, result = timed(engine.diagnose)
            if found_sets(result) != answer:  # type: ignore[arg-type]
                raise SystemExit(f"{instance.name} seed {seed}: re-diagnosis disagrees with Berge")
            seconds.append(took)
    return seconds


def fan(topics: int) -> Instance:
    """One root feeding ``topics`` topics with two publishers each, every topic failed:
    {root} and the 2**topics choices of one publisher per topic are the diagnoses."""
    nodes = [Node("root", (), ("r",))]
    for i in range(topics):
        nodes += [Node(f"a{i}", ("r",), (f"m{i}",)), Node(f"b{i}", ("r",), (f"m{i}",))]
    model = SystemDescription(
        tuple(nodes), tuple(ModelObserver.make("frequency", [f"m{i}"]) for i in range(topics))
    )
    failed = [ObservationInfo("frequency", (f"m{i}",), -1) for i in range(topics)]
    return Instance(f"fan {topics}", model, failed, ("root",))


def time_bounded(bound: float) -> None:
    """Very many diagnoses under a time bound: is the smallest one among those found?"""
    print(f"\nvery many diagnoses, time bound {bound * 1000:g} ms")
    print("model   diagnoses  all (ms)  status    found  {root} found  elapsed (ms)")
    for topics in (16, 18, 22, 26):
        instance = fan(topics)
        if topics <= 18:
            engine = DiagnosisEngine(instance.model)
            for info in instance.observations:
                engine.observe(info)
            seconds, every = timed(engine.diagnose)
            assert isinstance(every, DiagnosisResult)
            total, all_ms = str(len(every.diagnoses)), f"{seconds * 1000:.0f}"
        else:
            total, all_ms = str(2**topics + 1), "-"
        engine = DiagnosisEngine(instance.model, timeout=bound)
        for info in instance.observations:
            engine.observe(info)
        seconds, result = timed(engine.diagnose)
        assert isinstance(result, DiagnosisResult)
        print(
            f"{instance.name:<8}{total:>9}{all_ms:>10}  {result.status.value:<9}"
            f"{len(result.diagnoses):>6}  {'yes' if ('root',) in result.diagnoses else 'NO':>12}"
            f"{seconds * 1000:>14.1f}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--instances", type=int, default=5, help="instances per size")
    parser.add_argument("--anchor-limit", type=float, default=10.0, help="seconds per HS-DAG run")
    args = parser.parse_args()
    suites: list[tuple[str, list[Instance]]] = [
        ("chain 20, 2 faults", [chain(20, 2, s) for s in range(args.instances)]),
    ]
    for size in (20, 200, 1000, 5000):
        suites.append(
            (
                f"layered {size}, 1-3 faults",
                [layered(size, 1 + s % 3, s) for s in range(args.instances)],
            )
        )
    columns = (
        "instances",
        "diagnoses",
        "model",
        "observe",
        "diagnose",
        "re-diag",
        "full",
        "HS-DAG",
        "calls",
        "Berge",
    )
    widths = (26, 10, 7, 8, 9, 8, 8, 10, 7, 8)
    print(
        "".join(
            c.rjust(w) if i else c.ljust(w)
            for i, (c, w) in enumerate(zip(columns, widths, strict=True))
        )
    )
    print("-" * sum(widths))
    summary: dict[str, dict[str, float]] = {}
    for title, instances in suites:
        times: dict[str, list[float]] = {
            k: [] for k in ("model", "observe", "diagnose", "again", "anchor", "bound")
        }
        calls: list[int] = []
        counts: list[int] = []
        cut = False
        for seed, instance in enumerate(instances):
            model, observe, diagnose, engine, found = clingo_first(instance)
            times["model"].append(model)
            times["observe"].append(observe)
            times["diagnose"].append(diagnose)
            seconds, expected = timed(lambda i=instance: lower_bound(i))  # type: ignore[misc]
            times["bound"].append(seconds)
            if found != expected:
                raise SystemExit(f"{instance.name} seed {seed}: clingo and Berge disagree")
            counts.append(len(found))
            times["again"] += rediagnose(instance, engine, expected, seed)
            if not cut:
                try:
                    seconds, (hs, n) = timed(lambda i=instance: hs_dag(i, args.anchor_limit))  # type: ignore[misc]
                except Cutoff:
                    cut = True
                else:
                    if hs != expected:
                        raise SystemExit(f"{instance.name} seed {seed}: HS-DAG and Berge disagree")
                    times["anchor"].append(seconds)
                    calls.append(n)
        med = {k: statistics.median(v) * 1000 for k, v in times.items() if v}
        parts = zip(times["model"], times["observe"], times["diagnose"], strict=True)
        med["full"] = statistics.median(sum(p) for p in parts) * 1000
        if cut:
            med["anchor"] = args.anchor_limit * 1000
        summary[title] = med
        cells = (
            title,
            f"{min(counts)}-{max(counts)}",
            f"{med['model']:.2f}",
            f"{med['observe']:.2f}",
            f"{med['diagnose']:.2f}",
            f"{med['again']:.2f}",
            f"{med['full']:.2f}",
            (">" if cut else "") + f"{med['anchor']:.1f}",
            "-" if cut else str(int(statistics.median(calls))),
            f"{med['bound']:.2f}",
        )
        print(
            "".join(
                c.rjust(w) if i else c.ljust(w)
                for i, (c, w) in enumerate(zip(cells, widths, strict=True))
            )
        )
    chain20 = summary["chain 20, 2 faults"]
    big = summary["layered 1000, 1-3 faults"]
    print()
    print(
        f"HS-DAG / clingo on the chain (target >= 100x): "
        f"{chain20['anchor'] / chain20['again']:.0f}x per re-diagnosis, "
        f"{chain20['anchor'] / chain20['diagnose']:.0f}x per first diagnosis, "
        f"{chain20['anchor'] / chain20['full']:.0f}x from scratch"
    )
    print(
        f"1000 nodes: diagnose {big['diagnose']:.1f} ms (target <= 20), re-diagnose "
        f"{big['again']:.1f} ms (target <= 5), full {big['full']:.1f} ms"
    )
    print(
        f"1000 nodes: diagnose / Berge {big['diagnose'] / big['bound']:.1f}x, "
        f"full / Berge {big['full'] / big['bound']:.1f}x (target <= 5x)"
    )
    time_bounded(0.1)


if __name__ == "__main__":
    main()
