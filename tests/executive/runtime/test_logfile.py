"""Component log files rotate by size and keep a fixed number of old files."""

from __future__ import annotations

from pathlib import Path

from executive.runtime.logfile import LogFile, tail


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
