"""runtime/ideal.py: the one "ideal" of iterc run and the experiments, and the kinematic floor."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from iterplan_compiler.experiments import stats
from iterplan_compiler.runtime.ideal import (
    EXACT_MAX,
    IdealMethod,
    ideal_distance,
    ideal_path,
    kinematic_floor,
    nearest_neighbour_bound,
    path_length,
)
from iterplan_compiler.runtime.sorter import Pose


def brute(start, pts):
    return min(path_length(start, pts, o) for o in itertools.permutations(range(len(pts))))


@pytest.mark.parametrize("n", [1, 2, 5, 7])
def test_exact_is_the_optimum(n):
    rng = np.random.default_rng(n)
    pts = rng.random((n, 2)) * 800
    r = ideal_path(pts, (0.0, 0.0))
    assert r.method is IdealMethod.EXACT
    assert r.distance == pytest.approx(brute((0.0, 0.0), pts))
    assert sorted(r.order) == list(range(n))
    assert r.distance == pytest.approx(path_length((0.0, 0.0), pts, r.order))


def test_tour_on_a_grid_is_the_serpentine_optimum_and_above_its_bound():
    # 12 x 5 block entered at a corner: the optimum is reach + one side per further cell
    cells = [((c + 0.5) * 50, (r + 0.5) * 50) for r in range(5) for c in range(12)]
    r = ideal_path(cells, (25.0, -75.0))
    assert r.method is IdealMethod.TOUR
    assert r.distance == pytest.approx(100 + 59 * 50)
    assert r.lower <= r.distance + 1e-6
    assert r.lower == pytest.approx(r.distance)     # bound attained: proven optimal


def test_tour_never_beats_the_exact_optimum():
    rng = np.random.default_rng(3)
    pts = rng.random((EXACT_MAX + 3, 2)) * 500
    r = ideal_path(pts, (0.0, 0.0))
    assert r.method is IdealMethod.TOUR
    assert r.lower <= r.distance
    # dropping points cannot lengthen the optimum: exact on a subset is a lower bound
    assert ideal_path(pts[:EXACT_MAX], (0.0, 0.0)).distance <= r.distance + 1e-6


def test_bound_for_huge_sets_is_a_lower_bound_and_exact_on_a_grid():
    g = np.array([((c + 0.5) * 50, (r + 0.5) * 50) for r in range(30) for c in range(30)])
    nn = nearest_neighbour_bound((25.0, 25.0), g)
    assert nn == pytest.approx(899 * 50)
    rng = np.random.default_rng(0)
    pts = rng.random((9, 2)) * 300
    assert nearest_neighbour_bound((0.0, 0.0), pts) <= brute((0.0, 0.0), pts) + 1e-9


def test_ordered_closed_loop_and_the_experiments_use_the_same_definition():
    pts = [(0.0, 0.0), (300.0, 0.0), (300.0, 400.0)]
    assert ideal_path(pts, ordered=True, closed=True).distance == pytest.approx(1200.0)
    assert stats.ideal_patrol_loop(pts, 10.0) == pytest.approx(120.0)
    cells = [(125.0, 25.0), (25.0, 25.0), (75.0, 25.0)]
    assert stats.ideal_cover((0.0, 25.0), cells, 50.0, 1.0) == \
        pytest.approx(ideal_distance(cells, (0.0, 25.0)))


def test_kinematic_floor_is_at_least_the_ideal_and_straight_lines_cost_nothing_extra():
    col = [(25.0, 25.0 + 50 * k) for k in range(6)]       # a column, flown north
    start = Pose(25.0, -200.0, math.pi / 2)
    ideal = ideal_path(col, (25.0, -200.0))
    floor = kinematic_floor(col, ideal.order, start, math.pi / 2, 40.0)
    assert floor == pytest.approx(ideal.distance, abs=1e-6)
    zig = [(25.0, 25.0), (75.0, 25.0), (125.0, 25.0)]     # across the arrival heading
    i2 = ideal_path(zig, (25.0, -200.0))
    assert kinematic_floor(zig, i2.order, start, math.pi / 2, 40.0) > i2.distance + 100
