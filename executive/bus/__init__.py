"""The bus: the bottom layer of the executive.

It owns the Zenoh session (:mod:`session`), the key expressions (:mod:`keys`), the
payloads every service publishes (:mod:`payloads`), each service's request API declared
once (:mod:`api`), and the pieces services are built from: their one lifecycle
(:mod:`service`), the driver of a process's services (:mod:`lifecycle_manager`), the
relay of events between processes (:mod:`event_relay`), :mod:`worker`. It imports
nothing of dura but :mod:`knowledge`.
"""
