"""The architecture is visible in the imports: an upper layer may import a lower one,
never the reverse (docs/explanation/architecture.md); every import counts, lazy ones
included."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT

# Each layer and what it may import (besides itself and the standard library or
# third-party packages). A layer is a package prefix; the longest prefix wins.
ALLOWED: dict[str, set[str]] = {
    "knowledge": set(),
    "executive.bus": {"knowledge"},
    "monitoring": {"executive.bus", "knowledge"},
    "executive.sdk": {"executive.bus", "knowledge"},
    # the host of ROS 2 programs drives their nodes through the ROS 2 layer
    "executive.runtime": {"executive.bus", "executive.sdk", "executive.ros2", "knowledge"},
    "executive.ros2": {"executive.bus", "knowledge"},
    # a bag's ROS 2 messages are read as live ones are: ROS 2's message and decoder
    "executive.bags": {
        "executive.bus",
        "executive.ros2.message",
        "executive.ros2.cdr",
        "knowledge",
    },
    "executive.planning": {"executive.bus", "knowledge"},
    # the task executor runs plan steps through the plan executor's port
    "executive.tasks": {
        "executive.bus",
        "executive.runtime",
        "executive.sdk",
        "executive.planning.task_runner",
        "executive.planning.partial_order",
        "executive.planning.expression",
        "knowledge",
    },
    # the replay of a recording composes the bag reader and the offline replay of monitoring
    "executive.bag_replay": {"executive.bus", "executive.bags", "monitoring", "knowledge"},
    "executive.testing": {
        "executive.bus",
        "executive.sdk",
        "executive.bags",
        "executive.bag_replay",
        "monitoring",
        "knowledge",
    },
    "executive.dashboard": {"executive.bus", "executive.planning", "knowledge"},
    # a fleet's high level runs the planning layer's, its steps over the bus
    "executive.fleet": {"executive.bus", "executive.planning", "knowledge"},
    # the language server runs the checks of `dura validate` (its rule files' included)
    # and of `dura domain check`
    "executive.lsp": {
        "executive.bus",
        "executive.cli.validate",
        "executive.planning",
        "monitoring",
        "knowledge",
    },
    # the builders of the groups of services, for the composition root
    "executive.service_groups": {
        "executive.bus",
        "executive.runtime",
        "executive.ros2",
        "executive.bags",
        "executive.tasks",
        "executive.planning",
        "monitoring",
        "knowledge",
    },
    "executive.executive": {
        "executive.service_groups",
        "executive.bus",
        "executive.runtime",
        "executive.sdk",
        "executive.ros2",
        "executive.bags",
        "executive.tasks",
        "executive.planning",
        "executive.dashboard",
        "monitoring",
        "knowledge",
    },
    "executive.cli": {
        "executive.bus",
        "executive.runtime",
        "executive.sdk",
        "executive.ros2",
        "executive.bags",
        "executive.bag_replay",
        "executive.tasks",
        "executive.planning",
        "executive.testing",
        "executive.dashboard",
        "executive.executive",
        "executive.lsp",
        "executive.fleet",
        "monitoring",
        "knowledge",
    },
    # the package's own __init__ and fast_start, which every layer of executive may import
    "executive": {"knowledge"},
}
PACKAGES = ("executive", "monitoring", "knowledge")


def layer(module: str) -> str | None:
    """The layer a module belongs to: the longest layer name that prefixes it."""
    found = [name for name in ALLOWED if module == name or module.startswith(name + ".")]
    return max(found, key=len) if found else None


def module_name(path: Path, root: Path = ROOT) -> str:
    """The dotted name of the module in ``path``, a file of the tree at ``root``."""
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imports(path: Path, root: Path = ROOT) -> list[tuple[int, str]]:
    """Every module of dura that a file of the tree at ``root`` imports, with the line."""
    tree = ast.parse(path.read_text(), str(path))
    package = module_name(path, root).rpartition(".")[0]
    if path.name == "__init__.py":
        package = module_name(path, root)
    found: list[tuple[int, str]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.extend((node.lineno, alias.name) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*parent, base] if base else parent)
            found.append((node.lineno, base))
            found.extend((node.lineno, f"{base}.{alias.name}") for alias in node.names)
    return [(line, name) for line, name in found if name.split(".")[0] in PACKAGES]


def violations(root: Path = ROOT) -> list[str]:
    """Every import in the packages of the tree at ``root`` that runs upward or sideways,
    as ``path:line: layer imports module``."""
    found = []
    for package in PACKAGES:
        for path in sorted((root / package).rglob("*.py")):
            own = layer(module_name(path, root))
            assert own is not None, f"{path}: in no layer"
            for line, target in imports(path, root):
                other = layer(target)
                if other is None or other == own or own.startswith(other + "."):
                    continue
                allowed = ALLOWED[own]
                if any(target == a or target.startswith(a + ".") for a in allowed):
                    continue
                if other in allowed:
                    continue
                found.append(f"{path.relative_to(root)}:{line}: {own} imports {target}")
    return found


def test_no_layer_imports_one_above_it() -> None:
    assert violations() == []


def test_the_check_finds_an_import_that_runs_upward(tmp_path: Path) -> None:
    # a tree of its own: the bus imports the task executor lazily, the task executor
    # imports the bus (downward, allowed) and the runtime relatively (allowed)
    bus, tasks = tmp_path / "executive" / "bus", tmp_path / "executive" / "tasks"
    for package in (tmp_path / "executive", bus, tasks):
        package.mkdir(exist_ok=True)
        (package / "__init__.py").write_text("")
    (bus / "probe.py").write_text("def f() -> None:\n    from executive.tasks import executor\n")
    (tasks / "executor.py").write_text(
        "from executive.bus import probe\nfrom ..runtime import launcher\n"
    )
    assert violations(tmp_path) == [
        "executive/bus/probe.py:2: executive.bus imports executive.tasks",
        "executive/bus/probe.py:2: executive.bus imports executive.tasks.executor",
    ]


@pytest.mark.parametrize(
    ("module", "forbidden"),
    [
        (
            "executive.bus",
            (
                "executive.runtime",
                "executive.tasks",
                "executive.planning",
                "executive.cli",
                "monitoring",
            ),
        ),
        ("executive.bus.api.planning", ("executive.planning", "executive.cli", "monitoring")),
        (
            "monitoring.observer_manager",
            ("executive.runtime", "executive.tasks", "executive.planning"),
        ),
    ],
)
def test_importing_a_layer_loads_nothing_above_it(module: str, forbidden: tuple[str, ...]) -> None:
    code = (
        f"import sys, {module}\n"
        f"print('\\n'.join(m for m in sys.modules if m.startswith({forbidden!r})))"
    )
    loaded = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    ).stdout.split()
    assert loaded == []
