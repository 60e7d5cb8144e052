"""The flight adapter (experiments.flight) with a hand-written Fire Patrol controller: runs
without the compiler, so the runtime glue and the behaviour checks are tested on their own."""

from __future__ import annotations

import json

from iterplan_compiler.experiments import catalog, flight
from iterplan_compiler.runtime.mapfile import load_map

from .behaviour import check_fire_patrol

# The paper's iterator-based Fire Patrol plan (Fig. 1, top left) in the examples' vocabulary.
HAND_FIRE_PATROL = '''
from iterplan_compiler.runtime.controller import ControllerTable
T = [(0, "takeoff", 1), (1, "takeoff.ended", 2), (2, "has.next", 3), (3, "y.next", 4),
     (3, "n.next", 5), (5, "reset", 2), (4, "is.next.inP", 6), (6, "yes.next.inP", 7),
     (6, "no.next.inP", 8), (8, "remove.next", 2), (7, "go.next", 9), (9, "arrived", 10),
     (10, "is.fire", 11), (11, "yes.fire", 12), (12, "take.photo", 13), (11, "no.fire", 13),
     (13, "remove.next", 2)]
C = {"takeoff", "has.next", "reset", "is.next.inP", "remove.next", "go.next", "is.fire",
     "take.photo"}
U = {"takeoff.ended", "y.next", "n.next", "yes.next.inP", "no.next.inP", "arrived",
     "yes.fire", "no.fire"}
TABLE = ControllerTable.from_transitions("HandFirePatrol", 14, T, C, U)
'''


def test_hand_fire_patrol_flies_one_pass(tmp_path):
    mod = tmp_path / "hand_fire_patrol.py"
    mod.write_text(HAND_FIRE_PATROL)
    path = catalog.examples_dir() / "fire_patrol.json"
    grid = load_map(path)
    res = flight.fly(mod, grid, sorter="distance", stop=lambda e: e.label == "n.next",
                     map_data=json.loads(path.read_text()), max_time=3600)
    assert res.ok, res.reason
    check_fire_patrol(res.log, grid)
    assert res.log[-1].label == "n.next"
    assert len(res.track) > 10
    assert res.speed > 10


def test_dynamic_and_derived_bindings():
    grid = load_map(catalog.examples_dir() / "search_and_map.json")
    b = flight.example_bindings(grid, {
        "dynamic": {"target": {"yes_answers": 2}},
        "derived": {"adjacent": {"neighbours_of": "store.target", "connectivity": 8}}})
    target = int(grid.sensors["target"][0])
    pred = b.sensors["target"]
    assert [pred(target) for _ in range(3)] == [True, True, False]
    assert not pred(target + 1)

    class Ctx:
        def __init__(self, cell):
            self.cell, self.grid, self.notes = cell, grid, []

        def current_cell(self):
            return self.cell

        def note(self, text):
            self.notes.append(text)

    adj = b.sensors["adjacent"]
    assert not adj(target)
    b.custom["store.target"](Ctx(target), "store.target")
    cols = grid.cols
    assert adj(target) and adj(target + 1) and adj(target + cols + 1)
    assert not adj(target + 2) and not adj(target + 2 * cols)
