"""Component log files rotate by size and keep a fixed number of old files."""

from __future__ import annotations

from pathlib import Path

from executive.runtime.logfile import LogFile, last_words, tail


def test_a_log_file_rotates_before_it_grows_past_its_size(tmp_path: Path) -> None:
    path = tmp_path / "logs" / "lidar.log"
    log = LogFile(path, max_bytes=10, backups=2)
    for chunk in (b"one\n", b"two\n", b"three\n", b"four\n", b"five\n", b"six\n"):
        log.write(chunk)
    log.close()
    assert path.read_bytes() == b"six\n"
    assert (tmp_path / "logs" / "lidar.log.1").read_bytes() == b"four\nfive\n"
    assert (tmp_path / "logs" / "lidar.log.2").read_bytes() == b"three\n"
    assert not (tmp_path / "logs" / "lidar.log.3").exists()


def test_a_reopened_log_file_appends_and_counts_what_is_there(tmp_path: Path) -> None:
    path = tmp_path / "cam.log"
    path.write_bytes(b"12345678\n")
    log = LogFile(path, max_bytes=12, backups=1)
    log.write(b"abcd\n")
    log.close()
    assert path.read_bytes() == b"abcd\n"
    assert (tmp_path / "cam.log.1").read_bytes() == b"12345678\n"


def test_the_tail_of_a_log_is_its_last_lines(tmp_path: Path) -> None:
    path = tmp_path / "x.log"
    path.write_text("a\nb\nc\n")
    assert tail(path, 2) == ["b", "c"]
    assert tail(path, 0) == []
    assert tail(tmp_path / "missing.log", 5) == []


TRACEBACK = """\
--- dura: started barista (supervisor pid 42) 2026-11-27 10:00:00
2026-11-27 10:00:01,000 barista INFO: ready
2026-11-27 10:00:02,000 barista ERROR: unhandled exception in a handler: 'barista' ends
Traceback (most recent call last):
  File "/robot/sdk.py", line 10, in call
    handler(message)
  File "/robot/barista.py", line 7, in on_water
    self.celsius = message["celsius"]
                   ~~~~~~~^^^^^^^^^^^
TypeError: 'Message' object is not subscriptable
--- dura: exited: exited with code 1 2026-11-27 10:00:02
"""


def test_the_last_words_of_a_crash_are_its_failing_line_and_exception() -> None:
    assert last_words(TRACEBACK.splitlines()) == (
        '  File "/robot/barista.py", line 7, in on_water',
        '    self.celsius = message["celsius"]',
        "                   ~~~~~~~^^^^^^^^^^^",
        "TypeError: 'Message' object is not subscriptable",
    )


def test_the_last_words_without_a_traceback_are_the_last_lines_of_the_program() -> None:
    lines = ["--- dura: started x 10:00", "one", "", "two", "usage: x PORT", "--- dura: exited"]
    assert last_words(lines, keep=2) == ("two", "usage: x PORT")
    assert last_words(["--- dura: started x 10:00"]) == ()
