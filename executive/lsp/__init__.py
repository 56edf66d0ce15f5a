"""``dura lsp``: a language server for PDDL domains and problems, robot descriptions and
their rule files (stdio, on pygls).

- :mod:`.server` — the protocol wired to dura: the open documents, the checks as the user types;
  :mod:`.features` — one handler per request about a place in a file;
- :mod:`.project` — which files are checked together (a robot description and the files
  it names, or PDDL on its own);
- :mod:`.checks` — the checks of ``dura validate`` and ``dura domain check`` on the
  editor's unsaved texts; :mod:`.diagnostics` — a finding at the exact place of the name
  it is about;
- :mod:`.names` — every name the files declare and use, with its place;
  :mod:`.navigation` — hover, definition and references over them; :mod:`.completion` —
  what may be written at the cursor;
- :mod:`.pddl_syntax` — PDDL as tokens and lists with their places in the text;
  :mod:`.formatting` — PDDL in its canonical layout.

It sits above the planning layer and monitoring, whose checks it runs; pygls is imported
only by ``dura lsp`` itself.
"""
