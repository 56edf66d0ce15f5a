"""A registry of broken observer configurations in the use-case robot, with the finding each
must produce (the line that contains ``line_of``, and a message). Tests and docs share it."""

from __future__ import annotations

from tests.knowledge.robot_cases import BrokenRobot

FILTER = "filter: {type: mean, window_size: 10}"
CHECK = "frequency: {type: in_between, lower_bound: 8.0, upper_bound: 12.0}"
TIMEOUT = "{callerid: [], timeout: 0.5, max_timeouts_in_a_row: 2}"
GROUP = "caller-id group 1 of topic 'scan' of the frequency observer of functionality 'lidar'"
STATE = f"state 1 of {GROUP}"


def _case(name: str, old: str, new: str, message: str, line_of: str | None = None) -> BrokenRobot:
    return BrokenRobot(name, old, new, line_of or new.strip().splitlines()[0], message)


BROKEN_OBSERVERS = [
    _case(
        "mean window below 2",
        FILTER,
        "filter: {type: mean, window_size: 1}",
        f"'window_size' of the filter of {GROUP} must be at least 2, not 1",
    ),
    _case(
        "median without a window",
        FILTER,
        "filter: {type: median}",
        f"the filter of {GROUP} (median) has no 'window_size'",
    ),
    _case(
        "decay rate outside (0, 1)",
        FILTER,
        "filter: {type: ewma, decay_rate: 1.5}",
        f"'decay_rate' of the filter of {GROUP} must be between 0 and 1 (exclusive), not 1.5",
    ),
    _case(
        "ewma without a decay rate",
        FILTER,
        "filter: {type: ewma, window_size: 5}",
        f"the filter of {GROUP} has no 'decay_rate'",
    ),
    _case(
        "kmeans k above the window",
        FILTER,
        "filter: {type: kmeans, window_size: 5, k_size: 6}",
        f"'k_size' of the filter of {GROUP} (6) exceeds its window (5)",
    ),
    _case(
        "unknown filter",
        FILTER,
        "filter: {type: meen, window_size: 10}",
        "unknown filter type 'meen'",
    ),
    _case(
        "unknown deviation",
        FILTER,
        "filter: {type: mean, window_size: 10, deviation_type: sdt}",
        "unknown deviation type 'sdt'",
    ),
    _case(
        "unknown check",
        CHECK,
        "frequency: {type: in_betwen, lower_bound: 8.0, upper_bound: 12.0}",
        "unknown check type 'in_betwen' in the frequency check of " + STATE,
    ),
    _case(
        "bounds the wrong way round",
        CHECK,
        "frequency: {type: in_between, lower_bound: 12.0, upper_bound: 8.0}",
        "'lower_bound' 12 exceeds 'upper_bound' 8",
    ),
    _case(
        "check without its value",
        CHECK,
        "frequency: {type: greater_than}",
        f"the frequency check of {STATE} has no 'greater_than'",
    ),
    _case(
        "significance level outside (0, 1)",
        CHECK,
        "frequency: {type: student_t, true_mean: 10, std_deviation: 1, significance_level: 5}",
        "'significance_level' of the frequency check of",
    ),
    _case(
        "state without a number",
        "{state: ok, number: 1, ",
        "{state: ok, ",
        f"{STATE} has no 'number'",
        line_of="{state: ok, frequency",
    ),
    _case(
        "state without a check",
        f"{{state: ok, number: 1, {CHECK}}}",
        "{state: ok, number: 1}",
        f"{STATE} has no 'frequency' check",
    ),
    _case(
        "timeout missing",
        TIMEOUT,
        "{callerid: [], max_timeouts_in_a_row: 2}",
        "caller-id group 1 of topic 'scan' of the timeout observer of functionality 'lidar' has no 'timeout'",
    ),
    _case(
        "negative timeout",
        TIMEOUT,
        "{callerid: [], timeout: -1, max_timeouts_in_a_row: 2}",
        "'timeout' of caller-id group 1 of topic 'scan' of the timeout observer",
    ),
    _case(
        "unknown observer type",
        "      - type: timeout",
        "      - type: timeot",
        "unknown observer type 'timeot' (choose from",
    ),
    _case(
        "misspelt key",
        "        main_loop_rate: 2.0",
        "        main_loop_rat: 2.0",
        "unknown key 'main_loop_rat' in frequency observer of functionality 'lidar' "
        "(did you mean 'main_loop_rate'?)",
    ),
    _case(
        "wildcard topic",
        "          - name: scan\n            callerids:",
        "          - name: scan/*\n            callerids:",
        "invalid topic name 'scan/*'",
    ),
    _case(
        "caller id that is no name",
        "              - callerid: []",
        "              - callerid: [3]",
        "'callerid' of caller-id group 1 of topic 'scan' of the frequency observer of "
        "functionality 'lidar' must list names, not 3",
    ),
]
