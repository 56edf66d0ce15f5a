"""The component SDK: what a component author imports.

    from executive.sdk import Functionality, Behavior, GoalFailed

It owns the framework side of a component process (connecting to the bus, taking
lifecycle commands, rate loops, goals) and fault injection for tests. It may import
:mod:`executive.bus` and :mod:`knowledge`.
"""
