"""Component parameters at run time: set, get and list them (served by the task executor).

A parameter set here is stored in the knowledge base (it overrides the robot
description's ``params``) and reaches a running component at once: through its
``on_reconfigure`` hook, or, for a component without one, by a warm restart.
"""

from __future__ import annotations

from executive.bus.api.free_form import Params, Value
from executive.bus.keys import api
from executive.bus.schema import Payload, Text
from executive.bus.verb import Verb
from knowledge.record_class import record


@record
class ParameterChange(Payload):
    """A new value for one parameter of a component (what the ``parameter`` repair
    action sends)."""

    component: Text
    key: Text
    value: Value = None


@record
class ParameterKey(Payload):
    """One parameter of a component, by its key."""

    component: Text
    key: Text


@record
class ComponentParameters(Payload):
    """A component whose parameters to list."""

    component: Text


@record
class ParameterReply(Payload):
    """A parameter's value and where it comes from (``description`` or ``knowledge
    base``); after a change, how the component took it: ``reconfigured`` (running, by
    its hook), ``restarted`` (running, without a hook: the reason), or ``stored`` (for
    its next start)."""

    component: str
    key: str
    value: Value
    source: str
    applied: str = ""
    reason: str = ""


@record
class ParametersReply(Payload):
    """Every parameter of a component with its value and source."""

    component: str
    parameters: Params
    sources: dict[str, str]


PARAMETER_SET = Verb(api("parameter/set"), ParameterChange, ParameterReply, timeout=60.0)
PARAMETER_GET = Verb(api("parameter/get"), ParameterKey, ParameterReply)
PARAMETER_LIST = Verb(api("parameter/list"), ComponentParameters, ParametersReply)
