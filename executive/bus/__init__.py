"""The bus: the bottom layer of the executive.

It owns the Zenoh session (:mod:`session`), the key expressions (:mod:`keys`), the
payloads every service publishes (:mod:`payloads`), the records services report
(:mod:`reports`), each service's request API declared once (:mod:`api`), and the pieces
services are built from (:mod:`service`,
:mod:`worker`). It imports nothing of dura but :mod:`knowledge`.
"""
