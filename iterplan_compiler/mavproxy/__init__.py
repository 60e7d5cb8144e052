"""Running generated controllers inside MAVProxy (the paper's deployment style).

- :mod:`.mavproxy_iterplan`: the MAVProxy module (``module load iterplan``); the only part that
  imports MAVProxy (an optional dependency: ``pip install iterplan[mavproxy]``).
- :mod:`.mission`: one mission in a background thread (``iterplan run/status/stop``).
- :mod:`.link`: :class:`~.link.ModuleLink`, the pymavlink-style connection object that lets
  :class:`~iterplan_compiler.runtime.mavlink.MavlinkVehicle` run over MAVProxy's link.

See ``docs/mavproxy.md``.  Importing this package does not import MAVProxy.
"""
