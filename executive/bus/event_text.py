"""An event of the log as one readable line, the same in every view (``dura events``,
``goal show``, ``kb show``, the demo, the dashboard); a diagnosis result likewise.

:func:`describe` says what happened, starting with what it happened to: ``goal 1:
(picture_taken lab)``, ``move_to(dock, lab) (plan 1, step 0); as it starts: (robot_at
dock) no longer holds``, ``task 1 cancelled: stop robot_base, lidar_filter, lidar; nothing runs``.
Numbers are rounded, stamps are clocks, and no Python value shows through; a kind it
does not know reads as ``subject: key value, key value``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from executive.bus.event_kinds import WIDTH
from executive.bus.reports import DiagnosisInfo
from executive.bus.wording import (
    clock,
    goals_named,
    listed,
    number,
    pairs,
    plural,
    seconds,
    value,
)
from knowledge.records import Event

Data = Mapping[str, Any]


def describe(event: Event | Mapping[str, Any]) -> str:
    """What an event (a record, or its JSON form) says, on one line, without its kind and
    time."""
    data: Any
    if isinstance(event, Event):
        kind, subject, data = event.kind, event.subject, event.data
    else:
        kind, subject = str(event.get("kind", "")), str(event.get("subject", ""))
        data = event.get("data")
    if not isinstance(data, Mapping):
        data = {} if data in (None, "") else {"data": data}
    text = _TEXTS.get(kind)
    if text is None:
        text = next((t for prefix, t in _FAMILIES if kind.startswith(prefix)), _generic)
    try:
        return text(subject, data, kind)
    except (KeyError, TypeError, ValueError, AttributeError):  # an unexpected shape
        return _generic(subject, data, kind)


def line(event: Event | Mapping[str, Any]) -> str:
    """An event as a line of a log: its time of day, its kind, what it says."""
    if isinstance(event, Event):
        stamp, kind = event.stamp, event.kind
    else:
        stamp, kind = float(event.get("stamp", 0.0)), event.get("kind", "?")
    return f"{clock(stamp, millis=True)}  {kind!s:<{WIDTH}}  {describe(event)}".rstrip()


def diagnosis(payload: DiagnosisInfo | Mapping[str, Any]) -> str:
    """A diagnosis result (a ``diagnoses`` payload) on one line, as ``dura replay``
    writes it: ``DIAGNOSED: lidar (failed: timeout[scan])``, ``OK: nothing is faulty``."""
    if isinstance(payload, DiagnosisInfo):
        payload = payload.to_payload()
    status = str(payload.get("status", "?"))
    if status == "OK":
        return "OK: nothing is faulty"
    found = " | ".join(", ".join(d) for d in payload.get("diagnoses") or []) or "none"
    failed = "; ".join(_observer(o) for o in payload.get("failed") or []) or "-"
    return f"{status}: {found} (failed: {failed})"


def _observer(observer: Mapping[str, Any]) -> str:
    callers = list(observer.get("callerids") or [])
    ids = f" from {', '.join(callers)}" if callers else ""
    return f"{observer.get('type', '?')}[{', '.join(observer.get('resource') or [])}{ids}]"


def _generic(subject: str, data: Data, kind: str = "") -> str:
    shown = {k: v for k, v in data.items() if k != "stamp"}
    more = pairs(shown)
    return f"{subject}: {more}" if subject and more else subject or more


def _why(text: str, reason: object) -> str:
    return f"{text}: {reason}" if reason else text


# --- the executive and the world ------------------------------------------------------


def _executive(subject: str, data: Data, kind: str) -> str:
    if kind == "EXECUTIVE_STOPPED":
        return subject
    return f"{subject} on {data['endpoint']} (pid {data['pid']})"


def _world(subject: str, data: Data, kind: str) -> str:
    return f"{subject}: {plural(int(data['objects']), 'object')}"


def _fact(subject: str, data: Data, kind: str) -> str:
    if data.get("rule"):  # a sensing rule read it from a topic
        return f"{subject} (sensing rule {data['rule']}: {data.get('field')} = {value(data.get('value'))})"
    source = data.get("source")
    return f"{subject} (by {source})" if source else subject


def _timed(subject: str, data: Data, kind: str) -> str:
    """A fact that takes effect later: when (local time), and who said so."""
    import time  # only to show a timed fact

    when = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(float(data.get("at") or 0.0)))
    source = data.get("source")
    return f"{subject} from {when} on" + (f" (by {source})" if source else "")


def _object(subject: str, data: Data, kind: str) -> str:
    text = f"{subject} ({data['type']})"
    facts = list(data.get("facts") or [])
    if facts:
        text += f" with {plural(len(facts), 'fact')}: {listed(facts)}"
    return text


def _parameter(subject: str, data: Data, kind: str) -> str:
    return f"{subject}: {data['key']} = {value(data['value'])}"


def _exoneration(subject: str, data: Data, kind: str) -> str:
    return f"{subject}: exoneration {'on' if data['on'] else 'off'}"


# --- goals and plans ------------------------------------------------------------------


def _goal_added(subject: str, data: Data, kind: str) -> str:
    return f"{subject}: {data['expression']}" + (", kept true" if data.get("keep") else "")


def _goal_state(subject: str, data: Data, kind: str) -> str:
    return _why(subject, data.get("reason"))


def _planning(subject: str, data: Data, kind: str) -> str:
    text = f"for {goals_named(data.get('goals'))}"
    text = _why(text, data.get("reason"))
    blocked = list(data.get("blocked") or [])
    return f"{text}; cannot run now: {listed(blocked)}" if blocked else text


def _plan_stored(subject: str, data: Data, kind: str) -> str:
    text = f"{subject}: {plural(int(data['steps']), 'step')}"
    if data.get("engine"):
        text += f" by {data['engine']}"
    replaces = data.get("replaces")
    return f"{text}, replaces plan {replaces}" if replaces else text


def _plan_start(subject: str, data: Data, kind: str) -> str:
    return f"{subject}: {plural(int(data['steps']), 'step')} for {goals_named(data.get('goals'))}"


def _replan(subject: str, data: Data, kind: str) -> str:
    return _why(subject, data.get("reason"))


def _step(subject: str, data: Data, kind: str) -> str:
    text = subject
    if data.get("plan") is not None and data.get("step") is not None:
        robot = f", robot {data['robot']}" if data.get("robot") else ""  # a fleet's step
        text += f" (plan {data['plan']}, step {data['step']}{robot})"
    if kind == "START" and data.get("undo"):
        # the start's effects, said as changes ("at start: not (robot_at dock)" read as
        # a condition the step broke)
        text += "; as it starts: " + ", ".join(_effect(u) for u in data["undo"])
    if kind == "ADOPT" and data.get("from_plan") is not None:
        text += f" continues plan {data['from_plan']}'s step {data.get('from_step')}"
    if kind == "END" and isinstance(data.get("result"), Mapping) and data["result"]:
        text += f"; result: {pairs(data['result'])}"
    return _why(text, data.get("reason"))


def _effect(undo: Any) -> str:
    """An at-start effect from what it changed: ``[name, args, value before]``."""
    name, args, before = undo
    fact = "(" + " ".join([str(name), *map(str, args)]) + ")"
    if before is True:
        return f"{fact} no longer holds"
    if before is None or before is False:
        return f"{fact} holds"
    return f"{fact} changes from {number(before)}"


def _recovered(subject: str, data: Data, kind: str) -> str:
    cancelled = list(data.get("cancelled") or [])
    if not cancelled:
        return "recovery: no step was left under way"
    return f"recovery: cancelled {listed(cancelled)}, left under way by the last executive"


def _integrity(subject: str, data: Data, kind: str) -> str:
    if kind == "INTEGRITY_REFUSED":
        return _why(subject, data.get("reason"))
    trigger = str(data.get("trigger", "")).replace("_", " ")
    return f"{subject}: goal {data['goal']}" + (f" (on {trigger})" if trigger else "")


# --- tasks, configurations, faults ----------------------------------------------------


def _uses(providers: Any) -> str:
    return listed(sorted(set(dict(providers or {}).values())))


def _task(subject: str, data: Data, kind: str) -> str:
    if kind == "TASK_REQUESTED":
        duration = data.get("duration")
        return subject + (f" ({seconds(float(duration))})" if duration is not None else "")
    if kind in ("TASK_SCHEDULED", "TASK_STARTED"):
        text = f"{subject} on {_uses(data.get('providers'))}"
        attempt = data.get("attempt")
        return text + (f", attempt {attempt}" if attempt and int(attempt) > 1 else "")
    if kind == "TASK_RECONFIGURED":
        before = set(dict(data.get("before") or {}).values())
        after = set(dict(data.get("after") or {}).values())
        gone, new = sorted(before - after), sorted(after - before)
        return f"{subject}: {listed(gone) or 'nothing'} → {listed(new) or 'nothing'}"
    if kind == "TASK_RESTARTED" and data.get("attempt"):
        subject += f", restart {data['attempt']}"
    return _why(subject, data.get("reason"))


def _configuration(subject: str, data: Data, kind: str) -> str:
    stop, start = list(data.get("stop") or []), list(data.get("start") or [])
    resume = list(data.get("resume") or [])
    changes = []
    if stop:
        changes.append(f"stop {listed(stop)}")
    if resume:
        changes.append(f"resume {listed(resume)}")
    if start:
        changes.append(f"start {listed(start)}")
    if subject in ("", "nothing"):
        changes.append("nothing runs")
    elif set(subject.split(", ")) != set(start) | set(resume):
        changes.append(f"running {subject}")
    text = "; ".join(changes) or f"running {subject}"
    why = data.get("why")
    return f"{why}: {text}" if why else text


def _repair(subject: str, data: Data, kind: str) -> str:
    if "action" in data:  # the task executor's repair of a task's behavior
        return f"{subject}: {data['action']} {data.get('component', '')}".rstrip()
    attempt = f", attempt {data['attempt']}" if data.get("attempt") else ""
    parts = [f"{subject}: {'restart' if data.get('restart') else 'no restart'}{attempt}"]
    unusable = dict(data.get("unusable") or {})
    if unusable:
        parts.append("unusable: " + ", ".join(f"{n} ({why})" for n, why in unusable.items()))
    tasks = dict(data.get("tasks") or {})
    parts += [f"task {t}: {action}" for t, action in tasks.items()]
    return "; ".join(parts)


def _fault(subject: str, data: Data, kind: str) -> str:
    text = f"{subject}: fault {data['count']}"
    if data.get("permanent"):
        text += ", permanently faulty"
    return _why(text, data.get("reason"))


def _permanent_fault(subject: str, data: Data, kind: str) -> str:
    return _why(subject, data.get("reason"))


def _reset(subject: str, data: Data, kind: str) -> str:
    usable = list(data.get("usable") or [])
    return f"{subject}: usable again: {listed(usable)}" if usable else subject


def _host(subject: str, data: Data, kind: str) -> str:
    components = list(data.get("components") or [])
    if kind == "HOST_JOINED":
        return f"host {subject} joined" + (f": serves {listed(components)}" if components else "")
    how = "stopped" if kind == "HOST_STOPPED" else "lost"
    return f"host {subject} {how}" + (f": ended {listed(components)}" if components else "")


def _robot(subject: str, data: Data, kind: str) -> str:
    if kind == "ROBOT_JOINED":
        return f"robot {subject} joined the fleet"
    return _why(f"robot {subject} is unavailable", data.get("reason"))


def _component(subject: str, data: Data, kind: str) -> str:
    text = subject + (f" (pid {data['pid']})" if data.get("pid") is not None else "")
    if data.get("signal") is not None:
        text += f" killed by signal {data['signal']}"
    elif data.get("exit_code") is not None and (kind == "COMPONENT_EXITED" or data["exit_code"]):
        text += f" exited with code {data['exit_code']}"
    return _why(text, data.get("reason"))


def _goal_result(subject: str, data: Data, kind: str) -> str:
    status = kind.removeprefix("GOAL_RESULT_").lower()
    text = f"{subject}, goal {data['goal_id']}"
    reason = data.get("reason")
    return _why(text, reason if reason and str(reason).lower() != status else "")


# --- monitoring -------------------------------------------------------------------------


def _rule(subject: str, data: Data, kind: str) -> str:
    if kind == "RULE_FAILED":
        return _why(subject, data.get("error"))
    faulty = list(data.get("faulty") or [])
    text = f"{subject}: {data['action']}"
    return text + (f" (possibly faulty: {listed(faulty)})" if faulty else "")


Text = Callable[[str, Data, str], str]

_TEXTS: Mapping[str, Text] = {
    "EXECUTIVE_STARTED": _executive, "EXECUTIVE_STOPPED": _executive,
    "WORLD_SEEDED": _world, "STATE_SET": _fact, "STATE_UNSET": _fact,
    "STATE_TIMED": _timed,
    "OBJECT_ADDED": _object, "OBJECT_REMOVED": _object, "PARAMETER": _parameter,
    "EXONERATION": _exoneration,
    "GOAL_ADDED": _goal_added, "PLANNING": _planning, "PLAN_STORED": _plan_stored,
    "PLAN_START": _plan_start, "REPLAN": _replan, "DISPATCH": _step, "START": _step,
    "END": _step, "FAIL": _step, "CANCEL": _step, "ADOPT": _step, "RECOVERED": _recovered,
    "INTEGRITY_GOAL": _integrity, "INTEGRITY_REFUSED": _integrity,
    "CONFIGURATION": _configuration, "REPAIR": _repair, "FAULT": _fault,
    "PERMANENT_FAULT": _permanent_fault, "COMPONENT_RESET": _reset,
    "HOST_JOINED": _host, "HOST_LOST": _host, "HOST_STOPPED": _host,
    "ROBOT_JOINED": _robot, "ROBOT_LOST": _robot,
    "RULE_FIRED": _rule, "RULE_FAILED": _rule,
}  # fmt: skip
"""The readable form of each named kind."""

_FAMILIES: tuple[tuple[str, Text], ...] = (
    ("GOAL_RESULT_", _goal_result),
    ("GOAL_", _goal_state),
    ("TASK_", _task),
    ("COMPONENT_", _component),
)
"""The readable form of each family of composed kinds, the longest prefix first."""
