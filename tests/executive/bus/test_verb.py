"""A verb is served and called through one declaration; a bad request never reaches the handler."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from executive.bus.schema import Payload, Text
from executive.bus.session import Bus
from executive.bus.verb import Verb
from knowledge.errors import BusError, DuraError


@dataclass(frozen=True)
class Greet(Payload):
    name: Text
    times: int = 1


@dataclass(frozen=True)
class Greeting(Payload):
    text: str


GREET = Verb("test/greet", Greet, Greeting, timeout=5.0)


def test_a_served_verb_answers_a_typed_call(endpoint: str) -> None:
    seen: list[Greet] = []

    def handler(request: Greet) -> Greeting:
        seen.append(request)
        if request.name == "nobody":
            raise DuraError("nobody is not here")
        return Greeting(" ".join([f"hello {request.name}"] * request.times))

    with Bus("robot", name="server", endpoint=endpoint, listen=True) as server:
        GREET.serve(server, handler)
        with Bus("robot", name="client", endpoint=endpoint) as client:
            assert GREET.call(client, Greet("ada", 2)) == Greeting("hello ada hello ada")
            with pytest.raises(BusError, match=r"^nobody is not here$"):
                GREET.call(client, Greet("nobody"))
            with pytest.raises(BusError, match=r"^test/greet: 'times' must be an integer"):
                client.request(GREET.key, {"name": "ada", "times": "2"})
    assert [r.name for r in seen] == ["ada", "nobody"]
