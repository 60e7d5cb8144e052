"""Test oracles: deliberately naive, explicit-state solvers used only to cross-check the
symbolic engine (``synthesis/fixpoint.py``).  Nothing in the compiler pipeline imports this
package.

* :mod:`gr1_explicit` — the explicit GR(1) solver: brute-force enumeration of a slugsin
  game and the three-nested fixpoint on Python sets (transition-based form, classic passes,
  no optimisation), plus an exhaustive strategy checker.
"""
