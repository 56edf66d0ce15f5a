"""The runtime: component processes on this machine.

It owns the launcher (spawning, reaping and log files of component processes; their
lifecycle commands; the goal protocol of behaviors), the component API on the bus, and
the translators that carry lifecycle commands to programs not written with the SDK.
It may import :mod:`executive.bus`, :mod:`executive.sdk` and :mod:`knowledge`.
"""
