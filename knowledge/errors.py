"""The one exception hierarchy of dura.

Every error a user can cause (bad YAML, PDDL, ASP, CLI arguments or bus messages)
is a :class:`DuraError`. Its message is one line and names the file, the place and
the reason, e.g. ``robot.yaml:14: functionality 'lidar_filter' requires unknown
capability 'scna'``. Commands print it and exit non-zero; they never show a traceback.
"""

from __future__ import annotations


class DuraError(Exception):
    """Root of every error dura reports to a user.

    Its message is the one line that events, logs and ``--json`` carry; ``excerpt``
    (the source line with a caret under the place, for a terminal) may follow it.
    """

    def __init__(self, *args: object, excerpt: str = "") -> None:
        super().__init__(*args)
        self.excerpt = excerpt


class ConfigError(DuraError):
    """A configuration file (robot description, observers, rules) is invalid."""


class DomainError(DuraError):
    """A PDDL domain or problem cannot be read or does not fit the robot."""


class PlanningError(DuraError):
    """A planner could not be run (not: found no plan, which is a result)."""


class AspError(DuraError):
    """An ASP program is invalid or clingo failed."""


class KnowledgeError(DuraError):
    """The knowledge base refused a change or cannot be opened."""


class BusError(DuraError):
    """The message bus failed: no answer, no executive, a malformed message."""


class NoAnswer(BusError):
    """Nobody answered a request (no service serves its key, or none in time)."""


class BagError(DuraError):
    """A recording (a ROS 2 bag, an MCAP file) cannot be read, mapped or written."""


class ComponentError(DuraError):
    """A component process refused a command, or could not be started or reached."""


class ServiceError(DuraError):
    """A service of the executive was asked for a change its lifecycle does not allow."""


def located(path: object, line: int | None, message: str, column: int | None = None) -> str:
    """Format ``file:line:col: message`` (``file:line: message`` without a column,
    ``file: message`` without a line)."""
    if not line:
        return f"{path}: {message}"
    return f"{path}:{line}:{column}: {message}" if column else f"{path}:{line}: {message}"


def did_you_mean(word: str, choices: object) -> str:
    """`` (did you mean 'x'?)`` for the closest choice, or an empty string."""
    import difflib  # only once a word is wrong: commands stay quick to start

    names = [str(c) for c in choices]  # type: ignore[attr-defined]
    close = difflib.get_close_matches(word, names, n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""


QUOTED = 200  # characters of someone's input an error message quotes, at most


def excerpt(text: str, limit: int = QUOTED) -> str:
    """``text`` as an error message quotes it: at most ``limit`` characters, and how
    many more there were (a 900 KB goal gets a short refusal, not a 1.8 MB one)."""
    if len(text) <= limit:
        return text
    return f"{text[:limit]}... ({len(text) - limit} more characters)"
