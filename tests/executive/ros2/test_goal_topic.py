"""Goals from ROS 2: what one message on /dura/goals asks for."""

from __future__ import annotations

import pytest

from executive.bus.api.planning import GoalAdd
from executive.ros2.goal_topic import replies_topic, submission


def test_a_submission_is_an_expression_or_a_json_object_with_its_options() -> None:
    assert submission(" (visited lab) ") == GoalAdd("(visited lab)")
    assert submission('{"expression": "(visited lab)", "priority": 2, "deadline": 60}') == (
        GoalAdd("(visited lab)", 2, 60)
    )
    assert replies_topic("/dura/goals") == "/dura/goals/replies"


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        ('{"priority": 2}', "needs an 'expression'"),
        ('{"expression": "(x)", "prio": 2}', "unknown key 'prio'"),
        ("{not json", "Expecting property name"),
    ],
)
def test_a_malformed_json_submission_says_why(text: str, reason: str) -> None:
    with pytest.raises(ValueError, match=reason):
        submission(text)
