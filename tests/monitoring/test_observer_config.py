"""Observer configurations: every problem named with its file and line, tug files, plugins."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from collections.abc import Callable
from pathlib import Path
from subprocess import CompletedProcess

import pytest

from knowledge.errors import ConfigError
from knowledge.robot import load_robot, read_robot
from monitoring.observer import canonical_type, observer_class
from monitoring.observer_config import check_observer_file, check_observers, config_of
from monitoring.observers.frequency import FrequencyConfig
from tests.conftest import ROOT, USECASE
from tests.knowledge.robot_cases import BrokenRobot
from tests.monitoring.observer_cases import BROKEN_OBSERVERS

Dura = Callable[..., CompletedProcess[str]]


def test_the_use_case_observers_are_valid_and_typed() -> None:
    robot = load_robot(USECASE)
    assert check_observers(robot) == []
    config = config_of(robot.functionalities["lidar"].observers[0])
    assert isinstance(config, FrequencyConfig)
    [topic] = config.topics
    [group] = topic.groups
    assert (topic.name, group.callerids, group.settings.filter.window_size) == ("scan", (), 10)
    assert config.main_loop_rate == 2.0 and config.start_up_time == 2.0


@pytest.mark.parametrize("case", BROKEN_OBSERVERS, ids=lambda c: c.name)
def test_a_bad_observer_is_reported_with_its_file_and_line(
    case: BrokenRobot, tmp_path: Path
) -> None:
    path = case.write(tmp_path)
    robot, findings = read_robot(path)
    assert robot is not None and not [f for f in findings if f.is_error]
    found = check_observers(robot)
    lines = [str(f) for f in found]
    prefix = f"{path.resolve()}:{case.expected_line(tmp_path)}: "
    assert any(line.startswith(prefix) and case.message in line for line in lines), lines


def test_a_topic_no_component_knows_is_a_warning(tmp_path: Path) -> None:
    case = BrokenRobot(
        "topic typo",
        "          - name: scan\n            callerids:\n              - {callerid: [], timeout",
        "          - name: scna\n            callerids:\n              - {callerid: [], timeout",
        "- type: timeout",
        "the timeout observer of functionality 'lidar' watches topic 'scna', which no "
        "component publishes or subscribes to (did you mean 'scan'?)",
    )
    robot, _ = read_robot(case.write(tmp_path))
    assert robot is not None
    [warning] = check_observers(robot)
    assert not warning.is_error and warning.line == case.expected_line(tmp_path)
    assert warning.message == case.message


def test_dura_validate_lists_observer_errors_and_exits_1(dura: Dura, tmp_path: Path) -> None:
    path = BROKEN_OBSERVERS[0].write(tmp_path)
    result = dura("validate", str(path))
    assert result.returncode == 1
    line = BROKEN_OBSERVERS[0].expected_line(tmp_path)
    assert result.stderr.startswith(f"{path}:{line}: 'window_size' of the filter"), result.stderr


def test_aliases_and_legacy_spellings_of_tug_configurations_are_read() -> None:
    config = config_of(
        {
            "type": "hz",
            "topics": [
                {
                    "name": "/scan",
                    "callerids": [
                        {
                            "callerid": ["/nodeA"],
                            "filter": {"type": "mean", "window_size": 5},
                            "states": [
                                {
                                    "state": "fast",
                                    "number": 1,
                                    "frequenzy": {"type": "greather_than", "greather_than": 5},
                                }
                            ],
                        }
                    ],
                }
            ],
        }
    )
    assert isinstance(config, FrequencyConfig)
    group = config.topics[0].groups[0]
    assert config.type == "frequency" and config.topics[0].name == "scan"
    assert group.callerids == ("nodeA",)
    assert str(group.settings.states[0].checks["frequency"]) == "> 5"
    assert [canonical_type(a) for a in ("activated", "hz", "value", "velocity")] == [
        "component",
        "frequency",
        "scores",
        "movement",
    ]


def test_a_configuration_from_the_bus_has_no_line_but_names_its_source() -> None:
    with pytest.raises(ConfigError) as raised:
        config_of({"type": "timing", "topics": [{"topicA": "a"}]}, path="monitoring/observers/add")
    assert str(raised.value).startswith(
        "monitoring/observers/add: topic pair 1 of the timing observer has no 'topicB' (and "
    )


TUG_FILE = """\
setup:
  - type: timeout
    topics:
      - name: /scan
        callerids:
          - {callerid: [], timeout: 1.0}
  - type: timing
    main_loop_rate: 1.0
    use_global_subscriber: true
    topics:
      - topicA: /scan
        calleridA: []
        topicB: /scan_filtered
        calleridB: []
        filter: {type: median, window_size: 5}
        states:
          - {state: ok, number: 1, delay: {type: less_than, less_than: 0.1}}
"""


def test_a_tug_observers_file_is_read_with_lines(tmp_path: Path) -> None:
    path = tmp_path / "observers.yaml"
    path.write_text(TUG_FILE.replace("less_than: 0.1", "less_than: fast"))
    checked = check_observer_file(path)
    assert checked is not None
    specs, findings = checked
    assert [s.type for s in specs] == ["timeout", "timing"]
    assert [str(f) for f in findings] == [
        f"{path}:17: 'less_than' of the delay check of state 1 of topics 'scan' -> "
        "'scan_filtered' of the timing observer must be a number, not 'fast'"
    ]


def test_dura_validate_checks_a_tug_observers_file(dura: Dura, tmp_path: Path) -> None:
    path = tmp_path / "observers.yaml"
    path.write_text(TUG_FILE)
    result = dura("validate", str(path))
    assert result.returncode == 0, result.stderr
    assert result.stdout == f"{path}: valid: 2 observers (timeout, timing)\n"
    assert check_observer_file(USECASE) is None


PLUGIN = """\
from dataclasses import dataclass

from monitoring.observer import Observer, ObserverConfig


@dataclass(frozen=True, kw_only=True)
class BeaconConfig(ObserverConfig):
    colour: str


class Beacon(Observer):
    type = "beacon"
    aliases = ("lighthouse",)
    config_type = BeaconConfig

    def _observe(self, now):
        return []
"""


def test_third_party_observer_types_come_from_the_entry_point_group(tmp_path: Path) -> None:
    (tmp_path / "beacon_plugin.py").write_text(PLUGIN)
    info = tmp_path / "beacon_plugin-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: beacon-plugin\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(
        "[dura.observers]\nbeacon = beacon_plugin:Beacon\nbroken = beacon_plugin:Missing\n"
    )
    script = textwrap.dedent(
        """
        from monitoring.observer_config import config_of
        from monitoring.observer import observer_class
        print(config_of({"type": "lighthouse", "colour": "red"}).type)
        print(observer_class("broken"))
        """
    )
    result = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env={"PYTHONPATH": f"{tmp_path}:{ROOT}"},
        check=False,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == ["beacon", "None"]
    assert "cannot load observer plugin 'broken' (beacon_plugin:Missing)" in result.stderr
    assert observer_class("beacon") is None


def test_the_documented_example_of_every_observer_type_is_valid(tmp_path: Path) -> None:
    readme = (ROOT / "docs" / "how-to" / "observers.md").read_text()
    start = readme.index("```yaml\nobservers:\n") + len("```yaml\nobservers:\n")
    path = tmp_path / "observers.yaml"
    path.write_text(readme[start : readme.index("```", start)])
    checked = check_observer_file(path)
    assert checked is not None
    specs, findings = checked
    assert findings == []
    assert {canonical_type(s.type) for s in specs} == {
        "frequency",
        "timeout",
        "timestamp",
        "scores",
        "timing",
        "movement",
        "resources",
        "component",
    }
