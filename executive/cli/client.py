"""How commands find the running executive they talk to, and ask it.

``dura run`` writes ``.dura/executive.json`` (robot, endpoint, pid) in its working
folder; commands run in the same folder find the executive there. ``--robot
ROBOT.yaml`` (with ``--endpoint``, if the executive listens elsewhere) names it instead;
in the folder where that robot's executive runs, ``--robot`` alone finds it there.
``dura fleet run`` writes the same run file for a fleet, whose high level answers the
same verbs; ``--fleet FLEET.yaml`` names a fleet as ``--robot`` names a robot.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from executive.bus import security
from executive.bus.security import Login
from executive.bus.session import Bus
from executive.bus.verb import Codec, Verb
from knowledge.errors import DuraError, NoAnswer

if TYPE_CHECKING:
    from knowledge.description import RobotDescription

RUN_FILE = Path(".dura") / "executive.json"

Req = TypeVar("Req", bound=Codec)
Rep = TypeVar("Rep", bound=Codec)


def add_client_options(parser: Any) -> None:
    parser.add_argument(
        "--robot",
        metavar="ROBOT.yaml",
        type=Path,
        help="the robot whose executive to ask (default: the one 'dura run' runs in this folder)",
    )
    parser.add_argument(
        "--fleet",
        dest="fleet_file",
        metavar="FLEET.yaml",
        type=Path,
        help="the fleet whose high level to ask (dura fleet run), instead of a robot",
    )
    parser.add_argument(
        "--endpoint",
        help="where that executive listens (default: where the one that runs in this folder "
        "does, if it is that robot's; else where the robot's description says)",
    )


def write_run_file(robot: str, endpoint: str, description: Path, credentials: Path) -> None:
    RUN_FILE.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(
        {"robot": robot, "endpoint": endpoint, "pid": os.getpid(),
         "description": str(description), "credentials": str(credentials.resolve())}
    )  # fmt: skip
    RUN_FILE.write_text(text + "\n")


def remove_run_file() -> None:
    """Remove the run file if this process wrote it."""
    try:
        if json.loads(RUN_FILE.read_text()).get("pid") == os.getpid():
            RUN_FILE.unlink()
    except (OSError, ValueError, AttributeError):
        pass


def _target(args: argparse.Namespace) -> tuple[str, str, Login | None]:
    """The robot's name, the endpoint of its executive and the operator's login: the
    executive that runs in this folder, unless ``--robot`` names another robot (then
    at ``--endpoint``, else where its description says), or ``--fleet`` a fleet."""
    fleet_file = getattr(args, "fleet_file", None)
    if fleet_file is not None:
        return _fleet(args, fleet_file)
    if args.robot is not None:
        robot = _read(args.robot)
        if args.endpoint is None and RUN_FILE.is_file():
            with contextlib.suppress(DuraError):  # this folder's executive, if it is this robot's
                name, endpoint, login = _running_here(args)
                if name == robot.name:
                    return name, endpoint, login
        login = security.find_login(robot.name, security.OPERATOR, [Path.cwd()])
        return robot.name, args.endpoint or robot.endpoint, login
    return _running_here(args)


def described_robot(args: argparse.Namespace) -> RobotDescription:
    """The description of the robot the command line names: ``--robot``, else that of
    the executive ``dura run`` runs in this folder.

    Raises:
        DuraError: no robot is named, or its description is unusable.
    """
    if args.robot is not None:
        return _read(args.robot)
    return _read(Path(run_file("description")["description"]))


def run_file(*fields: str) -> dict[str, Any]:
    """The run file of the executive ``dura run`` runs in this folder, with ``fields``.

    Raises:
        DuraError: there is none, or it is unreadable or lacks one of ``fields``.
    """
    try:
        found = json.loads(RUN_FILE.read_text())
        if not isinstance(found, dict):
            raise TypeError("not a JSON object")
        missing = [f for f in fields if f not in found]
        if missing:
            raise KeyError(missing[0])
    except FileNotFoundError:
        raise DuraError(
            f"no executive runs in this folder (no {RUN_FILE}): start one with "
            "'dura run ROBOT.yaml' or name its robot with --robot ROBOT.yaml"
        ) from None
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise DuraError(f"{RUN_FILE}: unreadable ({e}); name the robot with --robot") from e
    return found


def _read(path: Path) -> RobotDescription:
    from knowledge.robot import read_robot  # YAML and the schema: only where needed

    robot, findings = read_robot(path)
    if robot is None:
        errors = [f for f in findings if f.is_error]
        raise DuraError(str(errors[0]) if errors else f"{path}: unusable")
    return robot


def _fleet(args: argparse.Namespace, path: Path) -> tuple[str, str, Login | None]:
    """The fleet's name, the endpoint of its high level and the operator's login there
    (its credentials in this folder, else in the fleet description's)."""
    from executive.fleet.description import load_fleet  # YAML and the schema: only here

    fleet = load_fleet(path)
    if args.endpoint is None and RUN_FILE.is_file():
        with contextlib.suppress(DuraError):  # this folder's fleet, if it is this one
            name, endpoint, login = _running_here(args)
            if name == fleet.name:
                return name, endpoint, login
    login = security.find_login(fleet.name, security.OPERATOR, [Path.cwd(), fleet.path.parent])
    return fleet.name, args.endpoint or fleet.endpoint, login


def _running_here(args: argparse.Namespace) -> tuple[str, str, Login | None]:
    """The executive ``dura run`` runs in this folder, from its run file."""
    found = run_file("robot", "endpoint")
    name, endpoint = str(found["robot"]), str(found["endpoint"])
    credentials = found.get("credentials")
    if isinstance(credentials, str) and not os.environ.get(security.ENV_CREDENTIALS):
        return (
            name,
            args.endpoint or endpoint,
            security.read_credentials(Path(credentials)).login(security.OPERATOR),
        )
    return (
        name,
        args.endpoint or endpoint,
        security.find_login(name, security.OPERATOR, [Path.cwd()]),
    )


def connect(args: argparse.Namespace) -> Bus:
    """A bus session with the executive the command line names.

    Raises:
        DuraError: no executive is named, or none answers at its endpoint.
    """
    name, endpoint, login = _target(args)
    return Bus(name, name="cli", endpoint=endpoint, login=login)


def ask(
    args: argparse.Namespace,
    verb: Verb[Req, Rep],
    request: Req | None = None,
    *,
    timeout: float | None = None,
) -> Rep:
    """Call one verb of the executive the command line names: every command's one way
    to ask (see :mod:`executive.bus.api`).

    A verb nobody serves yet is asked again until the timeout: an executive that has
    just started answers ``status`` and the goal verbs first, its other services' verbs
    a moment later.

    Raises:
        DuraError: no executive answers, or it refused the request (its reason).
    """
    limit = verb.timeout if timeout is None else timeout
    deadline = time.monotonic() + limit
    first: NoAnswer | None = None
    with connect(args) as bus:
        while True:
            try:
                return verb.call(bus, request, timeout=limit)
            except NoAnswer as e:
                first = first or e
                limit = deadline - time.monotonic()
                if limit <= 0.1:
                    raise first from None
                time.sleep(0.1)
