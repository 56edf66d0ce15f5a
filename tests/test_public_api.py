"""The public API is a promise: every name the documentation gives imports without a
warning, and every name that moved keeps working with a DeprecationWarning naming its new
place (docs/reference/public-api.md)."""

from __future__ import annotations

import importlib
import re
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from executive import moved
from tests.conftest import ROOT

PUBLIC_API = ROOT / "docs" / "reference" / "public-api.md"
PACKAGES = ("executive", "knowledge", "monitoring")


def documents() -> list[Path]:
    """The README and every page of the documentation."""
    return [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]


def documented_imports() -> set[tuple[str, str]]:
    """Every ``from MODULE import NAME`` of dura that a document shows."""
    found: set[tuple[str, str]] = set()
    pattern = re.compile(rf"^\s*from ((?:{'|'.join(PACKAGES)})[\w.]*) import \(?([\w, ]+)", re.M)
    for path in documents():
        for module, names in pattern.findall(path.read_text()):
            found.update((module, name.strip()) for name in names.split(",") if name.strip())
    return found


def declared_names() -> set[str]:
    """Every dotted name the public API page declares (in backticks, outside the table of
    names that moved)."""
    text = PUBLIC_API.read_text().split("## Names that moved")[0]
    return set(re.findall(rf"`((?:{'|'.join(PACKAGES)})\.[\w.]+)`", text))


def load(dotted: str) -> object:
    """A module, or a name in one, by its dotted name."""
    try:
        return importlib.import_module(dotted)
    except ModuleNotFoundError:
        module, _, name = dotted.rpartition(".")
        return getattr(importlib.import_module(module), name)


def test_the_documents_show_imports_and_declare_names() -> None:
    assert ("executive.sdk", "Functionality") in documented_imports()
    assert {"executive.sdk.Behavior", "executive.testing.dura_robot"} <= declared_names()


@pytest.mark.parametrize(("module", "name"), sorted(documented_imports()))
def test_every_documented_import_works_without_a_warning(module: str, name: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        assert getattr(importlib.import_module(module), name) is not None


@pytest.mark.parametrize("dotted", sorted(declared_names()))
def test_every_declared_name_is_there_without_a_warning(dotted: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        assert load(dotted) is not None


@pytest.mark.parametrize(
    ("statement", "new"),
    [
        ("from executive.component import Functionality", "executive.sdk.Functionality"),
        ("from executive.component import Behavior", "executive.sdk.Behavior"),
        ("from executive.component import GoalFailed", "executive.sdk.GoalFailed"),
        ("from executive.bus import Message", "executive.sdk.Message"),
        ("from executive.bus import Bus", "executive.bus.session.Bus"),
        ("from executive.harness import RobotProcess", "executive.testing.harness.RobotProcess"),
        ("from executive.launcher import Launcher", "executive.runtime.launcher.Launcher"),
        ("from executive.translator import Translator", "executive.runtime.translator.Translator"),
    ],
)
def test_a_name_that_moved_works_with_a_warning_naming_its_new_place(
    statement: str, new: str
) -> None:
    namespace: dict[str, object] = {}
    with pytest.warns(DeprecationWarning, match=re.escape(f"moved to {new}")) as caught:
        exec(statement, namespace)  # noqa: S102 - the statement is one of the above
    name = statement.rsplit(maxsplit=1)[-1]
    assert namespace[name] is load(new)
    assert caught[0].filename == "<string>"  # the warning points at the importing line


def test_every_moved_module_and_name_is_in_the_public_api_page() -> None:
    table = PUBLIC_API.read_text().split("## Names that moved")[1]
    for old in [*moved.MOVED, *moved.MOVED_NAMES]:
        assert f"`{old}" in table, old


def test_a_moved_module_refuses_a_name_its_new_place_lacks() -> None:
    with pytest.raises(AttributeError, match=r"moved to executive\.sdk"):
        _ = importlib.import_module("executive.component").NoSuchName


def test_the_old_translator_module_still_runs_a_translator() -> None:
    ran = subprocess.run(
        [sys.executable, "-m", "executive.translator"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    assert ran.returncode == 2  # no translator named: the usage, as the new module prints
    assert "moved to python -m executive.runtime.translator" in ran.stderr
    assert "usage" in ran.stderr.lower()
