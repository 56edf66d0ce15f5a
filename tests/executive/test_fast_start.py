"""The start-up tricks do what they save and change nothing else: a deferred module is
imported at its first use, by whoever uses it first; unified-planning loads without
ConfigSpace until something makes a configuration space; the reader environment reads
PDDL without any engine; garbage collection resumes after the imports; a command that
exits at once still runs its exit handlers and flushes its output."""

from __future__ import annotations

import subprocess
import sys
import textwrap

from tests.conftest import ROOT

DOMAIN = ROOT / "domains" / "usecase" / "domain.pddl"


def run(script: str, *, returncode: int = 0) -> list[str]:
    """The words a fresh Python prints running ``script`` (sys.modules of its own)."""
    done = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(script)],
        capture_output=True, text=True, cwd=ROOT, timeout=120, check=False,
    )  # fmt: skip
    assert done.returncode == returncode, done.stderr
    return done.stdout.split()


def test_the_tricks_module_loads_nothing_of_dura_nor_unified_planning() -> None:
    assert run("""
        import sys
        from executive import fast_start
        print(sorted(m for m in sys.modules if m.split(".")[0] in
                     ("executive", "knowledge", "monitoring", "unified_planning")))
    """) == ["['executive',", "'executive.fast_start']"]


def test_a_deferred_module_is_imported_at_the_first_name_asked_of_it() -> None:
    assert run("""
        import sys
        from executive import fast_start
        fast_start.defer_modules(("colorsys",))
        import colorsys
        print(type(sys.modules["colorsys"]).__name__)
        print(colorsys.rgb_to_hsv(1.0, 0.0, 0.0)[2])
        print(type(sys.modules["colorsys"]).__name__, colorsys.__file__.endswith(".py"))
        from colorsys import hsv_to_rgb
        print(hsv_to_rgb is colorsys.hsv_to_rgb is sys.modules["colorsys"].hsv_to_rgb)
    """) == ["DeferredModule", "1.0", "module", "True", "True"]


def test_a_name_imported_from_a_deferred_module_imports_it() -> None:
    assert run("""
        import sys
        from executive import fast_start
        fast_start.defer_modules(("colorsys",))
        from colorsys import rgb_to_hsv
        print(rgb_to_hsv(1.0, 0.0, 0.0)[2], type(sys.modules["colorsys"]).__name__)
    """) == ["1.0", "module"]


def test_a_module_imported_already_is_not_deferred() -> None:
    assert run("""
        import colorsys, sys
        from executive import fast_start
        fast_start.defer_modules(("colorsys",))
        print(sys.modules["colorsys"] is colorsys)
    """) == ["True"]


def test_a_name_the_module_lacks_is_an_attribute_error_after_the_import() -> None:
    assert run("""
        from executive import fast_start
        fast_start.defer_modules(("colorsys",))
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
        from executive import fast_start
        fast_start.defer_modules()
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


def test_unified_planning_loads_without_configspace_until_a_space_is_made() -> None:
    assert run("""
        import sys
        from executive import fast_start
        fast_start.import_unified_planning()
        print("ConfigSpace" in sys.modules, "scipy" in sys.modules)
        from unified_planning.engines import Engine
        space = Engine.get_configuration_space()
        print(type(space).__module__.split(".")[0], "scipy" in sys.modules)
    """) == ["False", "False", "ConfigSpace", "True"]


def test_nothing_stands_in_for_configspace_once_unified_planning_is_imported() -> None:
    assert run("""
        import sys
        from executive import fast_start
        fast_start.import_unified_planning()
        import ConfigSpace.hyperparameters  # a package's module: no stand-in has one
        print(type(sys.modules["ConfigSpace"]).__name__, hasattr(ConfigSpace, "__path__"))
    """) == ["module", "True"]


def test_the_reader_environment_reads_pddl_without_any_engine() -> None:
    assert run(f"""
        import sys
        from pathlib import Path
        from executive import fast_start
        from knowledge.domain import parse
        fast_start.use_reader_environment()
        problem = parse(Path({str(DOMAIN)!r}))
        from unified_planning.engines import factory
        from unified_planning.environment import get_environment
        print(len(problem.actions) > 0, len(get_environment().factory.engines))
        print(len(factory.DEFAULT_ENGINES) > 0)  # put back for any other environment
        engines = ("up_kairos", "up_aries", "up_fast_downward", "scipy")
        print(sorted(m for m in sys.modules if m.split(".")[0] in engines))
    """) == ["True", "0", "True", "[]"]


def test_the_reader_environment_leaves_an_environment_made_already_as_it_is() -> None:
    assert run("""
        from unified_planning.environment import get_environment
        from executive import fast_start
        made = get_environment()
        fast_start.use_reader_environment()
        print(get_environment() is made, len(made.factory.engines) > 0)
    """) == ["True", "True"]


def test_garbage_is_collected_again_after_the_paused_block_even_when_it_fails() -> None:
    assert run("""
        import gc
        from executive import fast_start
        with fast_start.collection_paused():
            print(gc.isenabled())
            made = [[] for _ in range(1000)]
        print(gc.isenabled(), gc.get_freeze_count() >= 1000)
        try:
            with fast_start.collection_paused():
                raise KeyError("x")
        except KeyError:
            print(gc.isenabled())
    """) == ["False", "True", "True", "True"]


def test_exiting_at_once_runs_the_exit_handlers_and_flushes_the_output() -> None:
    assert run(
        """
        import atexit, sys
        from executive import fast_start
        atexit.register(print, "handled")
        sys.stdout.write("written ")
        fast_start.exit_at_once(3)
    """,
        returncode=3,
    ) == ["written", "handled"]


def test_exiting_at_once_waits_for_another_thread_as_python_does() -> None:
    assert run(
        """
        import threading, time
        from executive import fast_start
        def late():
            time.sleep(0.2)
            print("late")
        threading.Thread(target=late).start()
        fast_start.exit_at_once(4)
    """,
        returncode=4,
    ) == ["late"]
