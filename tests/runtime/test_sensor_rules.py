"""Map sensor rules: ``dynamic`` (yes answers run out) and ``derived`` (answered from cells
stored by an action) -- map schema in ``grid.load_map``, bindings in ``bindings.py``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from iterplan_compiler.cli import main
from iterplan_compiler.runtime.bindings import Bindings, map_rule_bindings
from iterplan_compiler.runtime.executor import Executor, RunConfig
from iterplan_compiler.runtime.grid import DerivedSensor, DynamicSensor, MapError
from iterplan_compiler.runtime.mapfile import load_map, parse_cell_name
from iterplan_compiler.runtime.sim import SimVehicle
from tests.runtime.fire_patrol import TABLE

BASE = {"cols": 6, "rows": 5, "home": {"cell": "A1"}, "sensors": {"inP": ["B2", "C3"],
                                                                   "fire": ["B2"]}}


def grid_with(**extra):
    return load_map(data={**BASE, **extra})


class Ctx:
    """The part of MissionContext the store action uses."""

    def __init__(self, grid, cell):
        self.grid, self.cell, self.notes = grid, cell, []

    def current_cell(self):
        return self.cell

    def note(self, text):
        self.notes.append(text)


def test_load_map_reads_rules():
    g = grid_with(dynamic={"fire": {"yes_answers": 3}},
                  derived={"near": {"neighbours_of": "store.hit", "connectivity": 4}})
    assert g.dynamic == {"fire": DynamicSensor(3)}
    assert g.derived == {"near": DerivedSensor("store.hit", 4)}
    assert grid_with().dynamic == {} and grid_with().derived == {}
    # defaults
    assert grid_with(derived={"adj": {}}).derived["adj"] == DerivedSensor("store.target", 8)


@pytest.mark.parametrize("extra, message", [
    ({"dynamic": {"nemo": {"yes_answers": 2}}}, "dynamic sensor 'nemo' has no cells"),
    ({"dynamic": {"fire": {"yes_answers": 0}}}, "yes_answers must be an integer >= 1"),
    ({"dynamic": {"fire": {"yes_answers": "2"}}}, "yes_answers must be an integer >= 1"),
    ({"dynamic": {"fire": {"yes": 2}}}, "expected {\"yes_answers\": K}"),
    ({"dynamic": ["fire"]}, "must be JSON objects"),
    ({"derived": {"fire": {}}}, "also has static cells"),
    ({"derived": {"adj": {"connectivity": 6}}}, "connectivity must be 4 or 8"),
    ({"derived": {"adj": {"neighbours_of": 3}}}, "neighbours_of must name an action"),
    ({"derived": {"adj": {"of": "x"}}}, "expected {\"neighbours_of\""),
])
def test_bad_rules_are_map_errors(extra, message):
    with pytest.raises(MapError) as exc:
        grid_with(**extra)
    assert message in str(exc.value)


def test_dynamic_sensor_counts_yes_answers_per_cell_and_mission():
    g = grid_with(dynamic={"inP": {"yes_answers": 2}})
    b2, c3 = parse_cell_name(g, "B2"), parse_cell_name(g, "C3")
    pred = map_rule_bindings(g).sensors["inp"]
    assert [pred(b2) for _ in range(3)] == [True, True, False]
    assert [pred(c3) for _ in range(3)] == [True, True, False]
    assert not pred(0)
    # a new mission starts afresh
    assert map_rule_bindings(g).sensors["inp"](b2)


def test_derived_sensor_marks_the_neighbourhood_of_stored_cells():
    for conn, expect in ((8, {"B1", "C1", "D1", "B2", "C2", "D2", "B3", "C3", "D3"}),
                         (4, {"C1", "B2", "C2", "D2", "C3"})):
        g = grid_with(derived={"adj": {"neighbours_of": "store.target", "connectivity": conn}})
        b = map_rule_bindings(g)
        adj = b.sensors["adj"]
        assert not any(adj(c) for c in range(g.num_cells))
        ctx = Ctx(g, parse_cell_name(g, "C2"))
        b.custom["store.target"](ctx, "store.target")
        assert {g.cell_name(c) for c in range(g.num_cells) if adj(c)} == expect
        assert ctx.notes == ["stored C2"]
    # corner: the neighbourhood is clipped to the grid (no wrap-around to the other edge)
    b = map_rule_bindings(g)
    b.custom["store.target"](Ctx(g, parse_cell_name(g, "F1")), "store.target")
    assert {g.cell_name(c) for c in range(g.num_cells) if b.sensors["adj"](c)} == \
        {"F1", "E1", "F2"}


def test_callers_bindings_take_precedence():
    g = grid_with(dynamic={"fire": {"yes_answers": 1}}, derived={"adj": {}})
    mine = Bindings().sensor("fire", lambda c: True).bind("store.target", lambda ctx, lab: None)
    b = map_rule_bindings(g, mine)
    assert b.sensors["fire"](0) and b.sensors["fire"](0)    # the caller's, not the rule's
    assert "adj" not in b.sensors                           # rule skipped: action is bound
    assert mine.sensors.keys() == {"fire"}                   # the caller's object is not changed


def test_executor_applies_dynamic_rule():
    """Hand-written Fire Patrol, fire at B2 limited to one yes answer: two passes, one photo."""
    g = grid_with(dynamic={"fire": {"yes_answers": 1}})
    v = SimVehicle(home=g.home, heading=g.arrival_heading)
    res = Executor(TABLE, g, v, config=RunConfig(ideal_compute=True, passes=2)).run()
    assert res.ok, res.reason
    assert res.summary["arrivals"] == 4 and res.summary["photos"] == 1


def test_run_until(tmp_path, capsys):
    ctl = tmp_path / "ctl.py"
    ctl.write_text((Path(__file__).parent / "fire_patrol.py").read_text())
    m = tmp_path / "map.json"
    m.write_text(json.dumps(BASE))
    out = tmp_path / "out"
    args = ["run", str(ctl), "--map", str(m), "--out", str(out), "--ideal-compute", "--quiet",
            "--no-plot"]
    assert main([*args, "--until", "n.next:2"]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["arrivals"] == 4 and s["photos"] == 2 and "n.next" in s["reason"]
    capsys.readouterr()
    for bad in ("n.next:0", "n.next:x", ":2"):
        assert main([*args, "--until", bad]) == 2
        assert "--until expects" in capsys.readouterr().err
    assert main([*args, "--passes", "-1"]) == 2
