"""The dashboard: a live web page of a running robot, and pictures (SVG) of plans and
component graphs.

The pictures are drawn by :mod:`executive.dashboard.gantt` (a plan as a Gantt chart)
and :mod:`executive.dashboard.graph` (the component/capability/topic graph), pure
functions from data to SVG text used alike by the command line (``--svg FILE``) and by
the page. :mod:`executive.dashboard.live` keeps what the page shows, fed from the bus by
:mod:`executive.dashboard.feed`; :mod:`executive.dashboard.app` serves it (Starlette,
server-sent events) and :mod:`executive.dashboard.server` runs it (uvicorn).
"""
