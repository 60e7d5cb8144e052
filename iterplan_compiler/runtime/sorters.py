"""Choosing a sorter by name (``iterc run --sorter``): the one place that knows every kind.

:mod:`.sorter` has the paper's sorters (``distance``, ``last``, ``random``), :mod:`.tour` the
tour-based one built on them; this factory sits above both, so neither imports the other
back.
"""

from __future__ import annotations

import math

import numpy as np

from iterplan_compiler.runtime.sorter import (
    DistanceSorter,
    LastSorter,
    RandomSorter,
    Sorter,
    SorterKind,
    sorter_kind,
)
from iterplan_compiler.runtime.tour import TourSorter


def make_sorter(name: str | SorterKind, *, radius: float = 50.0,
                arrival_heading: float = math.pi / 2, parallel: bool = True,
                interesting: np.ndarray | None = None, seed: int = 0,
                headings: tuple[float, ...] | None = None, spacing: float = 50.0) -> Sorter:
    """Build a sorter (``distance``, ``last``, ``random``, ``tour``).  ``headings``: the
    admissible arrival headings for ``tour`` (default: the arrival heading, and its opposite
    when ``parallel``)."""
    kind = sorter_kind(name)
    if kind is SorterKind.DISTANCE:
        return DistanceSorter(radius, arrival_heading, parallel,
                              grid=headings is not None and len(headings) == 4)
    if kind is SorterKind.RANDOM:
        return RandomSorter(seed)
    if interesting is None:
        raise ValueError(f"the {kind.value!r} sorter needs the interesting-cells mask")
    if kind is SorterKind.LAST:
        return LastSorter(interesting)
    if headings is None:
        headings = (arrival_heading, arrival_heading + math.pi) if parallel else \
            (arrival_heading,)
    return TourSorter(radius, arrival_heading, interesting, headings, spacing)
