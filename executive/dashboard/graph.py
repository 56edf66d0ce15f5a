"""The component graph of a robot: its layout, the state drawn over it, and its SVG
picture.

Nodes are the components (functionalities and behaviors), the capabilities they provide
and require, and the topics they publish and subscribe. The layout is layered from left
to right along the capabilities (``requires`` is acyclic): a component stands one layer
after the providers of what it requires; a capability stands just after its providers,
a topic just after its publishers. Within a layer the nodes are ordered to cross few
edges. :class:`GraphState` is what a running robot adds: each component's state, the
current diagnoses, fault counters, the failed topics and the active configurations.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from executive.dashboard import svg
from knowledge.description import FunctionalitySpec, RobotDescription

COMPONENT, BEHAVIOR, TOPIC, CAPABILITY = "functionality", "behavior", "topic", "capability"
COMPONENT_STATES = ("running", "starting", "paused", "stopped", "faulty", "permanently faulty")
GAP_X, GAP_Y, MARGIN, TOP = 48.0, 16.0, 24.0, 44.0
LEGEND = 40.0


@dataclass(frozen=True)
class Node:
    """A placed node; ``key`` is unique (``kind:name``), ``name`` is what it shows."""

    key: str
    name: str
    kind: str
    x: float
    y: float
    width: float
    height: float

    @property
    def is_component(self) -> bool:
        return self.kind in (COMPONENT, BEHAVIOR)


@dataclass(frozen=True)
class Edge:
    """``publishes`` (component → topic), ``subscribes`` (topic → component),
    ``provides`` (functionality → capability) or ``requires`` (capability → component)."""

    source: str
    target: str
    kind: str


@dataclass(frozen=True)
class Layout:
    robot: str
    nodes: Mapping[str, Node]
    edges: tuple[Edge, ...]
    width: float
    height: float
    info: Mapping[str, tuple[str, ...]] = field(default_factory=dict)  # tooltip lines by key


@dataclass(frozen=True)
class GraphState:
    """What a running robot draws over its graph.

    ``states`` maps a component to one of :data:`COMPONENT_STATES`; ``faults`` to its
    fault count and ``max_faults`` (0: none, a behavior's); ``tasks`` to the active tasks it serves; ``used``
    holds the ``(capability, provider)`` pairs of the active configurations.
    """

    states: Mapping[str, str] = field(default_factory=dict)
    diagnosed: frozenset[str] = frozenset()
    faults: Mapping[str, tuple[int, int]] = field(default_factory=dict)
    failed_topics: frozenset[str] = frozenset()
    tasks: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    used: frozenset[tuple[str, str]] = frozenset()


def component_key(name: str) -> str:
    return f"component:{name}"


def _layers(robot: RobotDescription) -> dict[str, int]:
    """Each component's layer: one after the providers of the capabilities it requires."""
    found: dict[str, int] = {}

    def layer(name: str, seen: frozenset[str]) -> int:
        if name in found:
            return found[name]
        if name in seen:  # a requires cycle (validation reports it); draw it anyway
            return 0
        spec = robot.components[name]
        below = [
            layer(p.name, seen | {name}) + 1 for c in spec.requires for p in robot.providers(c)
        ]
        found[name] = max(below, default=0)
        return found[name]

    for name in robot.components:
        layer(name, frozenset())
    return found


def layout(robot: RobotDescription) -> Layout:
    """Place the robot's graph (see the module docstring)."""
    layers = _layers(robot)
    column: dict[str, int] = {}
    edges: list[Edge] = []
    info: dict[str, tuple[str, ...]] = {}
    names: dict[str, tuple[str, str]] = {}
    for name, spec in robot.components.items():
        key = component_key(name)
        kind = COMPONENT if isinstance(spec, FunctionalitySpec) else BEHAVIOR
        names[key] = (name, kind)
        column[key] = 3 * layers[name]
        lines = [f"{name} ({kind})"]
        if isinstance(spec, FunctionalitySpec) and spec.provides:
            lines.append("provides " + ", ".join(spec.provides))
        if spec.requires:
            lines.append("requires " + ", ".join(spec.requires))
        if spec.publishes:
            lines.append("publishes " + ", ".join(spec.publishes))
        if spec.subscribes:
            lines.append("subscribes " + ", ".join(spec.subscribes))
        info[key] = tuple(lines)
    capabilities = sorted(
        {c for s in robot.components.values() for c in s.requires}
        | {c for f in robot.functionalities.values() for c in f.provides}
    )
    for capability in capabilities:
        key = f"capability:{capability}"
        names[key] = (capability, CAPABILITY)
        providers = [f.name for f in robot.providers(capability)]
        users = [n for n, s in robot.components.items() if capability in s.requires]
        if providers:
            column[key] = 3 * max(layers[p] for p in providers) + 1
        else:
            column[key] = max(0, 3 * min(layers[u] for u in users) - 2)
        edges += [Edge(component_key(p), key, "provides") for p in providers]
        edges += [Edge(key, component_key(u), "requires") for u in users]
        info[key] = (
            f"capability {capability}",
            "provided by " + (", ".join(providers) or "nobody"),
            "required by " + (", ".join(users) or "nobody"),
        )
    for topic in robot.topics:
        key = f"topic:{topic}"
        names[key] = (topic, TOPIC)
        publishers = [n for n, s in robot.components.items() if topic in s.publishes]
        readers = [n for n, s in robot.components.items() if topic in s.subscribes]
        if publishers:
            column[key] = 3 * max(layers[p] for p in publishers) + 2
        else:
            column[key] = max(0, 3 * min(layers[r] for r in readers) - 1)
        edges += [Edge(component_key(p), key, "publishes") for p in publishers]
        edges += [Edge(key, component_key(r), "subscribes") for r in readers]
        info[key] = (
            f"topic {topic}",
            "published by " + (", ".join(publishers) or "nobody"),
            "read by " + (", ".join(readers) or "nobody"),
        )
    order = _order(column, edges, names)
    sizes = {key: _size(*names[key]) for key in names}
    nodes: dict[str, Node] = {}
    x = MARGIN
    heights = [
        sum(sizes[k][1] for k in keys) + GAP_Y * (len(keys) - 1) for keys in order
    ]  # fmt: skip
    tallest = max(heights, default=0.0)
    for keys, height in zip(order, heights, strict=True):
        width = max(sizes[k][0] for k in keys)
        y = TOP + (tallest - height) / 2
        for key in keys:
            w, h = sizes[key]
            name, kind = names[key]
            nodes[key] = Node(key, name, kind, x + (width - w) / 2, y, w, h)
            y += h + GAP_Y
        x += width + GAP_X
    width = max(x - GAP_X + MARGIN, 320.0)
    height = TOP + tallest + MARGIN + 48.0 + LEGEND  # room for edges that loop back below
    return Layout(robot.name, nodes, tuple(edges), width, height, info)


def _size(name: str, kind: str) -> tuple[float, float]:
    if kind in (COMPONENT, BEHAVIOR):
        return max(120.0, svg.text_width(name, 13) + 28.0), 44.0
    return max(64.0, svg.text_width(name, 11) + 22.0), 24.0


def _order(
    column: Mapping[str, int], edges: Iterable[Edge], names: Mapping[str, tuple[str, str]]
) -> list[list[str]]:
    """The nodes of each used column, ordered by a few barycenter sweeps."""
    neighbours: dict[str, list[str]] = {key: [] for key in column}
    for edge in edges:
        neighbours[edge.source].append(edge.target)
        neighbours[edge.target].append(edge.source)
    used = sorted(set(column.values()))
    rank = {c: i for i, c in enumerate(used)}
    kinds = {COMPONENT: 0, BEHAVIOR: 1, CAPABILITY: 2, TOPIC: 3}
    columns: list[list[str]] = [[] for _ in used]
    for key in sorted(column, key=lambda k: (kinds[names[k][1]], names[k][0])):
        columns[rank[column[key]]].append(key)
    position = {key: float(i) for keys in columns for i, key in enumerate(keys)}
    for sweep in range(6):
        sequence = columns if sweep % 2 == 0 else list(reversed(columns))
        for keys in sequence:
            centre = {}
            for key in keys:
                around = [position[n] for n in neighbours[key]]
                centre[key] = sum(around) / len(around) if around else position[key]
            keys.sort(key=lambda k: (centre[k], position[k]))
            for i, key in enumerate(keys):
                position[key] = float(i)
    return columns


# --- the picture ------------------------------------------------------------------------


def _ink(fill: str) -> str:
    """Dark or light text, whichever reads on ``fill``."""
    r, g, b = (int(fill[i : i + 2], 16) for i in (1, 3, 5))
    return svg.INK if 0.299 * r + 0.587 * g + 0.114 * b > 150 else "#ffffff"


Point = tuple[float, float]
Curve = tuple[Point, Point, Point, Point]  # a cubic Bézier: start, two controls, end
CLEARANCE = 6.0  # px an edge keeps from a box it passes


def edge_curves(a: Node, b: Node, bottom: float, nodes: Iterable[Node] = ()) -> list[Curve]:
    """The curves of the edge from ``a`` to ``b``: straight on if no box of ``nodes`` is in
    the way, else over or under the boxes between them (whichever is nearer); backwards,
    out to the right, under the graph and up in the gap before the target's column."""
    placed = list(nodes)
    x2, y2 = b.x, b.y + b.height / 2
    if b.x > a.x + a.width / 2:
        x1, y1 = a.x + a.width, a.y + a.height / 2
        bend = max(24.0, (x2 - x1) / 2)
        direct = [((x1, y1), (x1 + bend, y1), (x2 - bend, y2), (x2, y2))]
        between = [n for n in placed if n.x >= x1 - 1 and n.x + n.width <= x2 + 1]
        between = [n for n in between if n not in (a, b)]
        if not any(_hits(direct, n) for n in placed if n not in (a, b)) or not between:
            return direct
        above = min(n.y for n in between) - CLEARANCE * 2
        below = max(n.y + n.height for n in between) + CLEARANCE * 2
        lane = above if abs(above - (y1 + y2) / 2) <= abs(below - (y1 + y2) / 2) else below
        left = min(n.x for n in between) - CLEARANCE
        right = max(n.x + n.width for n in between) + CLEARANCE
        return [
            ((x1, y1), ((x1 + left) / 2, y1), ((x1 + left) / 2, lane), (left, lane)),
            ((left, lane), (left, lane), (right, lane), (right, lane)),
            ((right, lane), ((right + x2) / 2, lane), ((right + x2) / 2, y2), (x2, y2)),
        ]
    # backwards: out of the source's right side into the gap after its column, down
    # below the graph, along it, and up in the gap before the target's column
    x1, y1 = a.x + a.width, a.y + a.height / 2
    column = [n for n in placed if n.x < x1 and n.x + n.width > a.x] or [a]
    out = max(n.x + n.width for n in column) + 16.0
    turn = x2 - 16.0
    return [
        ((x1, y1), (out, y1), (out, y1), (out, (y1 + bottom) / 2)),
        ((out, (y1 + bottom) / 2), (out, bottom), (out, bottom), ((out + turn) / 2, bottom)),
        (((out + turn) / 2, bottom), (turn, bottom), (turn, bottom), (turn, (y2 + bottom) / 2)),
        ((turn, (y2 + bottom) / 2), (turn, y2), (turn, y2), (x2, y2)),
    ]


def sampled(curves: Sequence[Curve], steps: int = 24) -> list[Point]:
    """Points along curves (for checking what they pass through)."""
    points = []
    for p0, p1, p2, p3 in curves:
        for i in range(steps + 1):
            t = i / steps
            u = 1 - t
            points.append(
                (
                    u**3 * p0[0] + 3 * u * u * t * p1[0] + 3 * u * t * t * p2[0] + t**3 * p3[0],
                    u**3 * p0[1] + 3 * u * u * t * p1[1] + 3 * u * t * t * p2[1] + t**3 * p3[1],
                )
            )
    return points


def _hits(curves: Sequence[Curve], node: Node) -> bool:
    return any(
        node.x - CLEARANCE < x < node.x + node.width + CLEARANCE
        and node.y - CLEARANCE < y < node.y + node.height + CLEARANCE
        for x, y in sampled(curves)
    )


def _edge_path(curves: Sequence[Curve]) -> str:
    start = curves[0][0]
    parts = [f"M{start[0]:.1f},{start[1]:.1f}"]
    for _, c1, c2, end in curves:
        parts.append(f"C{c1[0]:.1f},{c1[1]:.1f} {c2[0]:.1f},{c2[1]:.1f} {end[0]:.1f},{end[1]:.1f}")
    return " ".join(parts)


def render(graph: Layout, state: GraphState | None = None, caption: str = "") -> str:
    """The graph as an SVG document; without ``state`` every component is drawn plain."""
    caption = caption or f"robot {graph.robot}: components, capabilities and topics"
    body = [
        svg.element(
            "defs",
            [
                svg.element(
                    "marker",
                    svg.element("path", d="M0,0 L8,4 L0,8 z", fill=colour),
                    id=f"dura-arrow-{name}", viewBox="0 0 8 8", refX=8, refY=4,
                    markerWidth=8, markerHeight=8, orient="auto-start-reverse",
                    markerUnits="userSpaceOnUse",
                )
                for name, colour in (("flow", "#8a939e"), ("alert", svg.ALERT),
                                     ("capability", svg.CAPABILITY))
            ],
        ),
        svg.label(MARGIN, 24, caption, font_size=14, font_weight="600"),
    ]  # fmt: skip
    bottom = graph.height - LEGEND - 12.0
    for edge in graph.edges:
        a, b = graph.nodes[edge.source], graph.nodes[edge.target]
        attrs: dict[str, object] = {"fill": "none", "class_": f"edge {edge.kind}"}
        if edge.kind in ("provides", "requires"):
            used = state is not None and (
                (b.name, a.name) in state.used
                if edge.kind == "provides"
                else bool(state.tasks.get(b.name)) and any(c == a.name for c, _ in state.used)
            )
            attrs.update(stroke=svg.CAPABILITY, stroke_dasharray=None if used else "5 4",
                         stroke_width=3 if used else 1.2, marker_end="url(#dura-arrow-capability)",
                         data_used="yes" if used else None)  # fmt: skip
        else:
            topic = a.name if a.kind == TOPIC else b.name
            failed = state is not None and topic in state.failed_topics
            attrs.update(stroke=svg.ALERT if failed else "#8a939e", stroke_width=2 if failed else 1.2,
                         marker_end=f"url(#dura-arrow-{'alert' if failed else 'flow'})")  # fmt: skip
        curves = edge_curves(a, b, bottom, graph.nodes.values())
        body.append(svg.element("path", d=_edge_path(curves), **attrs))
    for node in graph.nodes.values():
        body.append(_node(node, graph.info.get(node.key, ()), state))
    x = MARGIN
    legend_y = graph.height - 22.0
    states = COMPONENT_STATES if state is not None else ()
    for name in states:
        body.append(svg.element("rect", x=x, y=legend_y - 9, width=10, height=10, rx=2,
                                fill=svg.colour(name)))  # fmt: skip
        body.append(svg.label(x + 14, legend_y, name, font_size=10, fill=svg.MUTED))
        x += 26 + svg.text_width(name, 10)
    for name, colour in (("diagnosed", svg.ALERT), ("capability", svg.CAPABILITY)):
        body.append(svg.element("rect", x=x, y=legend_y - 9, width=10, height=10, rx=2,
                                fill="none", stroke=colour, stroke_width=2,
                                stroke_dasharray="3 2" if name == "diagnosed" else None))  # fmt: skip
        body.append(svg.label(x + 14, legend_y, name, font_size=10, fill=svg.MUTED))
        x += 26 + svg.text_width(name, 10)
    body.append(svg.label(x, legend_y, "topic", font_size=10, fill=svg.MUTED))
    return svg.document(graph.width, graph.height, body, name="graph", caption=caption)


def _node(node: Node, info: tuple[str, ...], state: GraphState | None) -> str:
    lines = list(info)
    x, y, w, h = node.x, node.y, node.width, node.height
    attrs: dict[str, object] = {"class_": f"node {node.kind}", "data_node": node.name,
                                "data_kind": node.kind}  # fmt: skip
    parts: list[str] = []
    count: tuple[int, int] | None = None
    if node.kind == TOPIC:
        failed = state is not None and node.name in state.failed_topics
        if failed:
            lines.append("an observation of it failed")
            attrs["data_state"] = "failed"
        parts.append(svg.element("rect", x=x, y=y, width=w, height=h, rx=h / 2,
                                 fill="#fdeceb" if failed else "#ffffff",
                                 stroke=svg.ALERT if failed else "#8a939e",
                                 stroke_width=2 if failed else 1))  # fmt: skip
        parts.append(svg.label(x + w / 2, y + 16, node.name, font_size=11, text_anchor="middle",
                               fill=svg.ALERT if failed else svg.INK))  # fmt: skip
    elif node.kind == CAPABILITY:
        parts.append(svg.element("rect", x=x, y=y, width=w, height=h, rx=4, fill="#f3eefa",
                                 stroke=svg.CAPABILITY))  # fmt: skip
        parts.append(svg.label(x + w / 2, y + 16, node.name, font_size=11, text_anchor="middle",
                               fill=svg.CAPABILITY, font_style="italic"))  # fmt: skip
    else:
        status = "" if state is None else state.states.get(node.name, "stopped")
        fill = svg.colour(status) if status else "#eef1f5"
        second = node.kind
        if state is not None:
            attrs["data_state"] = status
            second = status
            count = state.faults.get(node.name)
            tasks = state.tasks.get(node.name, ())
            lines += [f"serves {t}" for t in tasks]
            lines.insert(1, f"state {status}")
        parts.append(svg.element("rect", x=x, y=y, width=w, height=h,
                                 rx=16 if node.kind == BEHAVIOR else 5, fill=fill,
                                 stroke="#56606c" if state is None or status != "stopped" else "#9aa3ad",
                                 stroke_width=2.5 if state and state.tasks.get(node.name) else 1))  # fmt: skip
        ink = _ink(fill)
        parts.append(svg.label(x + w / 2, y + 19, node.name, font_size=13, font_weight="600",
                               text_anchor="middle", fill=ink))  # fmt: skip
        parts.append(svg.label(x + w / 2, y + 35, second, font_size=10, text_anchor="middle",
                               fill=ink, class_="state"))  # fmt: skip
        if state is not None and status == "permanently faulty":
            parts.append(svg.element("path", d=f"M{x + 4},{y + 4} L{x + w - 4},{y + h - 4} "
                                     f"M{x + w - 4},{y + 4} L{x + 4},{y + h - 4}",
                                     stroke="#ffffff", stroke_width=1.5, opacity=0.5))  # fmt: skip
        if state is not None and count is not None and count[0]:
            lines.append(f"faults {count[0]} of {count[1]}" if count[1] else f"faults {count[0]}")
            attrs["data_faults"] = count[0]
            badge = f"{count[0]}/{count[1]}" if count[1] else str(count[0])
            bw = svg.text_width(badge, 10) + 10
            parts.append(
                svg.element("g", [
                    svg.element("rect", x=x + w - bw + 6, y=y - 8, width=bw, height=16, rx=8,
                                fill=svg.ALERT, stroke="#ffffff"),
                    svg.label(x + w - bw / 2 + 6, y + 4, badge, font_size=10, fill="#ffffff",
                              text_anchor="middle", font_weight="600"),
                ], class_="faults")
            )  # fmt: skip
        if state is not None and node.name in state.diagnosed:
            attrs["data_diagnosed"] = "yes"
            lines.append("named by the current diagnosis")
            parts.append(svg.element("rect", x=x - 5, y=y - 5, width=w + 10, height=h + 10,
                                     rx=9, fill="none", stroke=svg.ALERT, stroke_width=2.5,
                                     stroke_dasharray="6 3", class_="diagnosed"))  # fmt: skip
    return svg.element("g", [svg.title("\n".join(lines)), *parts], **attrs)
