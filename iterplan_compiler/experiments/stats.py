"""Statistics and the paper's "ideal" mission durations.

Fig. 3's note: "The error bars are three times the estimated standard error of the mean ...
Ideal duration is calculated using the minimum flight distance needed for the mission using
constant speed, ignoring the UAV's movement restrictions."  That distance is defined and
computed once, in :mod:`iterplan_compiler.runtime.ideal` (shared with ``iterc run``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from iterplan_compiler.runtime.ideal import ideal_path


@dataclass(frozen=True)
class Summary:
    """Mean, sample standard deviation and standard error of the mean of ``n`` samples."""

    n: int
    mean: float
    std: float
    sem: float

    @property
    def err3(self) -> float:
        """Half-width of the paper's error bars: three standard errors."""
        return 3.0 * self.sem


def summarize(samples: Iterable[float]) -> Summary:
    """Summary of the samples.  ``std`` uses Bessel's correction (n - 1); with one sample the
    spread is unknown and reported as 0.  NaN samples (failed runs) are ignored."""
    xs = [float(x) for x in samples if not math.isnan(float(x))]
    n = len(xs)
    if n == 0:
        return Summary(0, math.nan, math.nan, math.nan)
    mean = math.fsum(xs) / n
    if n == 1:
        return Summary(1, mean, 0.0, 0.0)
    var = math.fsum((x - mean) ** 2 for x in xs) / (n - 1)
    std = math.sqrt(var)
    return Summary(n, mean, std, std / math.sqrt(n))


def overhead(duration: float, ideal: float) -> float:
    """Proportional overhead over the ideal, in percent: 100 (duration - ideal) / ideal."""
    if ideal <= 0:
        raise ValueError("ideal duration must be positive")
    return 100.0 * (duration - ideal) / ideal


def tour_length(points: Sequence[tuple[float, float]], closed: bool = True) -> float:
    """Length of the polygonal path through ``points`` in order (back to the first if
    ``closed``), in the points' unit."""
    return ideal_path(points, ordered=True, closed=closed).distance if points else 0.0


def ideal_patrol_loop(points: Sequence[tuple[float, float]], speed: float) -> float:
    """Ideal duration (s) of one Ordered-Patrol loop: the closed tour through the patrol
    locations in their (prescribed) order, straight legs at constant ``speed`` (m/s)."""
    if speed <= 0:
        raise ValueError("speed must be positive")
    return tour_length(points, closed=True) / speed


def ideal_cover(start: tuple[float, float], cells: Sequence[tuple[float, float]],
                cell_size: float, speed: float) -> float:
    """Ideal duration (s) to cover ``cells`` (ENU centres, metres) from ``start``: the
    runtime's one definition (:func:`iterplan_compiler.runtime.ideal.ideal_path`, the shortest
    open path through the cells at constant ``speed``, no turn limits), as ``iterc run``
    reports it.  ``cell_size`` is kept for the callers; the path needs none."""
    if speed <= 0 or cell_size <= 0:
        raise ValueError("speed and cell_size must be positive")
    if not cells:
        return 0.0
    return ideal_path(cells, start).distance / speed
