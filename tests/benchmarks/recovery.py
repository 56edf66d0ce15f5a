"""Crash recovery benchmark: kill ``dura run`` at random moments, round after round, and
check the facts against a replay of the event log after each kill and each restart.

    python -m tests.benchmarks.recovery [--rounds 200] [--seed 15]

One robot (the use case with short actions) on one knowledge base: each round starts the
executive, gives it a goal and often a second one while the first plan runs (a replan),
SIGKILLs it at a random moment, and checks (see :mod:`tests.e2e.kill_rounds`). Prints a
table: facts correct / rounds, after the kill and after the restart, how many kills came
while a step ran and after a replan, and the rounds that went wrong, if any.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

from executive.cli.output import section, table
from tests.e2e.kill_rounds import KillRounds, Round


def kill_rounds(count: int, *, seed: int = 15, longest: float = 3.0) -> list[Round]:
    """Run ``count`` kill rounds on one knowledge base; each round as it ends is printed."""
    with tempfile.TemporaryDirectory(prefix="dura-recovery-") as tmp:
        rounds = KillRounds(Path(tmp), seed=seed)
        try:
            for _ in range(count):
                done = rounds.round(longest)
                mark = "ok" if not done.left else "WRONG"
                print(f"round {done.number}: {mark} ({done.did})", flush=True)
            rounds.final_check()
        finally:
            rounds.close()
    return rounds.rounds


def rounds(count: int) -> tuple[int, int, str]:
    """For :mod:`tests.benchmarks.reliability`: the rounds whose facts were right after
    the kill and after the restart, the rounds, and what they covered."""
    done = kill_rounds(count)
    correct = sum(not r.problems for r in done)
    mid_step = [r for r in done if r.running]
    replanned = sum(r.replanned_mid_step for r in mid_step)
    return correct, len(done), f"{len(mid_step)} while a step ran, {replanned} after a replan"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rounds", type=int, default=200)
    parser.add_argument("--seed", type=int, default=15)
    parser.add_argument(
        "--longest", type=float, default=3.0, help="latest kill after the first goal (seconds)"
    )
    args = parser.parse_args()
    began = time.monotonic()
    done_rounds = kill_rounds(args.rounds, seed=args.seed, longest=args.longest)
    n = len(done_rounds)
    after_kill = sum(not r.left for r in done_rounds)
    after_restart = sum(r.recovered == [] for r in done_rounds)
    mid_step = [r for r in done_rounds if r.running]
    replanned = [r for r in mid_step if r.replanned_mid_step]
    two_places = sum(any("places" in p for p in r.problems) for r in done_rounds)
    seconds = [r.seconds for r in done_rounds]
    section(
        f"crash recovery: {n} kills of dura run at random moments (use case, short actions, "
        f"seed {args.seed}, {time.monotonic() - began:.0f} s)"
    )
    table(
        ["check", "result"],
        [
            ["facts correct after the kill / rounds", f"{after_kill} / {n}"],
            ["facts correct after the restart / rounds", f"{after_restart} / {n}"],
            ["kills while a step ran", len(mid_step)],
            ["... of them after a replan", len(replanned)],
            ["robot in two places", two_places],
            ["seconds per round (p50)", f"{statistics.median(seconds):.1f}"],
        ],
    )
    wrong = [r for r in done_rounds if r.problems]
    if wrong:
        section("rounds that went wrong")
        for r in wrong:
            print(f"round {r.number} ({r.did}): {'; '.join(r.problems)}")


if __name__ == "__main__":
    main()
