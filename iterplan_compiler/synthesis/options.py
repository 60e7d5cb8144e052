"""Options passed between the synthesis stages, as enums (issue 12: no option strings).

Dependency-free (no ``dd``): the command line builds its ``choices`` from these before any
BDD package is imported.
"""

from __future__ import annotations

from iterplan_compiler.enums import StrEnum

__all__ = ["GameMode", "MacroSteps", "Solver", "VariableOrder"]


class GameMode(StrEnum):
    """Which game :func:`encode.prepare` poses: MTSA's GR(1) game (§3.3), or the supervisory
    non-blocking game of ``heuristic``/``monolithicDirector`` with ``nonblocking`` (§3.9;
    its single guarantee is the marking)."""

    GR1 = "gr1"
    NONBLOCKING = "nonblocking"


class Solver(StrEnum):
    """Which GR(1) solver :func:`driver.synthesize` runs (both give the same verdict and
    controller)."""

    SYMBOLIC = "symbolic"  # BDD fixpoint (default)
    EXPLICIT = "explicit"  # MTSA's explicit rank solver


class VariableOrder(StrEnum):
    """BDD variable orders of the symbolic solver (``iterc synth --order``; see
    :mod:`symbolic_game`)."""

    CLUSTERED = "clustered"
    ACTION_FIRST = "action_first"
    ACTION_LAST = "action_last"
    BLOCKED = "blocked"


class MacroSteps(StrEnum):
    """Whether the symbolic GR(1) solver compresses the game: ``AUTO`` solves a turn-based
    game turn by turn (:mod:`turns`) where its conditions hold, else compresses
    controller-only chains into macro steps (:mod:`macro`) where those pay; ``CHAINS``
    only the latter; ``OFF`` never (the full game, e.g. to measure the transforms)."""

    AUTO = "auto"
    CHAINS = "chains"
    OFF = "off"
