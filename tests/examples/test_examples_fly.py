"""Every bundled example: front-end -> synthesis -> generated module -> flown on the built-in
simulator, with the task's observable behaviour checked from the event log."""

from __future__ import annotations

import pytest

from iterplan_compiler.experiments import catalog, flight
from iterplan_compiler.pipeline import load_model as load

from .behaviour import cells, check_cover, check_fire_patrol, check_ordered_patrol


@pytest.mark.parametrize("name", sorted(catalog.EXAMPLES))
def test_example_elaborates_without_diagnostics(name):
    ex = catalog.EXAMPLES[name]
    model, diags = load(str(catalog.example_path(name)))
    assert model is not None and not diags, diags
    assert ex.composite in model.names()
    problem, diags = model.synthesis_problem(ex.composite)
    assert problem is not None and not diags, diags
    assert "controller" in problem.keywords


def _fly(compiled, name, stop, **kw):
    grid, data = compiled.map(name)
    res = flight.fly(compiled.module(name), grid, stop=stop, map_data=data, max_time=3600, **kw)
    assert res.ok, res.reason
    return res, grid


@pytest.mark.parametrize("sorter", ["distance", "last", "random"])
def test_fire_patrol_one_pass(compiled, sorter):
    res, grid = _fly(compiled, "fire_patrol", lambda e: e.label == "n.next", sorter=sorter)
    check_fire_patrol(res.log, grid)


def test_fire_patrol_second_pass_after_reset(compiled):
    n = {"k": 0}

    def stop(e):
        n["k"] += e.label == "n.next"
        return n["k"] >= 2

    res, grid = _fly(compiled, "fire_patrol", stop)
    arrivals = cells(res.log, "arrived")
    patrol = {int(c) for c in grid.sensors["inP"]}
    assert len(arrivals) == 2 * len(patrol) and set(arrivals) == patrol


@pytest.mark.parametrize("sorter", ["distance", "random"])
def test_cover_visits_exactly_the_region(compiled, sorter):
    res, grid = _fly(compiled, "cover", lambda e: e.label == "n.next", sorter=sorter, seed=3)
    check_cover(res.log, grid)


def test_find_nemo_stays_while_nemo_is_there(compiled):
    res, grid = _fly(compiled, "find_nemo", lambda e: e.label == "n.next")
    roi = {int(c) for c in grid.sensors["roi"]}
    nemo = {int(c) for c in grid.sensors["nemo"]}
    assert set(cells(res.log, "arrived")) == roi
    photos = cells(res.log, "take.photo")
    # Nemo answers yes twice per cell (map: yes_answers 2): two photos at each Nemo cell,
    # taken before the plane moves on.
    assert sorted(photos) == sorted(c for c in nemo for _ in range(2))
    seq = [e.label for e in res.log if e.label in ("go.next", "take.photo")]
    for c in nemo:
        i = next(k for k, e in enumerate(res.log) if e.label == "take.photo" and e.cell == c)
        assert res.log[i - 1].label == "yes.nemo"
    assert seq.count("take.photo") == 4


def test_ordered_patrol_visits_in_order(compiled):
    seen = {"v": 0}

    def stop(e):
        seen["v"] += e.label.startswith("visited.p.")
        return seen["v"] >= 7

    res, grid = _fly(compiled, "ordered_patrol", stop)
    check_ordered_patrol(res.log, grid, 3)
    # never goes anywhere but the due patrol location
    targets = {int(grid.sensors[f"p.{i}"][0]) for i in range(3)}
    assert set(cells(res.log, "arrived")) <= targets


def test_search_and_map_maps_around_the_target_then_lands(compiled):
    # One mission: search, map, land; `restart` would begin the next one.
    res, grid = _fly(compiled, "search_and_map", lambda e: e.label == "restart")
    target = int(grid.sensors["target"][0])
    log = res.log
    stored = [e.cell for e in log if e.label == "store.target"]
    assert stored == [target]
    i_store = next(k for k, e in enumerate(log) if e.label == "store.target")
    # before the target was found: no photos; after: photos only of cells adjacent to it
    assert not [e for e in log[:i_store] if e.label == "take.photo"]
    cols = grid.cols
    tr, tc = divmod(target, cols)
    ring = {r * cols + c for r in range(tr - 1, tr + 2) for c in range(tc - 1, tc + 2)
            if 0 <= r < grid.rows and 0 <= c < cols}
    photos = {e.cell for e in log[i_store:] if e.label == "take.photo"}
    assert photos == ring
    # after the target was found, the plane only flies to cells adjacent to it
    assert set(cells(log[i_store + 1:], "arrived")) <= ring
    assert [e.label for e in log[-3:]] == ["land", "landed", "restart"]
    assert sum(e.label == "n.next" for e in log[i_store:]) == 2
