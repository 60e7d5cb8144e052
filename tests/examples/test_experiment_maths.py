"""Experiment maths: SEM, ideal durations, sweep definitions, the harness and the plots."""

from __future__ import annotations

import csv
import io
import math
import statistics

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from iterplan_compiler.experiments import harness, stats, sweeps
from iterplan_compiler.experiments.sweeps import Case, Experiment
from iterplan_compiler.runtime.sorter import SorterKind


def test_summary_matches_statistics_module():
    xs = [3.0, 5.0, 4.0, 8.0, 10.0]
    s = stats.summarize(xs)
    assert s.n == 5
    assert s.mean == pytest.approx(statistics.mean(xs))
    assert s.std == pytest.approx(statistics.stdev(xs))
    assert s.sem == pytest.approx(statistics.stdev(xs) / math.sqrt(5))
    assert s.err3 == pytest.approx(3 * s.sem)


def test_summary_edge_cases():
    assert stats.summarize([]).n == 0
    assert math.isnan(stats.summarize([]).mean)
    one = stats.summarize([2.5])
    assert (one.n, one.mean, one.sem) == (1, 2.5, 0.0)
    # failed runs (NaN) are ignored
    assert stats.summarize([1.0, math.nan, 3.0]).mean == pytest.approx(2.0)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-1e6, 1e6), min_size=2, max_size=30))
def test_sem_shrinks_with_copies(xs):
    s1, s2 = stats.summarize(xs), stats.summarize(xs * 4)
    assert s2.mean == pytest.approx(s1.mean, rel=1e-9, abs=1e-6)
    assert s2.sem <= s1.sem + 1e-9


def test_overhead():
    assert stats.overhead(188.0, 100.0) == pytest.approx(88.0)
    assert stats.overhead(100.0, 100.0) == 0.0
    with pytest.raises(ValueError):
        stats.overhead(1.0, 0.0)


def test_ideal_patrol_loop_is_closed_tour_over_speed():
    pts = [(0.0, 0.0), (300.0, 0.0), (300.0, 400.0)]
    # 300 + 400 + 500 = 1200 m at 17 m/s
    assert stats.ideal_patrol_loop(pts, 17.0) == pytest.approx(1200.0 / 17.0)


def test_ideal_cover_rectangle_from_corner():
    cells = [(25.0 + 50 * c, 25.0 + 50 * r) for r in range(3) for c in range(4)]
    start = (25.0 - 100.0, 25.0)  # 100 m west of the corner cell
    assert stats.ideal_cover(start, cells, 50.0, 20.0) == pytest.approx((100 + 11 * 50) / 20.0)


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 40), st.floats(-500, 500), st.floats(-500, 500))
def test_ideal_cover_is_a_lower_bound_of_any_order(n, sx, sy):
    cells = [(25.0 + 50 * (i % 7), 25.0 + 50 * (i // 7)) for i in range(n)]
    ideal = stats.ideal_cover((sx, sy), cells, 50.0, 1.0)
    # the row-by-row (boustrophedon-free) order from the start is one feasible path
    path = [(sx, sy)] + cells
    assert ideal <= stats.tour_length(path, closed=False) + 1e-6


def test_sweeps_full_sizes_follow_the_paper():
    b = sweeps.sweep(Experiment.FIG3B)
    assert max(c.universe for c in b) == 700_000
    assert {c.sorter for c in b} == set(SorterKind)
    assert len({c.seed for c in b}) == 30
    c = sweeps.sweep(Experiment.FIG3C)
    assert {x.universe for x in c} == {713}
    assert len({x.seed for x in c}) == 30
    d = sweeps.sweep(Experiment.FIG3D)
    assert {x.count for x in d} == {61}


@pytest.mark.parametrize("exp", sweeps.EXPERIMENTS)
def test_quick_cases_fit_their_maps(exp):
    for case in sweeps.sweep(exp, quick=True):
        data = sweeps.case_map_data(case)
        assert data["cols"] * data["rows"] >= case.universe
        sensors = data["sensors"]
        if exp is Experiment.FIG3B:
            assert sorted(sensors) == ["p.0", "p.1", "p.2"]
        else:
            assert len(sensors["cover"]) == case.count


def test_region_cells_contiguous_and_distinct():
    cells = sweeps.region_cells(61)
    assert len(set(cells)) == 61
    side = math.ceil(math.sqrt(61))
    assert all(sweeps.COVER_OFFSET[0] <= c < sweeps.COVER_OFFSET[0] + side for c, _ in cells)


def test_bad_case_rejected():
    with pytest.raises(ValueError):
        sweeps.check_case(Case("fig3c", 20, 61, "last", 0))
    with pytest.raises(ValueError, match="unknown experiment 'fig3a'; expected one of fig3b"):
        sweeps.sweep(Experiment.FIG3A)
    with pytest.raises(ValueError):
        Case("fig9", 20, 6, "last", 0)
    with pytest.raises(ValueError, match="unknown sorter"):
        Case("fig3c", 20, 6, "nearest", 0)


def test_case_values_are_converted_to_enums():
    case = Case("fig3c", 713, 25, "tour", 3)
    assert case.experiment is Experiment.FIG3C and case.sorter is SorterKind.TOUR
    assert case == Case(Experiment.FIG3C, 713, 25, SorterKind.TOUR, 3)
    assert case.values() == ("fig3c", 713, 25, "tour", 3, 1)
    assert Experiment.ALL.expand() == (Experiment.FIG3A, Experiment.FIG3B, Experiment.FIG3C,
                                       Experiment.FIG3D, Experiment.SYNTHESIS_TABLE)


def fake_runner(case: Case) -> dict:
    """Deterministic stand-in for a simulation: duration grows with the universe."""
    if case.sorter is SorterKind.RANDOM and case.seed == 1 and case.universe == 400:
        raise RuntimeError("simulated crash")
    ideal = 100.0
    return {"duration": ideal * (1 + case.universe / 1000) + case.seed, "ideal": ideal,
            "events": case.universe * 3}


@pytest.mark.parametrize("jobs", [1, 2])
def test_harness_rows_csv_and_aggregate(jobs):
    cases = sweeps.sweep(Experiment.FIG3B, quick=True)
    out = io.StringIO()
    prog = harness.Progress(len(cases), "fig3b", stream=out)
    rows = harness.run_cases(cases, fake_runner, jobs=jobs, progress=prog)
    assert [c.values() for c in cases] == [tuple(r[f] for f in harness.CASE_FIELDS) for r in rows]
    assert rows[0]["experiment"] == "fig3b" and rows[0]["sorter"] in sweeps.SORTERS
    assert prog.done == len(cases) and prog.failed == 1
    assert "failed" in out.getvalue()
    failed = [r for r in rows if r["error"]]
    assert len(failed) == 1 and "simulated crash" in failed[0]["error"]
    text = harness.write_csv(rows)
    parsed = list(csv.DictReader(io.StringIO(text)))
    assert len(parsed) == len(cases)
    assert "events" in parsed[0]
    points = harness.aggregate(rows)
    p = next(p for p in points if p.universe == 144 and p.sorter == "last")
    # seeds 0 and 1 -> durations d and d + 1
    assert p.n == 2
    assert p.duration == pytest.approx(100 * 1.144 + 0.5)
    assert p.duration_err3 == pytest.approx(3 * 0.5)
    assert p.overhead_pct == pytest.approx(14.4 + 0.5)
    bad = next(p for p in points if p.universe == 400 and p.sorter == "random")
    assert bad.failed == 1 and bad.n == 1


def test_plots_written(tmp_path):
    for exp in sweeps.EXPERIMENTS:
        rows = harness.run_cases(sweeps.sweep(exp, quick=True), fake_runner)
        png = harness_plot(exp, rows, tmp_path)
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def harness_plot(exp, rows, tmp_path):
    from iterplan_compiler.experiments import plots

    return plots.plot(exp, harness.aggregate(rows), tmp_path / f"{exp.value}.png")


def test_trajectory_plot(tmp_path):
    from types import SimpleNamespace

    from iterplan_compiler.experiments import missions, trajectories
    from iterplan_compiler.experiments.missions import LogEvent

    case = Case("fig3b", 144, 3, "last", 0)
    grid = missions.build_grid(case)
    res = SimpleNamespace(log=[LogEvent(5.0, "visited.p.0")],
                          track=[(float(t), 10.0 * t, 5.0 * t) for t in range(20)])
    png = trajectories.plot_tracks([(144, res, grid)], tmp_path / "a.png")
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_arrival_for_takes_the_enums():
    from iterplan_compiler.experiments.missions import arrival_for
    from iterplan_compiler.runtime.planner import ArrivalHeadings, HeadingChoice

    assert arrival_for(SorterKind.TOUR, Experiment.FIG3C, 10) == (ArrivalHeadings.GRID,
                                                                  HeadingChoice.LOOKAHEAD)
    assert arrival_for(SorterKind.TOUR, Experiment.FIG3C, 61) == (ArrivalHeadings.PARALLEL,
                                                                  HeadingChoice.LOOKAHEAD)
    for sorter, exp in ((SorterKind.TOUR, Experiment.FIG3B), (SorterKind.LAST, Experiment.FIG3C)):
        assert arrival_for(sorter, exp, 10) == (ArrivalHeadings.PARALLEL, HeadingChoice.SHORTEST)
