"""A plan as a Gantt chart: the data (one row per step, marks on the time axis) and its
SVG picture.

Two sources give the data: a plan found offline (:func:`offline_gantt`, times from the
plan's start) and the running robot's plan with its execution (:func:`live_gantt`:
planned and actual times from the event log, step states, each step's task and
configuration, and the plans and replans before it on the same time axis, 0 being the
current plan's start). :func:`render` draws either. A fleet's plan is drawn by robot:
a row per robot, each of its steps a bar in that row.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from executive.bus.wording import goals_named
from executive.dashboard import svg

if TYPE_CHECKING:
    from executive.bus.reports import ExecutionStatus, ExecutorTask
    from executive.planning.partial_order import PartialOrderPlan
    from knowledge.records import Event, Plan

HISTORY = 60.0  # seconds before the current plan's start whose plans and replans are marked
STATES = ("pending", "dispatched", "running", "paused", "done", "failed", "cancelled")
_ENDS = {"END": "done", "FAIL": "failed", "CANCEL": "cancelled"}


@dataclass(frozen=True)
class GanttStep:
    """One row: a step's planned place, its state and, once dispatched, when it ran
    (``ran``: from dispatch to its end, ``None`` for an end not reached yet)."""

    index: int
    label: str
    start: float
    duration: float | None
    state: str = "pending"
    ran: tuple[float, float | None] | None = None
    details: tuple[str, ...] = ()
    robot: str = ""  # a fleet's plan: the robot that carries it out

    @property
    def end(self) -> float:
        return self.start + (self.duration or 0.0)


@dataclass(frozen=True)
class Mark:
    """A moment on the time axis: a plan started (``plan``) or asked for a new one
    (``replan``)."""

    at: float
    kind: str
    text: str


@dataclass(frozen=True)
class Gantt:
    """What the chart shows; times are seconds on one axis."""

    title: str
    steps: tuple[GanttStep, ...]
    marks: tuple[Mark, ...] = ()
    now: float | None = None


def offline_gantt(plan: PartialOrderPlan, title: str) -> Gantt:
    """The chart of a plan found offline (every step planned, nothing ran)."""
    steps = []
    for step in plan.steps:
        after = ", ".join(
            f"{p.step}{'' if p.at.value == 'end' else ' (its start)'}" for p in step.after
        )
        details = [step.label, _planned(step.start, step.duration)]
        if after:
            details.append(f"after step {after}")
        steps.append(
            GanttStep(step.index, step.label, step.start, step.duration, "pending",
                      details=tuple(details))
        )  # fmt: skip
    return Gantt(title, tuple(steps))


def live_gantt(
    plan: Plan,
    execution: ExecutionStatus,
    events: Sequence[Event],
    tasks: Sequence[ExecutorTask],
    now: float,
    *,
    robots: Sequence[str] | None = None,
) -> Gantt:
    """The chart of the running robot's plan (a ``plan/show`` reply's ``plan`` and
    ``execution``), its events (``events``, oldest first) and tasks (``task/list``); for a
    fleet's plan, ``robots``: the reply's robot of each step (the chart is by robot)."""
    plan_id = plan.id
    origin = plan.created or now
    for event in events:
        if event.kind == "PLAN_START" and event.subject == f"plan {plan_id}":
            origin = event.stamp
    executing = execution.plan == plan_id
    states = {s.index: s.state for s in execution.steps} if executing else {}
    ran: dict[int, tuple[float, float | None]] = {}
    unended: dict[str, float] = {}  # a step a new plan adopts ran since an older plan's dispatch
    for event in events:
        kind, at, step = event.kind, event.stamp - origin, event.data.get("step")
        if kind == "DISPATCH":
            unended[event.subject] = at
        elif kind in _ENDS:
            unended.pop(event.subject, None)
        if event.data.get("plan") != plan_id or not isinstance(step, int):
            continue
        if kind == "DISPATCH":
            ran[step] = (at, None)
        elif kind in _ENDS and step in ran:
            ran[step] = (ran[step][0], at)
    # the newest task of a step (a restarted step has several)
    by_name = {t.name: t for t in sorted(tasks, key=lambda t: _number(t.id))}
    steps = []
    performers = list(robots or [])
    for position, planned in enumerate(plan.steps):
        label = f"{planned.action}({', '.join(planned.args)})"
        robot = performers[position] if position < len(performers) else ""
        state = _state(states.get(planned.index), plan.state.value)
        span = ran.get(planned.index)
        if span is None and state in ("dispatched", "running", "paused") and label in unended:
            span = (unended[label], None)
        details = [label, f"state {state}", _planned(planned.start, planned.duration)]
        task = by_name.get(label)
        if task is not None and span is not None:
            details.append(f"task {task.id}: {task.behavior} {task.state}")
            if task.providers:
                uses = ", ".join(f"{c} → {p}" for c, p in sorted(task.providers.items()))
                details.append(f"configuration: {uses}")
            if task.reason:
                details.append(f"reason: {task.reason}")
        if robot:
            details.insert(1, f"robot {robot}")
        steps.append(
            GanttStep(planned.index, label, planned.start, planned.duration, state, span,
                      tuple(details), robot)
        )  # fmt: skip
    if any(s.robot for s in steps):  # by robot: each robot's steps together
        steps.sort(key=lambda s: (s.robot or "~", s.start, s.index))
    marks = []
    for event in events:
        kind, at = event.kind, event.stamp - origin
        if at < -HISTORY or kind not in ("PLAN_START", "REPLAN"):
            continue
        if kind == "PLAN_START":
            marks.append(Mark(at, "plan", event.subject or "plan"))
        else:
            reason = event.data.get("reason", "")
            marks.append(Mark(at, "replan", f"replan: {reason}" if reason else "replan"))
    title = (
        f"plan {plan_id}: {plan.state.value}, by {plan.engine}, for {goals_named(plan.goal_ids)}"
    )
    # a plan that has ended is drawn on its own span, not on one that grows with the clock
    return Gantt(title, tuple(steps), tuple(marks), now - origin if executing else None)


def _number(value: str) -> float:
    try:
        return float(value)
    except ValueError:
        return math.inf


def _state(step_state: str | None, plan_state: str) -> str:
    if step_state is None:
        return "done" if plan_state == "succeeded" else "pending"
    return "done" if step_state == "ended" else step_state


def _planned(start: float, duration: float | None) -> str:
    length = "unknown duration" if duration is None else f"{duration:g} s"
    return f"planned at {start:g} s for {length}"


# --- the picture ------------------------------------------------------------------------

WIDTH = 960.0
ROW = 26.0
TOP = 58.0  # title and marks
BOTTOM = 56.0  # axis labels and legend


def ticks(low: float, high: float, count: int = 8) -> list[float]:
    """Round numbers from ``low`` to ``high``, about ``count`` of them."""
    span = max(high - low, 1e-9)
    raw = span / count
    magnitude = 10 ** math.floor(math.log10(raw))
    step = next(m * magnitude for m in (1, 2, 5, 10) if m * magnitude >= raw)
    first = math.ceil(low / step) * step
    return [round(first + i * step, 9) for i in range(int((high - first) / step + 1e-9) + 1)]


def rows(gantt: Gantt) -> list[tuple[str, tuple[GanttStep, ...]]]:
    """The chart's rows, each with its label: a row per step, or for a fleet's plan a row
    per robot with its steps (those no robot carries out in a row ``-``)."""
    if not any(s.robot for s in gantt.steps):
        return [(f"{s.index}  {s.label}", (s,)) for s in gantt.steps]
    robots = sorted({s.robot for s in gantt.steps}, key=lambda r: (not r, r))
    return [(robot or "-", tuple(s for s in gantt.steps if s.robot == robot)) for robot in robots]


def render(gantt: Gantt, width: float = WIDTH, *, titled: bool = True) -> str:
    """The chart as an SVG document (``titled``: with its title drawn on it; a page
    that shows the title itself draws none); a fleet's plan by robot."""
    lines = rows(gantt)
    by_robot = any(s.robot for s in gantt.steps)
    left = max(140.0 if not by_robot else 60.0,
               max((svg.text_width(t) for t, _ in lines), default=0.0) + 24.0)  # fmt: skip
    right = width - (84.0 if not by_robot else 24.0)  # room for the last step's state
    low = min([0.0, *(m.at for m in gantt.marks), *(s.ran[0] for s in gantt.steps if s.ran)])
    ends = [s.end for s in gantt.steps]
    ends += [s.ran[1] for s in gantt.steps if s.ran and s.ran[1] is not None]
    if gantt.now is not None and any(s.ran for s in gantt.steps):
        ends.append(gantt.now)
    high = max([low + 1.0, *ends])
    scale = (right - left) / (high - low)

    def x(t: float) -> float:
        return left + (t - low) * scale

    height = TOP + ROW * max(1, len(lines)) + BOTTOM
    body: list[str] = []
    if titled:
        body.append(svg.label(12, 20, gantt.title, font_size=14, font_weight="600"))
    axis_y = TOP + ROW * max(1, len(lines))
    for row in range(1, len(lines), 2):  # stripes under the grid, the marks and the bars
        body.append(svg.element("rect", x=0, y=TOP + row * ROW, width=width, height=ROW,
                                fill="#f7f8fa"))  # fmt: skip
    for t in ticks(low, high):
        body.append(svg.element("line", x1=x(t), y1=TOP - 4, x2=x(t), y2=axis_y, stroke=svg.GRID))
        body.append(svg.label(x(t), axis_y + 16, f"{t:g} s", font_size=10, fill=svg.MUTED,
                              text_anchor="middle"))  # fmt: skip
    for i, mark in enumerate(gantt.marks):
        colour = svg.ALERT if mark.kind == "replan" else svg.CAPABILITY
        line = svg.element(
            "line", x1=x(mark.at), y1=TOP - 14 + (i % 2) * 8, x2=x(mark.at), y2=axis_y,
            stroke=colour, stroke_width=1.5, stroke_dasharray="4 3",
        )  # fmt: skip
        short = mark.text if len(mark.text) <= 28 else mark.text[:27] + "…"
        tag = svg.label(x(mark.at) + 3, TOP - 16 + (i % 2) * 8, short, font_size=10, fill=colour)
        body.append(
            svg.element("g", [svg.title(f"{mark.at:+.1f} s  {mark.text}"), line, tag],
                        class_="mark", data_kind=mark.kind)
        )  # fmt: skip
    for row, (text, steps) in enumerate(lines):
        y = TOP + row * ROW
        if by_robot:
            body.append(svg.label(12, y + 17, text, font_weight="600", class_="robot"))
        for step in steps:
            body.append(
                _step(step, y, x, scale=scale, now=gantt.now, text=None if by_robot else text)
            )
    if gantt.now is not None and any(s.ran for s in gantt.steps):
        body.append(
            svg.element("line", x1=x(gantt.now), y1=TOP - 4, x2=x(gantt.now), y2=axis_y,
                        stroke=svg.INK, stroke_width=1.5, class_="now")
        )  # fmt: skip
        body.append(svg.label(x(gantt.now), TOP - 6, "now", font_size=10, text_anchor="middle"))
    legend_x = 12.0
    for state in STATES:
        body.append(svg.element("rect", x=legend_x, y=height - 20, width=10, height=10, rx=2,
                                fill=svg.colour(state)))  # fmt: skip
        body.append(svg.label(legend_x + 14, height - 11, state, font_size=10, fill=svg.MUTED))
        legend_x += 24 + svg.text_width(state, 10)
    return svg.document(width, height, body, name="gantt", caption=gantt.title)


def _step(
    step: GanttStep,
    y: float,
    x: Callable[[float], float],
    *,
    scale: float,
    now: float | None,
    text: str | None,
) -> str:
    """One step at row ``y``: its planned bar and, once dispatched, when it ran; ``text``:
    the row's label and its state after the bar (a row of its own), else (a robot's
    row) its label in its bar, if it fits."""
    fill = svg.colour(step.state)
    parts = [svg.title("\n".join(step.details or (step.label,)))]
    if text is not None:
        parts.append(svg.label(12, y + 17, text))
    bar_width = max(3.0, (step.duration or 0.0) * scale)
    parts.append(
        svg.element("rect", x=x(step.start), y=y + 5, width=bar_width, height=ROW - 10, rx=3,
                    fill=fill, fill_opacity=0.45, stroke=fill, class_="planned")
    )  # fmt: skip
    last = x(step.start) + bar_width
    if step.ran is not None:
        begin, end = step.ran
        stop = end if end is not None else (now if now is not None else begin)
        last = max(last, x(stop))
        parts.append(
            svg.element("rect", x=x(begin), y=y + 9, width=max(3.0, (stop - begin) * scale),
                        height=ROW - 18, rx=2, fill=fill, class_="ran")
        )  # fmt: skip
    if text is not None:
        parts.append(svg.label(last + 6, y + 17, step.state, font_size=10, fill=svg.MUTED))
    elif svg.text_width(step.label, 10) + 6 <= bar_width:
        parts.append(svg.label(x(step.start) + 3, y + 17, step.label, font_size=10))
    return svg.element("g", parts, class_="step", data_step=step.index, data_state=step.state,
                       data_label=step.label, data_robot=step.robot or None)  # fmt: skip
