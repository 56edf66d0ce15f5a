"""The diagnosis model follows the components the task executor starts and stops; an
update that is refused or gets no answer is a warning with the reason."""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.bus.api.monitoring import DIAGNOSIS_MODEL_READ
from executive.bus.keys import service_alive
from executive.bus.service import Context
from executive.bus.session import Bus
from executive.bus.worker import Worker
from executive.tasks.diagnosis_model import DiagnosisModelSync
from knowledge.description import RobotDescription
from knowledge.knowledge_base import KnowledgeBase
from monitoring.diagnosis.diagnosis_service import DiagnosisService
from tests.conftest import wait_for
from tests.executive.tasks.scheduling_cases import usecase_robot


def with_reserved_topic() -> RobotDescription:
    """The use case with lidar publishing ``ABscan`` (names starting AB are reserved)."""
    robot = usecase_robot()
    lidar = dataclasses.replace(robot.functionalities["lidar"], publishes=("ABscan",))
    return dataclasses.replace(robot, functionalities={**robot.functionalities, "lidar": lidar})


@pytest.fixture
def bus(endpoint: str) -> Iterator[Bus]:
    with Bus("usecase", name="executive", endpoint=endpoint, listen=True) as bus:
        yield bus


@pytest.fixture
def worker() -> Iterator[Worker]:
    worker = Worker("test worker")
    worker.start()
    yield worker
    worker.stop()


def model_nodes(bus: Bus) -> set[str]:
    model = DIAGNOSIS_MODEL_READ.call(bus).model or {}
    return {n["name"] for n in model.get("nodes", [])}


def test_a_refused_model_update_is_a_warning_with_the_reason_and_others_go_on(
    bus: Bus, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    robot = with_reserved_topic()
    with KnowledgeBase(tmp_path / "kb.db") as kb:
        diagnosis = DiagnosisService(Context(robot, bus, kb))
        diagnosis.configure()
        diagnosis.activate()
        try:
            sync = DiagnosisModelSync(bus, robot)
            with caplog.at_level(logging.WARNING, logger="dura.task_executor"):
                sync.add("lidar")
                sync.add("cam")
            (warning,) = caplog.records
            assert warning.levelno == logging.WARNING
            assert "ADD lidar" in warning.getMessage()
            assert "'ABscan' starts with 'AB'" in warning.getMessage()
            assert model_nodes(bus) == {"cam"}
            sync.remove("cam")
            sync.remove("lidar")  # never added: nothing to ask
            assert model_nodes(bus) == set()
            assert len(caplog.records) == 1
        finally:
            diagnosis.shutdown()


def test_a_model_update_nobody_answers_is_a_warning(
    bus: Bus, caplog: pytest.LogCaptureFixture
) -> None:
    sync = DiagnosisModelSync(bus, usecase_robot())
    with caplog.at_level(logging.WARNING, logger="dura.task_executor"):
        sync.add("cam")
    (warning,) = caplog.records
    assert warning.levelno == logging.WARNING
    assert warning.getMessage().startswith("diagnosis model not updated (ADD cam): ")


def test_changes_nobody_answered_reach_a_diagnosis_engine_that_comes_later(
    bus: Bus, worker: Worker, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    robot = usecase_robot()
    with KnowledgeBase(tmp_path / "kb.db") as kb:
        sync = DiagnosisModelSync(bus, robot, worker.post)
        try:
            with caplog.at_level(logging.WARNING, logger="dura.task_executor"):
                worker.call(lambda: sync.add("lidar"))
                worker.call(lambda: sync.add("cam"))
                worker.call(lambda: sync.remove("cam"))  # never added: nothing to ask
            assert caplog.records  # nobody answered: a warning
            diagnosis = DiagnosisService(Context(robot, bus, kb))  # monitoring comes now
            diagnosis.configure()
            diagnosis.activate()
            try:
                assert wait_for(lambda: model_nodes(bus) == {"lidar"}, 15)
            finally:
                diagnosis.shutdown()
        finally:
            worker.call(sync.close)


def test_a_monitoring_process_that_joins_gets_the_nodes_of_what_runs(
    bus: Bus, worker: Worker, tmp_path: Path
) -> None:
    robot = usecase_robot()
    with KnowledgeBase(tmp_path / "kb.db") as kb:
        first = DiagnosisService(Context(robot, bus, kb))
        first.configure()
        first.activate()
        sync = DiagnosisModelSync(bus, robot, worker.post)
        try:
            worker.call(lambda: sync.add("lidar"))
            assert model_nodes(bus) == {"lidar"}
            first.shutdown()  # the monitoring process ends, and another one starts
            second = DiagnosisService(Context(robot, bus, kb))
            second.configure()
            second.activate()
            token = bus.declare_alive(service_alive("monitoring"))
            try:
                assert wait_for(lambda: model_nodes(bus) == {"lidar"}, 15)
            finally:
                token.undeclare()
                second.shutdown()
        finally:
            worker.call(sync.close)
