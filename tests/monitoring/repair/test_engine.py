"""The rule engine: conditions, windows, recall, single shot, priorities, ASP rules."""

from __future__ import annotations

from pathlib import Path

import pytest

from executive.bus.payloads import DiagnosisInfo, ObservationInfo
from knowledge.errors import AspError
from monitoring.repair.engine import RuleEngine
from monitoring.repair.rule import read_rules


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def engine(
    tmp_path: Path, text: str, clock: Clock | None = None, asp: str | None = None
) -> RuleEngine:
    if asp is not None:
        (tmp_path / "extra.lp").write_text(asp)
    path = tmp_path / "rules.yaml"
    path.write_text(text)
    return RuleEngine([read_rules(path)], clock=clock or Clock())


def hz(value: int, resource: str = "scan") -> ObservationInfo:
    return ObservationInfo("hz", (resource,), value)


def diagnosed(*diagnoses: tuple[str, ...]) -> DiagnosisInfo:
    return DiagnosisInfo("DIAGNOSED" if diagnoses else "OK", diagnoses)


def fired(e: RuleEngine) -> list[str]:
    return [f.rule.name for f in e.evaluate()]


RESTART_ON_SLOW_SCAN = """
rules:
  - type: log
    name: slow
    positive_observations:
      - {type: frequency, resource: scan, observation: -1, occurrences: 2, window_size: 3}
"""


def test_a_rule_fires_when_its_observations_match_often_enough_in_the_window(
    tmp_path: Path,
) -> None:
    e = engine(tmp_path, RESTART_ON_SLOW_SCAN)
    e.observe(hz(-1))
    assert fired(e) == []
    e.observe(hz(0))
    assert fired(e) == []
    e.observe(hz(-1))
    assert fired(e) == ["slow"]
    e.observe(hz(0))
    e.observe(hz(0))
    assert fired(e) == []


def test_a_rule_fires_once_when_its_condition_becomes_true_and_again_after_it_was_false(
    tmp_path: Path,
) -> None:
    e = engine(tmp_path, RESTART_ON_SLOW_SCAN)
    for _ in range(2):
        e.observe(hz(-1))
    assert fired(e) == ["slow"]
    e.observe(hz(-1))
    assert fired(e) == []
    for _ in range(3):
        e.observe(hz(0))
    assert fired(e) == []
    for _ in range(2):
        e.observe(hz(-1))
    assert fired(e) == ["slow"]


def test_a_rule_fires_again_after_its_recall_duration_while_the_condition_holds(
    tmp_path: Path,
) -> None:
    clock = Clock()
    e = engine(tmp_path, RESTART_ON_SLOW_SCAN + "    recall_duration: 10\n", clock)
    e.observe(hz(-1))
    e.observe(hz(-1))
    assert fired(e) == ["slow"]
    clock.now = 9.9
    e.observe(hz(-1))
    assert fired(e) == []
    clock.now = 10.0
    assert fired(e) == ["slow"]


def test_a_condition_back_within_the_recall_duration_waits_until_it_is_up(
    tmp_path: Path,
) -> None:
    clock = Clock()
    e = engine(tmp_path, RESTART_ON_SLOW_SCAN + "    recall_duration: 5\n", clock)
    e.observe(hz(-1))
    e.observe(hz(-1))
    assert fired(e) == ["slow"]
    clock.now = 1.0
    for _ in range(3):
        e.observe(hz(0))
    assert fired(e) == []  # repaired
    clock.now = 2.0
    for _ in range(2):
        e.observe(hz(-1))
    assert fired(e) == []  # back 2 s after the firing
    clock.now = 5.0
    assert fired(e) == ["slow"]


def test_a_single_shot_rule_fires_only_once(tmp_path: Path) -> None:
    clock = Clock()
    e = engine(
        tmp_path, RESTART_ON_SLOW_SCAN + "    single_shot: true\n    recall_duration: 1\n", clock
    )
    e.observe(hz(-1))
    e.observe(hz(-1))
    assert fired(e) == ["slow"]
    for t in range(2, 10):
        clock.now = float(t)
        e.observe(hz(-1))
        assert fired(e) == []


def test_a_missing_observation_is_unknown_not_ok(tmp_path: Path) -> None:
    e = engine(
        tmp_path,
        """
rules:
  - type: log
    name: scan_ok
    positive_observations: [{type: hz, resource: scan, observation: ok}]
  - type: log
    name: scan_not_failing
    positive_observations: [{type: hz, resource: odom}]
    negative_observations: [{type: hz, resource: scan, observation: failed}]
""",
    )
    e.observe(hz(-1, "odom"))
    assert fired(e) == []
    e.observe(hz(3))
    assert fired(e) == ["scan_ok", "scan_not_failing"]


# Thesis Table 5.4: several rules fire at once; a list of resources is "any of them".
TABLE_5_4 = """
rules:
  - {type: log, name: first, positive_possible_faulty_resources: [{resource: N1}],
     negative_possible_faulty_resources: [{resource: N2}]}
  - {type: log, name: second, positive_possible_faulty_resources: [{resource: [N1, N2]}]}
  - {type: log, name: third, priority: 5,
     positive_possible_faulty_resources: [{resource: N1}, {resource: N2}]}
"""


@pytest.mark.parametrize(
    ("diagnoses", "expected"),
    [
        ([("N1",)], ["first", "second"]),
        ([("N2",)], ["second"]),
        ([("N1",), ("N2",)], ["third", "second"]),
        ([("N3",)], []),
    ],
)
def test_the_thesis_rules_fire_as_table_5_4_says(
    tmp_path: Path, diagnoses: list[tuple[str, ...]], expected: list[str]
) -> None:
    e = engine(tmp_path, TABLE_5_4)
    e.diagnosed(diagnosed(*diagnoses))
    assert fired(e) == expected


def test_possibly_faulty_counts_over_a_window_of_diagnoses(tmp_path: Path) -> None:
    e = engine(
        tmp_path,
        "rules:\n  - {type: log, name: lidar, positive_possible_faulty_resources: "
        "[{resource: lidar, occurrences: 2, window_size: 2}]}\n",
    )
    e.diagnosed(diagnosed(("lidar",)))
    assert fired(e) == []
    e.diagnosed(diagnosed(("lidar",), ("cam",)))
    assert fired(e) == ["lidar"]


def test_the_firing_names_the_faulty_components_and_failed_observations(tmp_path: Path) -> None:
    e = engine(tmp_path, TABLE_5_4)
    e.observe(hz(-1))
    e.diagnosed(diagnosed(("N1",)))
    firing = e.evaluate()[0].firing
    assert firing.faulty == ("N1",)
    assert firing.failed == ("frequency[scan]",)
    assert firing.fill("$rule: $faulty after $failed") == "first: N1 after frequency[scan]"


def test_rules_written_in_asp_trigger_and_inhibit_yaml_rules(tmp_path: Path) -> None:
    e = engine(
        tmp_path,
        TABLE_5_4 + "  - {type: log, name: by_asp, message: two at once}\nasp: [extra.lp]\n",
        asp='trigger("by_asp") :- diagnosis(_,"N1"), failed("frequency","scan").\n'
        'inhibit("second") :- status("DIAGNOSED"), possibly_faulty("N3").\n',
    )
    e.observe(hz(-1))
    e.diagnosed(diagnosed(("N1",)))
    assert fired(e) == ["first", "second", "by_asp"]
    e.diagnosed(diagnosed(("N2",), ("N3",)))
    assert fired(e) == []


def test_an_invalid_asp_rule_file_is_refused_with_file_and_line(tmp_path: Path) -> None:
    with pytest.raises(AspError, match=r"extra\.lp:2:8: syntax error"):
        engine(tmp_path, TABLE_5_4 + "asp: [extra.lp]\n", asp="a.\nb :- c(.\n")
