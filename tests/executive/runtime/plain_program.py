"""A program that knows nothing of dura: it prints, waits, and exits with a code.

Usage: python -m tests.executive.runtime.plain_program [SECONDS [CODE]]  (default: 60 s, code 0)
"""

from __future__ import annotations

import sys
import time


def main() -> None:
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 60.0
    code = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    print(f"plain program runs for {seconds:g} s", flush=True)
    time.sleep(seconds)
    sys.exit(code)


if __name__ == "__main__":
    main()
