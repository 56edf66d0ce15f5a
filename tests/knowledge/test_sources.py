"""An editor's unsaved text is read instead of the file, only where it is lent."""

from __future__ import annotations

import threading
from pathlib import Path

import pytest

from knowledge.domain import parse, read_domain
from knowledge.errors import DomainError
from knowledge.sources import Memo, read_text, unsaved
from tests.conftest import ROOT


def test_unsaved_text_is_read_instead_of_the_file_inside_unsaved_only(tmp_path: Path) -> None:
    path = tmp_path / "domain.pddl"
    path.write_text("on disk")
    with unsaved({tmp_path / "." / "domain.pddl": "in the editor"}):
        assert read_text(path) == "in the editor"
        elsewhere: list[str] = []
        other = threading.Thread(target=lambda: elsewhere.append(read_text(path)))
        other.start()
        other.join()
        assert elsewhere == ["on disk"]
    assert read_text(path) == "on disk"


def test_the_domain_reader_reads_the_unsaved_text() -> None:
    path = ROOT / "domains" / "usecase" / "domain.pddl"
    renamed = path.read_text().replace("durative-action take_picture", "durative-action snap")
    with unsaved({path: renamed}):
        assert sorted(read_domain(path).actions) == ["move_to", "snap"]
    assert sorted(read_domain(path).actions) == ["move_to", "take_picture"]


def test_a_memo_parses_a_text_once_and_gives_each_reader_a_copy() -> None:
    path = ROOT / "domains" / "usecase" / "domain.pddl"
    memo = Memo()
    with unsaved({}, memo):
        first = parse(path)
        again = parse(path)
    assert len(_readings(memo)) == 1
    assert again is not first and again == first
    renamed = path.read_text().replace("durative-action take_picture", "durative-action snap")
    with unsaved({path: renamed}, memo):
        assert sorted(a.name for a in parse(path).actions) == ["move_to", "snap"]
    assert len(_readings(memo)) == 2
    assert list(memo.results).count(("pddl reader",)) == 1  # one reader read both


def _readings(memo: Memo) -> list[object]:
    """What the memo keeps of texts read (not the reader that read them)."""
    return [k for k in memo.results if k != ("pddl reader",)]


def test_a_memo_raises_a_remembered_error_again() -> None:
    path = ROOT / "domains" / "usecase" / "domain.pddl"
    broken = path.read_text().replace("(:types place)", "(:types place")
    memo = Memo()
    for _ in range(2):
        with unsaved({path: broken}, memo), pytest.raises(DomainError, match="is not closed"):
            parse(path)
    assert len(_readings(memo)) == 1
