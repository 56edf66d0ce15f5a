"""Every package has a map: its ``__init__`` docstring names each of its modules and
subpackages (``:mod:`.name```) with what is there, so a reader finds a module from its
package."""

from __future__ import annotations

import ast
import re
from pathlib import Path

from tests.conftest import ROOT

PACKAGES = ("executive", "monitoring", "knowledge")


def unmapped(root: Path = ROOT) -> dict[str, list[str]]:
    """The modules and subpackages each package of the tree at ``root`` does not name in
    its docstring (the command line's command modules are named by its ``COMMANDS``)."""
    found: dict[str, list[str]] = {}
    for package in PACKAGES:
        for init in sorted((root / package).rglob("__init__.py")):
            folder = init.parent
            tree = ast.parse(init.read_text())
            doc = ast.get_docstring(tree) or ""
            named = set(_commands(tree))
            parts = [p.stem for p in folder.glob("*.py") if p.stem not in ("__init__", "__main__")]
            parts += [p.name for p in folder.iterdir() if (p / "__init__.py").is_file()]
            missing = sorted(
                part
                for part in parts
                if part not in named and not re.search(rf":mod:`~?([\w.]*\.)?{part}`", doc)
            )
            if missing:
                found[folder.relative_to(root).as_posix()] = missing
    return found


def stale(root: Path = ROOT) -> dict[str, list[str]]:
    """The modules and subpackages each package's map names (``:mod:`.name```) that the
    package does not have."""
    found: dict[str, list[str]] = {}
    for package in PACKAGES:
        for init in sorted((root / package).rglob("__init__.py")):
            folder = init.parent
            doc = ast.get_docstring(ast.parse(init.read_text())) or ""
            gone = sorted(
                {
                    name
                    for name in re.findall(r":mod:`~?\.(\w+)`", doc)
                    if not (folder / f"{name}.py").is_file()
                    and not (folder / name / "__init__.py").is_file()
                }
            )
            if gone:
                found[folder.relative_to(root).as_posix()] = gone
    return found


def _commands(tree: ast.Module) -> list[str]:
    """The names of a module's ``COMMANDS`` tuple of strings, if it has one."""
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == "COMMANDS" for t in node.targets
        ):
            return [ast.literal_eval(e) for e in getattr(node.value, "elts", [])]
    return []


def test_every_package_names_its_modules_in_its_map() -> None:
    assert unmapped() == {}


def test_every_module_a_map_names_is_there() -> None:
    assert stale() == {}


def test_a_module_the_map_does_not_name_is_found(tmp_path: Path) -> None:
    package = tmp_path / "monitoring" / "repair"
    (package / "actions").mkdir(parents=True)
    (package / "actions" / "__init__.py").write_text('"""Actions: :mod:`.restart`."""\n')
    (package / "actions" / "restart.py").write_text("")
    (package / "__init__.py").write_text('"""Repair: :mod:`.rule`, the rules."""\n')
    for module in ("rule", "engine"):
        (package / f"{module}.py").write_text("")
    (tmp_path / "monitoring" / "__init__.py").write_text(
        '"""Monitoring: :mod:`monitoring.repair`."""\n'
    )
    assert unmapped(tmp_path) == {"monitoring/repair": ["actions", "engine"]}
    (package / "__init__.py").write_text('"""Repair: :mod:`.rule`, :mod:`.gone`."""\n')
    assert stale(tmp_path) == {"monitoring/repair": ["gone"]}
