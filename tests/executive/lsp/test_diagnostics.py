"""Diagnostics as the user types: the words of ``dura validate`` and ``dura domain
check``, each at the name it is about, the domain and the robot checked together."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest
from lsprotocol import types
from pytest_lsp import LanguageClient

from executive.planning.integrity import read_rules as read_integrity_rules
from executive.planning.problem import read_world
from knowledge.domain import read_domain
from knowledge.finding import Report
from knowledge.robot import load_robot
from knowledge.validation import validate
from monitoring.observer_config import check_observer_file
from monitoring.repair.rule import read_rules as read_repair_rules
from tests.executive.lsp.conftest import WAIT, change_file, diagnostics_until, open_file, uri

pytestmark = [pytest.mark.slow, pytest.mark.asyncio]


def _words(diagnostics: list[types.Diagnostic]) -> list[str]:
    return [d.message for d in diagnostics]


def _at(text: str, line: int, word: str) -> types.Range:
    column = text.splitlines()[line].index(word)
    return types.Range(types.Position(line, column), types.Position(line, column + len(word)))


async def test_the_valid_use_case_has_no_diagnostics(client: LanguageClient, usecase: Path) -> None:
    robot = usecase / "examples" / "usecase" / "robot.yaml"
    open_file(client, robot)
    shown = await diagnostics_until(client, robot, lambda d: True)
    assert shown == []
    domain = usecase / "domains" / "usecase" / "domain.pddl"
    assert await diagnostics_until(client, domain, lambda d: True) == []


async def test_an_unknown_capability_typed_is_shown_at_its_name_in_dura_validates_words(
    client: LanguageClient, usecase: Path
) -> None:
    robot = usecase / "examples" / "usecase" / "robot.yaml"
    text = robot.read_text()
    open_file(client, robot)
    await diagnostics_until(client, robot, lambda d: True)
    typo = text.replace("requires: [obstacle_scan, base]", "requires: [obstacle_scna, base]")
    change_file(client, robot, typo)
    shown = await diagnostics_until(client, robot, lambda d: len(d) > 0)
    copy = robot.with_name("typo.yaml")
    copy.write_text(typo)
    expected = [f.message for f in validate(copy).findings]
    assert _words(shown) == expected
    assert (
        "requires unknown capability 'obstacle_scna' (did you mean 'obstacle_scan'?)" in expected[0]
    )
    line = typo.splitlines().index("    requires: [obstacle_scna, base]")
    assert shown[0].range == _at(typo, line, "obstacle_scna")
    assert shown[0].severity == types.DiagnosticSeverity.Error
    assert robot.read_text() == text  # unsaved: the file is as it was


async def test_an_action_renamed_in_the_domain_rechecks_the_robot_description(
    client: LanguageClient, usecase: Path
) -> None:
    robot = usecase / "examples" / "usecase" / "robot.yaml"
    domain = usecase / "domains" / "usecase" / "domain.pddl"
    open_file(client, robot)
    domain_text = domain.read_text()
    open_file(client, domain)
    await diagnostics_until(client, robot, lambda d: True)
    renamed = domain_text.replace("(:durative-action take_picture", "(:durative-action snap")
    change_file(client, domain, renamed)
    on_robot = await diagnostics_until(client, robot, lambda d: len(d) > 0)
    assert _words(on_robot) == ["task 'take_picture' names no action of domain 'usecase'"]
    robot_text = robot.read_text()
    lines = robot_text.splitlines()
    line = len(lines) - 1 - lines[::-1].index("  take_picture:")  # the task, not the behavior
    assert on_robot[0].range == _at(robot_text, line, "take_picture")
    on_domain = await diagnostics_until(client, domain, lambda d: len(d) > 0)
    assert _words(on_domain) == [
        "action 'snap' has no task in robot.yaml: it will be applied without running a behavior"
    ]
    line = renamed.splitlines().index("  (:durative-action snap")
    assert on_domain[0].range == _at(renamed, line, "snap")
    assert on_domain[0].severity == types.DiagnosticSeverity.Warning
    change_file(client, domain, domain_text, version=3)  # undone: both are clean again
    assert await diagnostics_until(client, robot, lambda d: len(d) == 0) == []
    assert await diagnostics_until(client, domain, lambda d: len(d) == 0) == []


async def test_a_pddl_syntax_error_is_shown_on_its_line(
    client: LanguageClient, usecase: Path
) -> None:
    domain = usecase / "domains" / "usecase" / "domain.pddl"
    text = domain.read_text()
    broken = text.replace("(at end (picture_taken ?p)))", "(at end (picture_taken ?p))")
    open_file(client, domain, broken)
    shown = await diagnostics_until(client, domain, lambda d: len(d) > 0)
    assert len(shown) == 1
    assert _words(shown) == [
        "'(define' is not closed before the end of the file (a ')' is missing)"
    ]
    opened = next(i for i, t in enumerate(broken.splitlines()) if t.startswith("(define"))
    assert shown[0].range == _at(broken, opened, "(define")  # the list left open
    assert shown[0].severity == types.DiagnosticSeverity.Error


async def test_domain_check_warnings_are_shown_at_the_name(
    client: LanguageClient, usecase: Path
) -> None:
    domain = usecase / "domains" / "usecase" / "domain.pddl"
    text = domain.read_text()
    unused = text.replace(
        "(photographable ?p - place))", "(photographable ?p - place)\n    (charged))"
    )
    open_file(client, domain, unused)
    shown = await diagnostics_until(client, domain, lambda d: len(d) > 0)
    assert _words(shown) == ["predicate 'charged' is not used by any action or the problem"]
    line = next(i for i, t in enumerate(unused.splitlines()) if t.startswith("    (charged))"))
    assert shown[0].range == _at(unused, line, "charged")


async def test_an_unknown_object_in_the_problem_is_an_error_on_its_line(
    client: LanguageClient, usecase: Path
) -> None:
    problem = usecase / "examples" / "usecase" / "problem.pddl"
    text = problem.read_text()
    wrong = text.replace("(robot_at dock)", "(robot_at dokc)")
    open_file(client, problem, wrong)
    shown = await diagnostics_until(client, problem, lambda d: len(d) > 0)
    assert [d.severity for d in shown] == [types.DiagnosticSeverity.Error]
    line = wrong.splitlines().index("    (robot_at dokc)")
    assert shown[0].range == _at(wrong, line, "dokc")


async def test_a_standalone_observers_file_is_checked_as_dura_validate_checks_it(
    client: LanguageClient, usecase: Path
) -> None:
    observers = usecase / "observers.yaml"
    text = "- type: timeout\n  topics:\n    - name: scan\n      callerids:\n        - {callerid: [], timeout: 0.5, max_timeouts_in_a_row: 2}\n"
    observers.write_text(text)
    open_file(client, observers)
    assert await diagnostics_until(client, observers, lambda d: True) == []
    wrong = text.replace("type: timeout", "type: timeot")
    change_file(client, observers, wrong)
    shown = await diagnostics_until(client, observers, lambda d: len(d) > 0)
    copy = usecase / "copy.yaml"
    copy.write_text(wrong)
    checked = check_observer_file(copy)
    assert checked is not None
    assert _words(shown) == [f.message for f in checked[1]]
    assert shown[0].range == _at(wrong, 0, "timeot")


@pytest.mark.parametrize("domain_open", [False, True], ids=["closed", "open"])
async def test_a_robot_that_names_another_domain_clears_the_old_domains_diagnostics(
    client: LanguageClient, usecase: Path, domain_open: bool
) -> None:
    robot = usecase / "examples" / "usecase" / "robot.yaml"
    domain = usecase / "domains" / "usecase" / "domain.pddl"
    other = domain.with_name("other.pddl")
    other.write_text(domain.read_text())
    renamed = domain.read_text().replace("(:durative-action take_picture", "(:durative-action snap")
    domain.write_text(renamed)
    if domain_open:
        open_file(client, domain)
    text = robot.read_text()
    open_file(client, robot)
    on_domain = await diagnostics_until(client, domain, lambda d: len(d) > 0)
    assert _words(on_domain) == [
        "action 'snap' has no task in robot.yaml: it will be applied without running a behavior"
    ]
    moved = text.replace(
        "domain: ../../domains/usecase/domain.pddl", "domain: ../../domains/usecase/other.pddl"
    )
    change_file(client, robot, moved)
    assert await diagnostics_until(client, domain, lambda d: len(d) == 0) == []
    assert await diagnostics_until(client, robot, lambda d: len(d) == 0) == []


async def test_a_rules_file_no_robot_names_is_checked_alone_with_its_asp_files(
    client: LanguageClient, usecase: Path
) -> None:
    rules = usecase / "spare_rules.yaml"
    text = "rules:\n  - type: restart\n    name: restart_cam\n    component: cam\n"
    rules.write_text(text)
    open_file(client, rules)
    shown = await diagnostics_until(client, rules, lambda d: len(d) > 0)
    report = Report(str(rules))
    read_repair_rules(rules, report)
    assert _words(shown) == [f.message for f in report.findings]
    assert _words(shown) == [
        "rule 'restart_cam' has no condition (give it one, or trigger it from an ASP file"
        " named under 'asp')"
    ]
    assert shown[0].range == _at(text, 1, "- type: restart")
    program = usecase / "more.lp"
    program.write_text('trigger("restart_cam") :- fault(cam)\ninhibit(X).\n')
    change_file(client, rules, "asp: [more.lp]\n" + text)
    assert await diagnostics_until(client, rules, lambda d: len(d) == 0) == []
    [syntax] = await diagnostics_until(client, program, lambda d: len(d) > 0)
    assert syntax.message == "syntax error, unexpected <IDENTIFIER>"
    assert syntax.range == _at(program.read_text(), 1, "inhibit")


async def test_an_asp_program_is_checked_as_typed_at_clingos_line_and_column(
    client: LanguageClient, usecase: Path
) -> None:
    program = usecase / "alone.lp"  # no rules file names it
    text = 'trigger("restart_cam") :- fault(cam).\n'
    program.write_text(text)
    open_file(client, program)
    assert await diagnostics_until(client, program, lambda d: True) == []
    typed = text + "% the camera again\ninhibit(X) :- 📷 fault(cam).\n"
    change_file(client, program, typed)  # unsaved: the file on disk is fine
    [syntax] = await diagnostics_until(client, program, lambda d: len(d) > 0)
    assert syntax.message == "unexpected character '📷'"  # clingo's lexer would abort dura
    assert syntax.severity == types.DiagnosticSeverity.Error
    column = len("inhibit(X) :- ")
    assert syntax.range == types.Range(  # the client counts UTF-16: the camera is 2
        types.Position(2, column), types.Position(2, column + 2)
    )
    change_file(client, program, text + "inhibit(X) :- fault(X), X != cam.\n", version=3)
    assert await diagnostics_until(client, program, lambda d: len(d) == 0) == []
    change_file(client, program, text + "inhibit(X) :- fault(X) X.\n", version=4)
    [syntax] = await diagnostics_until(client, program, lambda d: len(d) > 0)
    assert syntax.message == "syntax error, unexpected <VARIABLE>"
    assert syntax.range == _at(text + "inhibit(X) :- fault(X) X.\n", 1, "X.")


INTEGRITY = """goals:
  - name: dock
    when: {permanent_fault: lidar}
    goal: "(robot_at dock)"
"""


async def test_an_integrity_rules_file_no_robot_names_is_checked_alone_in_dura_validates_words(
    client: LanguageClient, usecase: Path
) -> None:
    rules = usecase / "spare_integrity.yaml"
    rules.write_text(INTEGRITY)
    open_file(client, rules)
    # what only the robot and its domain know is not guessed at: no finding
    assert await diagnostics_until(client, rules, lambda d: True) == []
    wrong = (
        INTEGRITY.replace(
            "{permanent_fault: lidar}", "{permanent_fault: lidar, diagnosis: cam}"
        ).replace('"(robot_at dock)"', '"(robot_at dock"')
        + "    priorty: 3\n"
        + "  - {name: charge, when: {condition: robot_at dock}, goal: (robot_at dock), for: -1}\n"
    )
    change_file(client, rules, wrong)
    shown = await diagnostics_until(client, rules, lambda d: len(d) >= 5)
    # the words of dura validate, which checks the same file against the use-case robot
    copy = usecase / "checked.yaml"
    copy.write_text(wrong)
    robot = load_robot(usecase / "examples" / "usecase" / "robot.yaml")
    report = Report(str(copy))
    assert robot.problem is not None
    objects = read_world(robot.domain, robot.problem)[0].objects
    read_integrity_rules(copy, robot, read_domain(robot.domain), objects, report)
    assert sorted(_words(shown)) == sorted(f.message for f in report.findings)
    assert {d.message: d.range.start.line for d in shown} == {
        "'when' of integrity rule 'dock' needs exactly one of permanent_fault, diagnosis,"
        " condition": 2,
        "integrity rule 'dock': goal '(robot_at dock': missing ')'": 3,
        "unknown key 'priorty' in integrity rule 'dock' (did you mean 'priority'?)": 4,
        "'for' of integrity rule 'charge' must be at least 0, not -1": 5,
        "integrity rule 'charge': condition 'robot_at dock': text after the expression: dock": 5,
    }
    assert all(d.severity == types.DiagnosticSeverity.Error for d in shown)
    assert shown[2].range == _at(wrong, 4, "priorty")
    change_file(client, rules, INTEGRITY, version=3)
    assert await diagnostics_until(client, rules, lambda d: len(d) == 0) == []


async def test_diagnostics_name_the_version_of_the_text_they_were_found_in(
    client: LanguageClient, usecase: Path
) -> None:
    robot = usecase / "examples" / "usecase" / "robot.yaml"
    text = robot.read_text()
    open_file(client, robot)
    await diagnostics_until(client, robot, lambda d: True)
    typo = text.replace("requires: [obstacle_scan, base]", "requires: [obstacle_scna, base]")
    change_file(client, robot, typo, version=7)

    async def published() -> types.PublishDiagnosticsParams:
        while True:
            params = await client.wait_for_notification(types.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
            if params.uri == uri(robot) and params.diagnostics:
                return params  # type: ignore[no-any-return]

    shown = await asyncio.wait_for(published(), WAIT)
    assert shown.version == 7
