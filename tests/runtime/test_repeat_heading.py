"""HeadingChoice.REPEAT: the hybrid layer learns a patrol's loop by watching the go.next targets
and picks each arrival heading for the whole loop (issue #15, Ordered Patrol ≤ 10 %)."""

from __future__ import annotations

import math

import pytest

from iterplan_compiler.experiments import missions
from iterplan_compiler.experiments.sweeps import Case, layout
from iterplan_compiler.runtime.executor import load_controller
from iterplan_compiler.runtime.ideal import kinematic_floor
from iterplan_compiler.runtime.mission import TargetMemory
from iterplan_compiler.runtime.planner import (
    ArrivalHeadings,
    HeadingChoice,
    MotionPlanner,
    admissible_headings,
    shortest_csc,
)
from iterplan_compiler.runtime.sim import SimVehicle
from iterplan_compiler.runtime.sorter import Pose


def test_memory_expects_nothing_until_a_target_repeats():
    m = TargetMemory()
    for c in (5, 7, 9):
        m.record(c)
        assert m.expected_after(c) == ([], False)
    m.record(5)                                 # the loop closes: 5 -> 7 -> 9 -> 5
    assert m.expected_after(5) == ([7, 9], True)
    assert m.expected_after(7) == ([9, 5], True)
    m.record(8)                                 # the plan changed its mind: 5 -> 8
    assert m.expected_after(5) == ([8], False)
    assert m.expected_after(9) == ([5, 8], False)
    assert TargetMemory().expected_after(1, limit=0) == ([], False)


def test_loop_heading_is_the_periodic_optimum():
    """Closing the chain, the chosen heading starts the cheapest periodic loop through the
    patrol points (cross-checked against the kinematic floor's DP in runtime/ideal.py)."""
    pts = [(0.0, 0.0), (350.0, 50.0), (150.0, 350.0)]
    heads = admissible_headings(math.pi / 2, True, ArrivalHeadings.GRID)
    v = SimVehicle(heading=0.0)
    radius = 43.9
    planner = MotionPlanner(v, radius=radius, arrival_heading=math.pi / 2,
                            headings=ArrivalHeadings.GRID, choice=HeadingChoice.REPEAT)
    p = v.pose()
    start = Pose(p.x, p.y, p.course)
    h = planner._best_heading(*pts[0], pts[1:], closes=True)
    loop = kinematic_floor(pts, [0, 1, 2], None, 0.0, radius, closed=True, headings=heads)
    leg = shortest_csc(start, *pts[0], h, radius).length
    best = min(shortest_csc(start, *pts[0], g, radius).length
               + _loop_from(pts, g, heads, radius) for g in heads)
    assert leg + _loop_from(pts, h, heads, radius) == pytest.approx(best)
    assert min(_loop_from(pts, g, heads, radius) for g in heads) == pytest.approx(loop)


def _loop_from(pts, h0, heads, radius):
    """Brute force: the closed loop through ``pts`` arriving at pts[0] with ``h0``."""
    best = math.inf
    for h1 in heads:
        for h2 in heads:
            hs = [h0, h1, h2, h0]
            total = sum(shortest_csc(Pose(*pts[i], hs[i]), *pts[(i + 1) % 3], hs[i + 1],
                                     radius).length for i in range(3))
            best = min(best, total)
    return best


@pytest.fixture(scope="module")
def patrol_table(tmp_path_factory):
    from iterplan_compiler.experiments.pipeline import compile_example

    path, _ = compile_example("ordered_patrol", tmp_path_factory.mktemp("ctrl"))
    return path, load_controller(path)


def test_repeat_leaves_the_patrol_events_unchanged_and_shortens_the_loop(patrol_table):
    """Same controller-observable events as the paper's heading choice (the `last` sorter's
    order does not depend on the pose), and the loops after the first are shorter."""
    path, _ = patrol_table
    from iterplan_compiler.experiments import flight

    case = Case("fig3b", 400, 3, "last", 1, loops=2)
    runs = {}
    for arrival in ((ArrivalHeadings.PARALLEL, HeadingChoice.SHORTEST),
                    (ArrivalHeadings.GRID, HeadingChoice.REPEAT)):
        grid = missions.build_grid(case)
        res = flight.fly(path, grid, sorter="last", seed=1,
                         stop=missions.StopWhen(case, grid, warmup=1), full_log=True,
                         heading=layout(case).heading, arrival=arrival)
        assert res.ok, res.reason
        runs[arrival[1]] = (res, missions.measure(case, res.log, grid, res.speed, warmup=1))
    (ref, ref_m), (rep, rep_m) = runs[HeadingChoice.SHORTEST], runs[HeadingChoice.REPEAT]
    assert [e.label for e in rep.log] == [e.label for e in ref.log]
    assert rep_m["duration"] < 0.98 * ref_m["duration"]
    assert rep_m["ideal"] == ref_m["ideal"] and rep_m["warmup"] == 1
