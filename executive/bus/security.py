"""Who may use a robot's bus: per-robot credentials and Zenoh's own access control.

The executive listens as a Zenoh router with user-password authentication: a process
without the robot's credentials cannot even connect. Every user has a role, and Zenoh's
access control (default deny) lets each role do only what its part needs, checked by the
router on every message that reaches it from a client:

- ``executive`` and ``service`` (the executive's own services in other processes):
  everything under ``dura/<robot>/``;
- ``host.<name>`` (one user per host agent, ``dura host``): serve its own requests
  (``host/<name>/...``: spawn, signal, logs), publish the exits of its processes and the
  resources of its components (on ``host/<name>/resources``: the executive passes on
  only those of the components placed on that host), declare its own liveliness token, and listen — nothing
  else, so a host cannot command components, forge a state or call the API;
- ``operator`` (the CLI, the dashboard, the test harness, scripts): call the services'
  APIs, command components (fault injection), read the diagnosis model and switch
  exoneration, subscribe and watch liveliness — but publish nothing and change no
  diagnosis model (only the executive and its services do), so no operator can forge a
  diagnosis, an observation or a state, nor make the diagnosis blind;
- ``fleet`` (a fleet's high level, ``dura fleet run``, which plans for several robots):
  ask this robot's task executor for plan steps and control them
  (``executive/steps/{run,control,upcoming}``), hear how they go
  (``executive/steps/progress``) and the robot's events, read the robot's world (``state/get``, ``status``) and
  watch liveliness — nothing else: it cannot post goals, change facts, command components
  or publish;
- ``component.<name>`` (one user per component): publish the topics its description
  lists under ``publishes``, and only under its own name (``from/<name>/topic/<t>``: the
  caller id observers see is the login's, see :mod:`executive.bus.session`), subscribe
  to the topics it ``subscribes`` and those its ``may_subscribe`` opens, publish its
  own results and feedback, answer its own commands, declare its own liveliness token, watch liveliness, and call the few verbs
  a component needs: its own achievements (``.../component/achieve/<name>``) and facts.

The rules are made from the robot description each time the executive starts: a
changed description changes them.

Credentials are generated on the executive's first run into ``.dura/<robot>.bus.json``
(user-only permissions, 0600) and kept; components get theirs from the launcher in their
environment, the command line reads the file. For a client on another machine, copy the
file (it is the robot's key: treat it like an SSH key). A host agent needs only its own
login: the executive writes it alone into ``.dura/<robot>.<host>.bus.json`` (also
user-only), the file to copy to that host; the launcher hands each component started
there its login in the start request. The same for a fleet's login:
``.dura/<robot>.fleet.bus.json``.
"""

from __future__ import annotations

import contextlib
import json
import os
import stat
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from knowledge.errors import BusError

if TYPE_CHECKING:
    from knowledge.description import RobotDescription

EXECUTIVE = "executive"
SERVICE = "service"
OPERATOR = "operator"
FLEET = "fleet"
COMPONENT = "component."
HOST = "host."

ENV_USER = "DURA_BUS_USER"  # a component's user and password, set by the launcher
ENV_PASSWORD = "DURA_BUS_PASSWORD"  # noqa: S105 - the name of a variable, not a password
ENV_CREDENTIALS = "DURA_BUS_CREDENTIALS"  # a credentials file to use instead of .dura/'s

ALL = [
    "put",
    "delete",
    "declare_subscriber",
    "query",
    "declare_queryable",
    "reply",
    "liveliness_token",
    "declare_liveliness_subscriber",
    "liveliness_query",
]


@dataclass(frozen=True)
class Topics:
    """The topics a component may publish and subscribe (its description's):
    ``may_subscribe`` are more it may read, names or patterns (``*``, ``**``)."""

    publishes: tuple[str, ...] = ()
    subscribes: tuple[str, ...] = ()
    may_subscribe: tuple[str, ...] = ()


@dataclass(frozen=True)
class Login:
    """A user and password to connect with."""

    user: str
    password: str


@dataclass(frozen=True)
class Credentials:
    """A robot's bus users and their passwords (the router's dictionary)."""

    robot: str
    passwords: Mapping[str, str]

    def login(self, user: str) -> Login:
        """The login of a user.

        Raises:
            BusError: the credentials have no such user.
        """
        password = self.passwords.get(user)
        if password is None:
            raise BusError(f"the bus credentials of robot '{self.robot}' have no user '{user}'")
        return Login(user, password)

    def to_payload(self) -> dict[str, Any]:
        return {"robot": self.robot, "users": dict(sorted(self.passwords.items()))}


def component_user(name: str) -> str:
    return COMPONENT + name


def host_user(name: str) -> str:
    return HOST + name


def credentials_file(folder: Path, robot: str) -> Path:
    """Where a robot's credentials live in a working folder's ``.dura/``."""
    return folder / ".dura" / f"{robot}.bus.json"


def host_credentials_file(folder: Path, robot: str, host: str) -> Path:
    """Where the login of one host agent lives (the file to copy to that host)."""
    return folder / ".dura" / f"{robot}.{host}.bus.json"


def fleet_credentials_file(folder: Path, robot: str) -> Path:
    """Where the fleet's login lives (the file to copy to the fleet's computer)."""
    return folder / ".dura" / f"{robot}.{FLEET}.bus.json"


def write_fleet_credentials(credentials: Credentials, folder: Path) -> None:
    """Write the fleet's login alone into its file (user-only), the file to copy."""
    login = credentials.login(FLEET)
    only = Credentials(credentials.robot, {login.user: login.password})
    path = fleet_credentials_file(folder, credentials.robot)
    _write_private(path, json.dumps(only.to_payload(), indent=2) + "\n")


def write_host_credentials(credentials: Credentials, folder: Path, hosts: Iterable[str]) -> None:
    """Write each host agent's own login into its file (user-only), the file to copy."""
    for host in hosts:
        login = credentials.login(host_user(host))
        only = Credentials(credentials.robot, {login.user: login.password})
        path = host_credentials_file(folder, credentials.robot, host)
        _write_private(path, json.dumps(only.to_payload(), indent=2) + "\n")


def read_credentials(path: Path) -> Credentials:
    """Read a credentials file.

    Raises:
        BusError: it is missing, unreadable, malformed, or others may read it.
    """
    try:
        mode = path.stat().st_mode
        data = json.loads(path.read_text())
        users = data["users"]
        if not isinstance(users, dict) or not all(
            isinstance(k, str) and isinstance(v, str) for k, v in users.items()
        ):
            raise ValueError("'users' must map names to passwords")
        robot = str(data["robot"])
    except FileNotFoundError:
        raise BusError(
            f"{path}: no bus credentials (the executive writes them when it starts)"
        ) from None
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise BusError(f"{path}: unreadable bus credentials ({e})") from e
    if mode & (stat.S_IRWXG | stat.S_IRWXO):
        raise BusError(f"{path}: others may read the bus credentials (run: chmod 600 {path})")
    return Credentials(robot, users)


def ensure_credentials(
    path: Path, robot: str, components: Iterable[str], hosts: Iterable[str] = ()
) -> Credentials:
    """The robot's credentials, created with user-only permissions if missing; a user for
    every component and host that lacks one is added (a robot description may grow).

    Raises:
        BusError: an existing file is unreadable, or belongs to another robot.
    """
    wanted = [EXECUTIVE, SERVICE, OPERATOR, FLEET, *(component_user(c) for c in components),
              *(host_user(h) for h in hosts)]  # fmt: skip
    existing: dict[str, str] = {}
    if path.exists():
        known = read_credentials(path)
        if known.robot != robot:
            raise BusError(f"{path}: bus credentials of robot '{known.robot}', not '{robot}'")
        existing = dict(known.passwords)
    missing = [user for user in wanted if user not in existing]
    if not missing:
        return Credentials(robot, existing)
    import secrets  # only when credentials are made: the command line never needs it

    passwords = {**existing, **{user: secrets.token_urlsafe(24) for user in missing}}
    credentials = Credentials(robot, passwords)
    _write_private(path, json.dumps(credentials.to_payload(), indent=2) + "\n")
    return credentials


def _write_private(path: Path, text: str) -> None:
    """Write a file only its owner may read, atomically (never readable by others, not
    even for a moment)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{os.getpid()}")
    fd = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    try:
        with os.fdopen(fd, "w") as out:
            out.write(text)
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(OSError):
            temporary.unlink()
        raise


def dictionary(credentials: Credentials, path: Path) -> Path:
    """Write the router's user-password dictionary (user-only) and return its path."""
    lines = "".join(f"{user}:{password}\n" for user, password in credentials.passwords.items())
    _write_private(path, lines)
    return path


def access_control(
    robot: str,
    components: Iterable[str],
    hosts: Iterable[str] = (),
    *,
    topics: Mapping[str, Topics] | None = None,
) -> dict[str, Any]:
    """Zenoh's access control configuration for a robot's bus (see the module doc);
    ``topics`` are what each component may publish and subscribe (none if absent)."""
    root = f"dura/{robot}"
    topics = topics or {}
    rules: list[dict[str, Any]] = [
        _rule("everything", ALL, [f"{root}/**"]),
        _rule("deliver", ALL, [f"{root}/**"], flows=["egress"]),
        _rule("ask", ["query"], [f"{root}/executive/api/**", f"{root}/monitoring/**",
                                 f"{root}/diagnosis/model/read", f"{root}/diagnosis/exonerate",
                                 f"{root}/component/*/cmd"]),
        _rule("listen", ["declare_subscriber", "declare_liveliness_subscriber",
                         "liveliness_query"], [f"{root}/**"]),
        _rule("watch", ["declare_liveliness_subscriber", "liveliness_query"],
              [f"{root}/alive/**"]),
        _rule("component calls", ["query"], [f"{root}/executive/api/state/set",
                                             f"{root}/executive/api/state/unset"]),
        _rule("fleet steps", ["query"], [f"{root}/executive/steps/run",
                                         f"{root}/executive/steps/control",
                                         f"{root}/executive/steps/upcoming",
                                         f"{root}/executive/api/state/get",
                                         f"{root}/executive/api/status"]),
        _rule("fleet hears", ["declare_subscriber"], [f"{root}/executive/steps/progress",
                                                      f"{root}/events"]),
    ]  # fmt: skip
    subjects = [
        {"id": "trusted", "usernames": [EXECUTIVE, SERVICE]},
        {"id": "operators", "usernames": [OPERATOR]},
        {"id": "fleet", "usernames": [FLEET]},
    ]
    policies = [
        {"rules": ["everything", "deliver"], "subjects": ["trusted"]},
        {"rules": ["deliver", "ask", "listen"], "subjects": ["operators"]},
        {"rules": ["deliver", "watch", "fleet steps", "fleet hears"], "subjects": ["fleet"]},
    ]
    for name in components:
        own = f"own {name}"
        allowed = topics.get(name, Topics())
        published = [f"{root}/from/{name}/topic/{t.strip('/')}" for t in allowed.publishes]
        rules.append(
            _rule(
                own,
                ["put"],
                [f"{root}/component/{name}/result", f"{root}/component/{name}/feedback",
                 *published],
            )
        )  # fmt: skip
        rules.append(_rule(f"{own} calls", ["query"],
                           [f"{root}/executive/api/component/achieve/{name}"]))  # fmt: skip
        heard = [f"{root}/from/*/topic/{t.strip('/')}"
                 for t in dict.fromkeys((*allowed.subscribes, *allowed.may_subscribe))]  # fmt: skip
        if heard:
            rules.append(_rule(f"{own} subscribes", ["declare_subscriber"], heard))
        rules.append(_rule(f"{own} commands", ["declare_queryable", "reply"],
                           [f"{root}/component/{name}/cmd"]))  # fmt: skip
        rules.append(_rule(f"{own} token", ["liveliness_token"],
                           [f"{root}/alive/component/{name}/*"]))  # fmt: skip
        subject = f"component {name}"
        subjects.append({"id": subject, "usernames": [component_user(name)]})
        policies.append(
            {
                "rules": ["deliver", "watch", "component calls", own, f"{own} calls",
                          f"{own} commands", f"{own} token",
                          *([f"{own} subscribes"] if heard else [])],
                "subjects": [subject],
            }
        )  # fmt: skip
    for name in hosts:
        own = f"host {name}"
        rules.append(_rule(f"{own} serves", ["declare_queryable", "reply"],
                           [f"{root}/host/{name}/*"]))  # fmt: skip
        rules.append(_rule(f"{own} reports", ["put"],
                           [f"{root}/host/{name}/exit", f"{root}/host/{name}/resources",
                            f"{root}/host/{name}/stopping"]))  # fmt: skip
        rules.append(_rule(f"{own} token", ["liveliness_token"], [f"{root}/alive/host/{name}"]))
        subjects.append({"id": own, "usernames": [host_user(name)]})
        policies.append(
            {
                "rules": ["deliver", "listen", f"{own} serves", f"{own} reports", f"{own} token"],
                "subjects": [own],
            }
        )
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }


def topics_of(robot: RobotDescription) -> dict[str, Topics]:
    """What each component of a robot may publish and subscribe, from its description."""
    return {
        name: Topics(tuple(spec.publishes), tuple(spec.subscribes), tuple(spec.may_subscribe))
        for name, spec in robot.components.items()
    }


def _rule(
    rule_id: str, messages: list[str], keys: list[str], *, flows: list[str] | None = None
) -> dict[str, Any]:
    return {
        "id": rule_id,
        "permission": "allow",
        "flows": flows or ["ingress"],
        "messages": messages,
        "key_exprs": keys,
    }


def find_login(robot: str, user: str, folders: Iterable[Path]) -> Login | None:
    """The login of ``user`` from the robot's credentials: the file ``DURA_BUS_CREDENTIALS``
    names, else ``.dura/<robot>.bus.json`` in the first of ``folders`` that has one;
    ``None`` if there is none (an executive without security, or none yet).

    Raises:
        BusError: a credentials file is there but unusable (unreadable, others may read
            it, another robot's, or without that user).
    """
    named = os.environ.get(ENV_CREDENTIALS)
    candidates = [Path(named)] if named else [credentials_file(f, robot) for f in folders]
    for path in candidates:
        if path.exists() or named:
            credentials = read_credentials(path)
            if credentials.robot != robot:
                raise BusError(
                    f"{path}: bus credentials of robot '{credentials.robot}', not '{robot}'"
                )
            return credentials.login(user)
    return None


def find_host_login(robot: str, host: str, folder: Path, named: Path | None = None) -> Login:
    """A host agent's login: from ``named``, else the file ``DURA_BUS_CREDENTIALS`` names,
    else ``.dura/<robot>.<host>.bus.json``, else ``.dura/<robot>.bus.json`` in ``folder``.

    Raises:
        BusError: none of them is there, or the one there is unusable.
    """
    env = os.environ.get(ENV_CREDENTIALS)
    if named is not None or env:
        candidates = [named or Path(str(env))]
    else:
        candidates = [host_credentials_file(folder, robot, host), credentials_file(folder, robot)]
    for path in candidates:
        if path.exists() or len(candidates) == 1:
            credentials = read_credentials(path)
            if credentials.robot != robot:
                raise BusError(
                    f"{path}: bus credentials of robot '{credentials.robot}', not '{robot}'"
                )
            return credentials.login(host_user(host))
    wanted = host_credentials_file(Path("."), robot, host)
    raise BusError(
        f"no bus credentials for host '{host}': copy {wanted} from the executive's folder "
        f"into {folder / '.dura'} (chmod 600), or name it with --credentials"
    )
