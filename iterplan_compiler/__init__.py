"""iterplan: iterator-based temporal-logic task planning for UAVs.

Compiles FSP/FLTL specifications (the MTSA dialect) into GR(1) controllers and runs them
through :mod:`iterplan_compiler.runtime`.  Importing this package imports nothing heavy.
"""

__version__ = "0.1.0"
