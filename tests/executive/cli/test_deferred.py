"""A deferred module is imported at its first use, by whoever uses it first."""

from __future__ import annotations

import subprocess
import sys
import textwrap

from tests.conftest import ROOT


def run(script: str) -> list[str]:
    """The lines a fresh Python prints running ``script`` (sys.modules of its own)."""
    done = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(script)],
        capture_output=True, text=True, cwd=ROOT, timeout=60, check=True,
    )  # fmt: skip
    return done.stdout.split()


def test_a_deferred_module_is_imported_at_the_first_name_asked_of_it() -> None:
    assert run("""
        import sys
        from executive.cli import deferred
        deferred.defer(("colorsys",))
        import colorsys
        print(type(sys.modules["colorsys"]).__name__)
        print(colorsys.rgb_to_hsv(1.0, 0.0, 0.0)[2])
        print(type(sys.modules["colorsys"]).__name__, colorsys.__file__.endswith(".py"))
        from colorsys import hsv_to_rgb
        print(hsv_to_rgb is colorsys.hsv_to_rgb is sys.modules["colorsys"].hsv_to_rgb)
    """) == ["DeferredModule", "1.0", "module", "True", "True"]


def test_a_module_imported_already_is_not_deferred() -> None:
    assert run("""
        import colorsys, sys
        from executive.cli import deferred
        deferred.defer(("colorsys",))
        print(sys.modules["colorsys"] is colorsys)
    """) == ["True"]


def test_a_name_the_module_lacks_is_an_attribute_error_after_the_import() -> None:
    assert run("""
        from executive.cli import deferred
        deferred.defer(("colorsys",))
        import colorsys
        for _ in range(2):
            try:
                colorsys.no_such_name
            except AttributeError:
                print("AttributeError")
    """) == ["AttributeError", "AttributeError"]


def test_dataclasses_work_with_inspect_and_copy_deferred() -> None:
    assert run("""
        import sys
        from executive.cli import deferred
        deferred.defer()
        import dataclasses

        @dataclasses.dataclass
        class Documented:
            \"\"\"A docstring: inspect is not needed.\"\"\"
            x: int

        print(type(sys.modules["inspect"]).__name__)

        @dataclasses.dataclass
        class Bare:
            x: int

        print(type(sys.modules["inspect"]).__name__, Bare.__doc__)
        print(type(sys.modules["copy"]).__name__, dataclasses.asdict(Bare([1])))
        print(type(sys.modules["copy"]).__name__)
    """) == [
        "DeferredModule",
        "module",
        "Bare(x:",
        "int)",
        "DeferredModule",
        "{'x':",
        "[1]}",
        "module",
    ]
