"""Hover, go to definition and find references over a project's names."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from executive.lsp.names import Occurrence, pddl_names, yaml_names
from executive.lsp.pddl_syntax import Form, Token, parse
from knowledge.description import GoalArg, RobotDescription
from knowledge.robot import read_robot
from knowledge.sources import unsaved

_FLUENTS = frozenset({"fluent", "predicate", "function"})


def same(a: Occurrence, b: Occurrence) -> bool:
    """Whether two occurrences name one thing (a fluent's use, a predicate or function)."""
    kinds = a.kind == b.kind or (a.kind in _FLUENTS and b.kind in _FLUENTS)
    return kinds and a.name == b.name


@dataclass(frozen=True)
class Names:
    """The occurrences of the names of a project's files, and their texts."""

    texts: Mapping[Path, str]
    occurrences: tuple[Occurrence, ...]
    robot: Path | None = None

    @classmethod
    def of(cls, texts: Mapping[Path, str], robot: Path | None) -> Names:
        found: list[Occurrence] = []
        for path, text in texts.items():
            if path.suffix.lower() == ".pddl":
                found += pddl_names(path, text)
            elif path.suffix.lower() in (".yaml", ".yml"):
                found += yaml_names(path, text)
        return cls(texts, tuple(found), robot)

    def at(self, path: Path, offset: int) -> Occurrence | None:
        """The name written at (or just before) ``offset`` of a file."""
        return next(
            (o for o in self.occurrences if o.path == path and o.start <= offset <= o.end), None
        )

    def definitions(self, name: Occurrence) -> list[Occurrence]:
        return [o for o in self.occurrences if o.declared and same(o, name)]

    def references(self, name: Occurrence, declarations: bool = True) -> list[Occurrence]:
        return [o for o in self.occurrences if same(o, name) and (declarations or not o.declared)]

    def declared(self, kind: str) -> list[Occurrence]:
        """The declarations of one kind, each name once."""
        seen: dict[str, Occurrence] = {}
        for o in self.occurrences:
            if o.declared and (o.kind == kind or (kind == "fluent" and o.kind in _FLUENTS)):
                seen.setdefault(o.name, o)
        return list(seen.values())

    def description(self) -> RobotDescription | None:
        if self.robot is None or self.robot not in self.texts:
            return None
        with unsaved(self.texts):
            return read_robot(self.robot, self.texts[self.robot])[0]

    def hover(self, name: Occurrence) -> str:
        """What a name is, as Markdown: its declaration and what dura knows of it."""
        if name.kind == "action":
            return self._action(name)
        if name.kind in ("capability", "component", "topic"):
            return self._robot_part(name)
        lines = [
            f"**{'predicate or function' if name.kind == 'fluent' else name.kind}** `{name.name}`"
        ]
        for d in self.definitions(name):
            lines.append(
                f"```pddl\n{d.detail or d.name}\n```\n{d.kind}, declared in {_where(self, d)}"
            )
        if name.kind == "type":
            objects = [
                o.detail for o in self.declared("object") if o.detail.endswith(f" - {name.name}")
            ]
            if objects:
                lines.append("objects: " + ", ".join(o.split(" - ")[0] for o in objects))
        return "\n\n".join(lines)

    def _action(self, name: Occurrence) -> str:
        lines = [f"**action** `{name.name}`"]
        for d in self.definitions(name):
            form = _action_form(self.texts[d.path], d.start)
            if form is None:
                continue
            text = self.texts[d.path]
            lines.append(f"{d.detail} in {_where(self, d)}")
            for key in (":parameters", ":duration", ":condition", ":precondition", ":effect"):
                part = form.after(key)
                if part is not None:
                    lines.append(f"{key[1:]}: `{_one_line(text, part)}`")
        robot = self.description()
        if robot is not None:
            task = next((t for k, t in robot.tasks.items() if k.lower() == name.name), None)
            if task is None:
                lines.append(f"no task in {robot.path.name}: applied without running a behavior")
            else:
                goal = ", ".join(f"{k}={_goal_arg(v)}" for k, v in task.goal.items())
                lines.append(
                    f"task: behavior `{task.behavior}`" + (f" with goal {goal}" if goal else "")
                )
                behavior = robot.behaviors.get(task.behavior)
                if behavior is not None:
                    for capability in behavior.requires:
                        providers = (
                            ", ".join(p.name for p in robot.providers(capability)) or "nobody"
                        )
                        lines.append(f"- requires `{capability}`: provided by {providers}")
        return "\n\n".join(lines)

    def _robot_part(self, name: Occurrence) -> str:
        robot = self.description()
        lines = [f"**{name.kind}** `{name.name}`"]
        if robot is None:
            return lines[0]
        components = list(robot.components.values())
        if name.kind == "capability":
            providers = [c.name for c in robot.providers(name.name)]
            requirers = [c.name for c in components if name.name in c.requires]
            lines.append(f"provided by: {', '.join(providers) or 'nobody'}")
            lines.append(f"required by: {', '.join(requirers) or 'nobody'}")
        elif name.kind == "topic":
            lines.append(
                f"published by: {', '.join(c.name for c in components if name.name in c.publishes) or 'nobody'}"
            )
            lines.append(
                f"subscribed by: {', '.join(c.name for c in components if name.name in c.subscribes) or 'nobody'}"
            )
        else:
            c = robot.components.get(name.name)
            if c is not None:
                lines[0] = f"**{c.kind.value}** `{c.name}`"
                for key in ("provides", "requires", "publishes", "subscribes"):
                    values = getattr(c, key, ())
                    if values:
                        lines.append(f"{key}: {', '.join(values)}")
                tasks = [t.action for t in robot.tasks.values() if t.behavior == c.name]
                if tasks:
                    lines.append(f"carries out: {', '.join(tasks)}")
        return "\n\n".join(lines)


def _goal_arg(arg: GoalArg) -> str:
    if arg.parameter is None:
        return repr(arg.constant)
    return f"?{arg.parameter}" + (f".{arg.property}" if arg.property else "")


def _where(names: Names, o: Occurrence) -> str:
    line = names.texts[o.path].count("\n", 0, o.start) + 1
    return f"{o.path.name}:{line}"


def _action_form(text: str, offset: int) -> Form | None:
    for define in parse(text).forms():
        for part in define.forms():
            if part.start <= offset < part.end:
                return part
    return None


def _one_line(text: str, part: Token | Form) -> str:
    if isinstance(part, Token):
        return part.text
    lines = [line.split(";", 1)[0] for line in text[part.start : part.end].splitlines()]
    return " ".join(" ".join(lines).replace("( ", "(").split())
