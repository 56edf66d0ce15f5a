"""The dashboard: a live web page of a running robot, and pictures (SVG) of plans and
component graphs.

It may import :mod:`executive.bus`, :mod:`executive.planning` and :mod:`knowledge`.

- :mod:`.gantt`, :mod:`.graph` — a plan as a Gantt chart, the component/capability/topic
  graph: pure functions from data to SVG text, for the command line (``--svg FILE``)
  and the page alike (:mod:`.svg`: the small SVG writer both use);
- :mod:`.live` — what the page shows of a running robot, plain data;
- :mod:`.feed` — the link to the robot: bus subscriptions in, server-sent events out;
- :mod:`.app` — the web application (Starlette): the page (``static/``), the stream,
  the pictures, adding and cancelling goals;
- :mod:`.access` — who may open the page;
- :mod:`.server` — uvicorn serving the application on a thread of its own.
"""
