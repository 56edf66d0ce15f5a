"""The thesis use-case components (chapter 7), written with dura's component SDK.

Each is scripted and deterministic: it simulates hardware, never dura itself. Every one
takes the faults of :mod:`executive.sdk.fault_injection`; ``out_of_range`` and ``slip`` are
interpreted here.
"""
