"""Measurements taken from mission event logs (synthetic logs: no simulator needed)."""

from __future__ import annotations

import pytest

from iterplan_compiler.experiments import missions, sweeps
from iterplan_compiler.experiments.missions import LogEvent as E
from iterplan_compiler.experiments.stats import ideal_cover, ideal_patrol_loop


def test_loop_times():
    log = [E(0, "has.next"), E(10, "visited.p.0"), E(20, "visited.p.1"), E(40, "visited.p.0"),
           E(75, "visited.p.0")]
    assert missions.loop_times(log) == [30, 35]


def test_cover_time_from_first_has_next():
    log = [E(1, "takeoff.ended"), E(5, "has.next", -1, 0.0, 0.0), E(9, "arrived", 3),
           E(12, "arrived", 7), E(13, "arrived", 3), E(20, "arrived", 4), E(30, "arrived", 9)]
    t, start = missions.cover_time(log, [3, 4, 7])
    assert t == 15 and start.t == 5
    with pytest.raises(missions.MeasurementError):
        missions.cover_time(log, [3, 11])
    with pytest.raises(missions.MeasurementError):
        missions.cover_time(log[:1], [3])


def test_measure_patrol_case_uses_the_tour_of_patrol_cells():
    case = sweeps.Case("fig3b", 144, 3, "last", 0, loops=1)
    grid = missions.build_grid(case)
    assert len(grid.cells) == 144
    log = [E(10, "visited.p.0"), E(200, "visited.p.0")]
    res = missions.measure(case, log, grid, speed=17.0)
    pts = [grid.centre(int(grid.sensors[f"p.{i}"][0])) for i in range(3)]
    assert res["duration"] == 190
    assert res["ideal"] == pytest.approx(ideal_patrol_loop(pts, 17.0))


def test_measure_cover_case_and_stop_predicate():
    case = sweeps.Case("fig3d", 169, 4, "distance", 0)
    grid = missions.build_grid(case)
    region = [int(c) for c in grid.sensors["cover"]]
    assert len(region) == 4
    stop = missions.StopWhen(case, grid)
    log = [E(2, "has.next", -1, 25.0, 25.0)]
    assert not stop(log[0])
    for i, c in enumerate(region):
        log.append(E(10 + 5 * i, "arrived", c))
        assert stop(log[-1]) == (i == len(region) - 1)
    res = missions.measure(case, log, grid, speed=20.0)
    assert res["duration"] == 10 + 5 * 3 - 2
    centres = [grid.centre(c) for c in region]
    assert res["ideal"] == pytest.approx(ideal_cover((25.0, 25.0), centres, 50.0, 20.0))


def test_patrol_stop_after_loops_plus_one_visits():
    case = sweeps.Case("fig3b", 144, 3, "random", 1, loops=2)
    stop = missions.StopWhen(case, missions.build_grid(case))
    hits = [stop(E(i, "visited.p.0")) for i in range(3)]
    assert hits == [False, False, True]
