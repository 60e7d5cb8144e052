"""The order levers (runtime/tour.py, planner heading options): better flights, same controller.

The controller-observable event sequence must not change with the levers: the heading options
change only the flight (so with an order that does not depend on poses, ``last``, every event
and every offered cell is identical), and the tour sorter changes only the order in which the
Iterator offers locations (Cover: the same multiset of events, one pass over the same cells).
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest

from iterplan_compiler.experiments import missions
from iterplan_compiler.experiments.sweeps import Case, layout
from iterplan_compiler.runtime.executor import Executor, RunConfig, load_controller
from iterplan_compiler.runtime.planner import ArrivalHeadings, HeadingChoice
from iterplan_compiler.runtime.sim import SimVehicle
from iterplan_compiler.runtime.sorter import Pose, SorterKind
from iterplan_compiler.runtime.sorters import make_sorter
from iterplan_compiler.runtime.tour import (
    TourSorter,
    _greedy,
    dubins_order_length,
    dubins_order_plan,
    plan_tour,
)


@pytest.fixture(scope="module")
def cover_table(tmp_path_factory):
    from iterplan_compiler.experiments.pipeline import compile_example

    path, _ = compile_example("cover", tmp_path_factory.mktemp("ctrl"))
    return load_controller(path)


def fly(table, case, sorter, headings=ArrivalHeadings.PARALLEL,
        choice=HeadingChoice.SHORTEST):
    grid = missions.build_grid(case)
    events, offered = [], []
    holder = {}

    def on_event(kind, label):
        events.append((kind, label))
        if label == "has.next":
            if holder["ex"].iterator.next is not None:
                offered.append(holder["ex"].iterator.next)

    cfg = RunConfig(sorter=sorter, ideal_compute=True, passes=1, log_limit=0,
                    headings=headings, heading_choice=choice, on_event=on_event)
    ex = Executor(table, grid, SimVehicle(home=grid.home, heading=layout(case).heading),
                  config=cfg)
    holder["ex"] = ex
    res = ex.run()
    assert res.ok, res.reason
    return events, offered, res


@pytest.mark.parametrize("headings,choice", [
    (ArrivalHeadings.PARALLEL, HeadingChoice.LOOKAHEAD),
    (ArrivalHeadings.GRID, HeadingChoice.SHORTEST),
    (ArrivalHeadings.GRID, HeadingChoice.LOOKAHEAD),
    (ArrivalHeadings.PARALLEL, HeadingChoice.REPEAT),
    (ArrivalHeadings.GRID, HeadingChoice.REPEAT)])
def test_heading_levers_leave_the_controller_events_unchanged(cover_table, headings, choice):
    case = Case("fig3c", 144, 12, "last", 1)
    ref_events, ref_offered, ref = fly(cover_table, case, SorterKind.LAST)
    events, offered, res = fly(cover_table, case, SorterKind.LAST, headings, choice)
    assert events == ref_events and offered == ref_offered
    assert (res.summary["headings"], res.summary["heading_choice"]) == \
        (headings.value, choice.value)
    if headings is ArrivalHeadings.GRID:      # the lever did change the flight
        assert res.track.shape != ref.track.shape or not np.allclose(res.track, ref.track)


def test_tour_sorter_changes_only_the_order(cover_table):
    case = Case("fig3c", 144, 12, "tour", 2)
    ref_events, ref_offered, _ = fly(cover_table, case, SorterKind.DISTANCE)
    events, offered, res = fly(cover_table, case, SorterKind.TOUR, choice=HeadingChoice.LOOKAHEAD)
    assert Counter(events) == Counter(ref_events)
    assert sorted(offered) == sorted(ref_offered) == list(range(144))
    assert offered != ref_offered
    region = set(missions.build_grid(case).sensors["cover"].tolist())
    # the tour offers the region first, in its planned order
    assert set(offered[:len(region)]) == region
    assert res.summary["sorter"] == "tour"


def test_tour_keys_follow_the_plan_and_put_the_rest_after():
    xs = np.array([25.0, 75.0, 125.0, 25.0, 75.0, 500.0], dtype=np.float32)
    ys = np.array([25.0, 25.0, 25.0, 75.0, 75.0, 500.0], dtype=np.float32)
    ids = np.arange(6)
    mask = np.array([True, True, True, True, True, False])
    s = make_sorter("tour", radius=40.0, arrival_heading=math.pi / 2, interesting=mask)
    assert isinstance(s, TourSorter)
    pose = Pose(0.0, -300.0, math.pi / 2)
    s.on_reset(xs, ys, ids, pose)
    keys = s.keys(xs, ys, ids, pose)
    order = np.argsort(keys, kind="stable")
    assert order[-1] == 5 and sorted(order[:5].tolist()) == [0, 1, 2, 3, 4]
    assert all(s.planned_heading(int(c)) is not None for c in range(5))
    assert s.planned_heading(5) is None


def test_plan_is_no_longer_than_greedy_and_the_dp_heads_reproduce_its_length():
    rng = np.random.default_rng(5)
    pts = np.array([((c + 0.5) * 50, (r + 0.5) * 50) for r in range(5) for c in range(6)])
    pts = pts[rng.permutation(len(pts))]
    start = Pose(-100.0, -100.0, 0.3)
    heads = (math.pi / 2, 3 * math.pi / 2)
    order, planned = plan_tour(pts, start, heads, 44.0, 50.0)
    length, again = dubins_order_plan(pts[order], start, heads, 44.0)
    assert planned == again and len(planned) == len(pts)
    greedy = dubins_order_length(pts[_greedy(pts, start, heads, 44.0)], start, heads, 44.0)
    assert length <= greedy + 1e-6


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_grid_plan_is_never_longer_than_an_axis_plan(seed):
    """The orders found over the axis headings are candidates of a grid plan too (and the DP
    flies them with all four headings), so adding headings can only shorten the plan."""
    rng = np.random.default_rng(seed)
    side = 4
    pts = np.array([((c + 0.5) * 50, (r + 0.5) * 50) for r in range(side) for c in range(side)])
    pts = pts[: 10 + seed * 3]
    start = Pose(float(rng.uniform(-400, -100)), float(rng.uniform(-400, -100)),
                 float(rng.uniform(0, 2 * math.pi)))
    axis = (math.pi / 2, 3 * math.pi / 2)
    grid = (*axis, 0.0, math.pi)
    lengths = {}
    for heads in (axis, grid):
        order, _ = plan_tour(pts, start, heads, 43.9, 50.0)
        lengths[len(heads)] = dubins_order_length(pts[order], start, heads, 43.9)
    assert lengths[4] <= lengths[2] + 1e-6
