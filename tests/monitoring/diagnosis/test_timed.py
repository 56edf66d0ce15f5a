"""The diagnosis service's timing on a clock the test drives (the replay's diagnosis)."""

from __future__ import annotations

from executive.bus.payloads import ObservationInfo
from monitoring.diagnosis.engine import DiagnosisEngine
from monitoring.diagnosis.model import Node, UpdateAction
from monitoring.diagnosis.timed import TimedDiagnosis


def scan(observation: int, stamp: float) -> ObservationInfo:
    return ObservationInfo("timeout", ("scan",), observation, stamp=stamp)


def timed() -> TimedDiagnosis:
    diagnosis = TimedDiagnosis(DiagnosisEngine(), settle=0.02, period=1.0)
    diagnosis.change_model(UpdateAction.ADD, [Node("lidar", (), ("scan",))], 0.0)
    assert diagnosis.wake_at == 0.02 and diagnosis.wake(0.02) is None  # OK, as before
    return diagnosis


def test_a_failed_observation_is_diagnosed_after_settling_and_repeated_every_period() -> None:
    diagnosis = timed()
    diagnosis.observe(scan(-4, 5.0), 5.0)  # the observer is learnt from its observation
    diagnosis.observe(scan(-4, 5.01), 5.01)  # no change of verdict: nothing more to do
    assert diagnosis.wake_at == 5.02
    published = diagnosis.wake(5.02)
    assert published is not None and published.changed
    assert published.result.diagnoses == (("lidar",),)
    assert diagnosis.wake_at == 6.02
    repeated = diagnosis.wake(6.02)
    assert repeated is not None and not repeated.changed and repeated.time == 6.02


def test_a_change_while_waiting_to_repeat_settles_first_and_the_all_clear_ends_the_repeats() -> (
    None
):
    diagnosis = timed()
    diagnosis.observe(scan(-4, 5.0), 5.0)
    diagnosis.wake(5.02)
    diagnosis.observe(scan(0, 5.5), 5.5)
    assert diagnosis.wake_at == 5.52
    cleared = diagnosis.wake(5.52)
    assert cleared is not None and cleared.changed and cleared.result.diagnoses == ()
    assert diagnosis.wake_at is None


def test_removing_a_node_removes_the_observers_learnt_for_it() -> None:
    diagnosis = timed()
    diagnosis.observe(scan(-4, 5.0), 5.0)
    diagnosis.change_model(UpdateAction.REMOVE, [Node("lidar", (), ("scan",))], 5.01)
    assert diagnosis.engine.model.observers == ()
    assert diagnosis.wake(5.02) is None  # nothing failed any more: OK, as before
