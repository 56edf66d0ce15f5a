"""A recorder that records until it is killed: ``python -m tests.executive.bags.recorder_child
OUT.mcap``. It writes scan message number k at 100 Hz (recorded time ``T0 + k / 100``,
payload ``{"stamp": ..., "k": k}``) and prints ``flushed N`` each time the first N
messages are on disk in whole chunks."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from executive.bags.recording import Recorder
from executive.bus.keys import topic
from executive.bus.message import Message, encode

T0 = 1_700_000_000.0
RATE = 100.0


def message(k: int) -> Message:
    t = T0 + k / RATE
    return Message(topic("scan"), encode({"stamp": t, "k": k}), "lidar", t, t)


def main() -> None:
    recorder = Recorder(Path(sys.argv[1]), "usecase", flush_every=float(sys.argv[2]))
    began, told, k = time.monotonic(), 0, 0
    while True:
        recorder.write(message(k))
        k += 1
        if recorder.flushed != told:
            told = recorder.flushed
            print(f"flushed {told}", flush=True)
        time.sleep(max(0.0, began + k / RATE - time.monotonic()))


if __name__ == "__main__":
    main()
