"""The translator plug-ins that come with dura (entry-point group ``dura.translators``).

- :mod:`.process` — any program, driven through its process: started on start, ended
  on stop.
"""
