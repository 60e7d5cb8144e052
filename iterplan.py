"""MAVProxy entry point: ``module load iterplan`` finds this top-level module (MAVProxy tries
``MAVProxy.modules.mavproxy_iterplan`` first, then plain ``iterplan``).  The module itself is
:mod:`iterplan_compiler.mavproxy.mavproxy_iterplan`; see ``docs/mavproxy.md``."""

from iterplan_compiler.mavproxy.mavproxy_iterplan import IterplanModule, init  # noqa: F401
