"""Run-time layer that executes synthesised controllers on a UAV.

Must import without ``lark`` or ``dd``: it ships to the aircraft's companion computer.
"""
