"""A second process on the bus: answers `echo`, publishes on `topic/chatter` when asked,
subscribes to a key when asked (`listen`) and tells how many messages it heard there.

Usage: python -m tests.executive.bus.bus_peer ROBOT ENDPOINT
"""

from __future__ import annotations

import sys
import threading
from typing import Any

from executive.bus.session import Bus
from knowledge.errors import DuraError


def main() -> None:
    robot, endpoint = sys.argv[1], sys.argv[2]
    done = threading.Event()
    with Bus(robot, name="peer", endpoint=endpoint) as bus:

        def echo(request: dict[str, Any]) -> dict[str, Any]:
            if "fail" in request:
                raise DuraError(f"refused: {request['fail']}")
            return {"echo": request, "from": "peer"}

        def chatter(request: dict[str, Any]) -> dict[str, Any]:
            for i in range(int(request["count"])):
                bus.publish("topic/chatter", {"i": i, "run": request.get("run", "")})
            return {"sent": request["count"]}

        heard: dict[str, int] = {}

        def listen(request: dict[str, Any]) -> dict[str, Any]:
            key = str(request["key"])
            heard[key] = 0
            bus.subscribe(key, lambda message: heard.update({key: heard[key] + 1}))
            return {}

        def stop(request: dict[str, Any]) -> dict[str, Any]:
            done.set()
            return {}

        bus.serve("test/echo", echo)
        bus.serve("test/chatter", chatter)
        bus.serve("test/listen", listen)
        bus.serve("test/heard", lambda request: {"count": heard.get(str(request["key"]), 0)})
        bus.serve("test/stop", stop)
        print("ready", flush=True)
        done.wait(60)


if __name__ == "__main__":
    main()
