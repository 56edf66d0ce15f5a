"""``dura diagnose MODEL.yaml --observations OBS.yaml``: diagnose offline."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from executive.cli.arguments import count, seconds
from executive.cli.output import add_json_flag, print_json
from monitoring.diagnosis.engine import DiagnosisEngine
from monitoring.diagnosis.reader import read_model, read_observations
from monitoring.diagnosis.result import Status


def register(sub: Any) -> None:
    p = sub.add_parser(
        "diagnose",
        help="diagnose a model against observations (offline)",
        description="Compute all subset-minimal diagnoses of a diagnosis model for a set of "
        "observations, as the running diagnosis engine would. Exit 0 on any result, 1 on "
        "invalid input.",
    )
    p.add_argument("model", metavar="MODEL.yaml", type=Path, help="nodes and observers")
    p.add_argument(
        "--observations", metavar="OBS.yaml", type=Path, required=True, help="the observations"
    )
    p.add_argument(
        "--exonerate", action="store_true", help="an OK topic observation clears that topic"
    )
    p.add_argument("--max-card", metavar="K", type=count, help="only diagnoses of at most K names")
    p.add_argument("--timeout", metavar="SECONDS", type=seconds(), help="stop after this long")
    add_json_flag(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    model = read_model(args.model)
    engine = DiagnosisEngine(
        model, exonerate=args.exonerate, max_card=args.max_card, timeout=args.timeout
    )
    for info in read_observations(args.observations, model):
        engine.observe(info)
    result = engine.diagnose()
    if args.json:
        data: dict[str, Any] = {
            "status": result.status.value,
            "diagnoses": sorted(list(d) for d in result.diagnoses),
        }
        if result.status is Status.INCONSISTENT:
            data["conflicts"] = [str(o) for o in result.conflicts]
        print_json(data)
        return 0
    count = len(result.diagnoses)
    print(
        f"{result.status.value}: {count} minimal diagnos{'i' if count == 1 else 'e'}s "
        f"({result.elapsed * 1000:.1f} ms)"
    )
    if result.failed:
        print("failed: " + "; ".join(str(o) for o in result.failed))
    if result.conflicts:
        print("conflicting: " + "; ".join(str(o) for o in result.conflicts))
    for i, diagnosis in enumerate(result.diagnoses, 1):
        print(f"  {i}. {', '.join(diagnosis)}")
    return 0
