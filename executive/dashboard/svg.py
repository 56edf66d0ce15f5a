"""A small SVG writer: escaped text, elements from keyword attributes, one palette.

The pictures carry their colours as attributes, so a file written by ``--svg`` looks
the same in any viewer as on the page; ``class`` and ``data-*`` attributes name what
each element shows, for the page's script, its style sheet and the tests.
"""

from __future__ import annotations

from collections.abc import Iterable
from xml.sax.saxutils import escape, quoteattr

# Colours by state, shared by the Gantt chart, the graph and the page's style sheet.
PALETTE: dict[str, str] = {
    "pending": "#d9dee5",
    "planned": "#d9dee5",
    "dispatched": "#f2c14e",
    "starting": "#f2c14e",
    "stopping": "#f2c14e",
    "running": "#3fa34d",
    "paused": "#4a90d9",
    "done": "#2b6f36",
    "ended": "#2b6f36",
    "stopped": "#b8bfc9",
    "failed": "#d64541",
    "faulty": "#d64541",
    "cancelled": "#8a8f98",
    "permanently faulty": "#5c1a1a",
    "unknown": "#eef1f5",
}
INK = "#1f2630"
MUTED = "#6b7480"
GRID = "#e3e7ec"
ALERT = "#d64541"
CAPABILITY = "#7b4fb5"
FONT = "system-ui, -apple-system, 'Segoe UI', Roboto, sans-serif"
CHAR = 6.6  # the width of a character of 12 px text, roughly (layouts only need a guess)


def colour(state: str) -> str:
    return PALETTE.get(state, PALETTE["unknown"])


def text_width(text: str, size: float = 12.0) -> float:
    return len(text) * CHAR * size / 12.0


def _name(key: str) -> str:
    """A keyword argument as an attribute name: ``data_state`` → ``data-state``,
    ``class_`` → ``class``."""
    return key.rstrip("_").replace("_", "-")


def attributes(attrs: dict[str, object]) -> str:
    parts = []
    for key, value in attrs.items():
        if value is None or value is False:
            continue
        shown = f"{value:.1f}".rstrip("0").rstrip(".") if isinstance(value, float) else str(value)
        parts.append(f" {_name(key)}={quoteattr(shown)}")
    return "".join(parts)


def element(tag: str, content: str | Iterable[str] = "", /, **attrs: object) -> str:
    """An element; ``content`` is markup (escape text with :func:`text`)."""
    inner = content if isinstance(content, str) else "".join(content)
    if not inner:
        return f"<{tag}{attributes(attrs)}/>"
    return f"<{tag}{attributes(attrs)}>{inner}</{tag}>"


def text(value: object) -> str:
    """Text content, escaped."""
    return escape(str(value))


def title(value: str) -> str:
    """A tooltip (the ``<title>`` child a browser shows on hover)."""
    return element("title", text(value))


def label(x: float, y: float, value: str, /, **attrs: object) -> str:
    """A line of text at ``x, y`` (the baseline)."""
    attrs.setdefault("font_size", 12)
    attrs.setdefault("fill", INK)
    return element("text", text(value), x=x, y=y, **attrs)


def document(width: float, height: float, body: Iterable[str], *, name: str, caption: str) -> str:
    """A standalone SVG document that scales to its container (``viewBox``)."""
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        + element(
            "svg",
            [element("title", text(caption)), element("rect", x=0, y=0, width=width,
                                                       height=height, fill="#ffffff"), *body],
            xmlns="http://www.w3.org/2000/svg",
            viewBox=f"0 0 {width:.0f} {height:.0f}",
            width=f"{width:.0f}",
            height=f"{height:.0f}",
            font_family=FONT,
            class_=f"dura-{name}",
            role="img",
        )
        + "\n"
    )  # fmt: skip


def inline(svg: str) -> str:
    """An SVG document without its XML declaration, to put into a page."""
    return svg.split("?>", 1)[1].lstrip() if svg.startswith("<?xml") else svg
