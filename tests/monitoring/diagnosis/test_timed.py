"""The diagnosis service's timing on a clock the test drives (the replay's diagnosis), in
integer nanoseconds since the epoch."""

from __future__ import annotations

from executive.bus.payloads import ObservationInfo
from monitoring.diagnosis.engine import DiagnosisEngine
from monitoring.diagnosis.model import Node, UpdateAction
from monitoring.diagnosis.timed import TimedDiagnosis

T0_NS = 1_700_000_000 * 10**9  # a recording's clock


def at(ms: int) -> int:
    """``ms`` milliseconds after T0, in nanoseconds."""
    return T0_NS + ms * 1_000_000


def scan(observation: int, ms: int) -> ObservationInfo:
    return ObservationInfo("timeout", ("scan",), observation, stamp=at(ms) / 1e9)


def timed(settle: float = 0.02) -> TimedDiagnosis:
    diagnosis = TimedDiagnosis(DiagnosisEngine(), settle=settle, period=1.0)
    diagnosis.change_model(UpdateAction.ADD, [Node("lidar", (), ("scan",))], at(0))
    settled = at(round(settle * 1000))
    assert diagnosis.wake_at_ns == settled and diagnosis.wake(settled) is None  # OK, as before
    return diagnosis


def test_a_failed_observation_is_diagnosed_after_settling_and_repeated_every_period() -> None:
    diagnosis = timed()
    diagnosis.observe(scan(-4, 5000), at(5000))  # the observer is learnt from its observation
    diagnosis.observe(scan(-4, 5010), at(5010))  # no change of verdict: nothing more to do
    assert diagnosis.wake_at_ns == at(5020)
    published = diagnosis.wake(at(5020))
    assert published is not None and published.changed
    assert published.result.diagnoses == (("lidar",),)
    assert diagnosis.wake_at_ns == at(6020)
    repeated = diagnosis.wake(at(6020))
    assert repeated is not None and not repeated.changed and repeated.time_ns == at(6020)


def test_a_change_while_waiting_to_repeat_settles_first_and_the_all_clear_ends_the_repeats() -> (
    None
):
    diagnosis = timed()
    diagnosis.observe(scan(-4, 5000), at(5000))
    diagnosis.wake(at(5020))
    diagnosis.observe(scan(0, 5500), at(5500))
    assert diagnosis.wake_at_ns == at(5520)
    cleared = diagnosis.wake(at(5520))
    assert cleared is not None and cleared.changed and cleared.result.diagnoses == ()
    assert diagnosis.wake_at_ns is None


def test_a_settle_ends_to_the_nanosecond_where_float_seconds_since_the_epoch_do_not() -> None:
    diagnosis = timed(settle=0.01)
    diagnosis.observe(scan(-4, 10500), at(10500))
    assert diagnosis.wake_at_ns == at(10510)  # in float seconds: 128 ns early
    assert round((at(10500) / 1e9 + 0.01) * 1e9) == at(10510) - 128


def test_removing_a_node_removes_the_observers_learnt_for_it() -> None:
    diagnosis = timed()
    diagnosis.observe(scan(-4, 5000), at(5000))
    diagnosis.change_model(UpdateAction.REMOVE, [Node("lidar", (), ("scan",))], at(5010))
    assert diagnosis.engine.model.observers == ()
    assert diagnosis.wake(at(5020)) is None  # nothing failed any more: OK, as before
