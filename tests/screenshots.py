"""Screenshots of the dashboard during ``dura demo``, for a person to look at.

    python -m tests.screenshots [OUTDIR] [--readme]

runs ``dura demo --dashboard`` and saves a PNG of each view into OUTDIR (default: a new
temporary folder): while the robot drives on lidar after its first fault, and again
after lidar became permanently faulty and move_to switched to the camera. With
``--readme`` it also writes ``examples/usecase/dashboard.png``, the picture the README
shows. Needs Debian's Chromium (``apt-get install chromium``). Nothing here is a test:
the files are not committed (but for the README's picture).
"""

from __future__ import annotations

import argparse
import os
import queue
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from executive.testing.harness import free_endpoint
from tests.conftest import ROOT
from tests.executive.dashboard.browser import Browser, chromium

VIEWS = ("all", "goals", "plan", "components", "observations", "events")
README = ROOT / "examples" / "usecase" / "dashboard.png"


def free_port() -> int:
    return int(free_endpoint().rsplit(":", 1)[1])


def lines_of(process: subprocess.Popen[str]) -> queue.Queue[str | None]:
    """The demo's output, line by line, echoed (``None`` when it ends)."""
    found: queue.Queue[str | None] = queue.Queue()

    def read() -> None:
        assert process.stdout is not None
        for line in process.stdout:
            print(line, end="", flush=True)
            found.put(line)
        found.put(None)

    threading.Thread(target=read, daemon=True).start()
    return found


def wait_for(lines: queue.Queue[str | None], pattern: str, timeout: float = 120.0) -> str:
    deadline = time.monotonic() + timeout
    while True:
        line = lines.get(timeout=max(0.1, deadline - time.monotonic()))
        if line is None:
            raise SystemExit(f"the demo ended before '{pattern}'")
        if re.search(pattern, line):
            return line


def shoot(browser: Browser, folder: Path, moment: str) -> list[Path]:
    saved = []
    for view in VIEWS:
        browser.evaluate(f"location.hash = '#{view}'")
        browser.wait_for(f"document.body.dataset.view === '{view}'")
        browser.evaluate(PAINTED)
        saved.append(browser.screenshot(folder / f"{moment}-{view}.png"))
    browser.evaluate("location.hash = '#all'")
    return saved


# a promise kept once the page has painted what it shows now (two frames later)
PAINTED = "new Promise((done) => requestAnimationFrame(() => requestAnimationFrame(done)))"


def shown(browser: Browser, kind: str, text: str = "") -> None:
    """Wait until the page lists an event of ``kind`` that mentions ``text``, and the
    highlight of its row (a new row's, 1.5 s) has faded."""
    rows = f"document.querySelectorAll('#event-table tr[data-kind=\"{kind}\"]')"
    row = f"[...{rows}].find((r) => r.textContent.includes({text!r}))"
    browser.wait_for(f"Boolean({row})", timeout=30)
    faded = f"({row}).getAnimations({{subtree: true}}).map((a) => a.finished)"
    browser.evaluate(f"Promise.allSettled({faded}).then(() => true)")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.screenshots", description=__doc__)
    parser.add_argument("outdir", nargs="?", type=Path, help="where the PNGs go")
    parser.add_argument("--readme", action="store_true", help=f"also write {README}")
    args = parser.parse_args(argv)
    if chromium() is None:
        print("no Chromium: apt-get install chromium", file=sys.stderr)
        return 1
    folder = args.outdir or Path(tempfile.mkdtemp(prefix="dura-screenshots-"))
    folder.mkdir(parents=True, exist_ok=True)
    port = free_port()
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1"}
    demo = subprocess.Popen(
        [sys.executable, "-m", "executive.cli", "demo", "--dashboard", str(port)],
        cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )  # fmt: skip
    try:
        lines = lines_of(demo)
        url = wait_for(lines, r"dashboard on http").split("dashboard on ", 1)[1].strip()
        with Browser(width=1400, height=1000) as browser:
            browser.open(url)
            wait_for(lines, r"FAULT\s+lidar")
            wait_for(lines, r"TASK_RESTARTED\s+task \d+ move_to")
            shown(browser, "TASK_RESTARTED", "move_to")
            saved = shoot(browser, folder, "1-after-a-fault")
            wait_for(lines, r"PERMANENT_FAULT\s+lidar")
            wait_for(lines, r"CONFIGURATION\s+.*cam_to_lidar")
            shown(browser, "CONFIGURATION", "cam_to_lidar")
            if args.readme:  # first: the demo ends a few seconds after the switch
                shutil.copy(browser.screenshot(folder / "readme.png"), README)
                saved.append(README)
            saved += shoot(browser, folder, "2-on-the-camera")
            errors = list(browser.errors)
        demo.wait(180)
    finally:
        if demo.poll() is None:
            demo.send_signal(signal.SIGINT)  # the demo stops its robot
            demo.wait(60)
    print("\n".join(str(p) for p in saved))
    if errors:
        print("console errors:\n" + "\n".join(errors), file=sys.stderr)
    return 0 if not errors and demo.returncode == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
