"""Fast skip (runtime/skip.py): the controller's skip cycles run for many locations at once,
and nothing the mission observes changes — same visits, photos, event counts, final state —
on every bundled example whose map sensors are static, and on a large map."""

from __future__ import annotations

import numpy as np
import pytest

from iterplan_compiler.runtime.controller import load_controller
from iterplan_compiler.runtime.executor import Executor, RunConfig
from iterplan_compiler.runtime.mapfile import load_map
from iterplan_compiler.runtime.sim import SimParams, SimVehicle


def fly(table, grid, fast, **kw):
    v = SimVehicle(SimParams(seed=1), home=grid.home, heading=grid.arrival_heading)
    ex = Executor(table, grid, v, config=RunConfig(ideal_compute=True, fast_skip=fast, **kw))
    return ex.run(), ex


def same_mission(a, b):
    assert a.ok and b.ok, (a.reason, b.reason)
    assert a.arrivals == b.arrivals and a.photos == b.photos
    ca, cb = dict(a.counts), dict(b.counts)
    assert ca.pop("skipped") == 0 and cb.pop("skipped") > 0
    assert ca == cb
    assert np.array_equal(a.track, b.track)


@pytest.mark.parametrize("name", ["fire_patrol", "cover", "ordered_patrol"])
def test_fast_skip_changes_nothing_observable(compiled, name):
    table = load_controller(compiled.module(name))
    grid, _ = compiled.map(name)
    kw = {"passes": 2}
    (a, ea), (b, eb) = fly(table, grid, False, **kw), fly(table, grid, True, **kw)
    same_mission(a, b)
    assert ea.controller.state == eb.controller.state
    assert ea.iterator.num_done == eb.iterator.num_done


def test_fast_skip_with_an_until_hook_sees_every_wanted_event(compiled):
    table = load_controller(compiled.module("ordered_patrol"))
    grid, _ = compiled.map("ordered_patrol")
    seen = {False: [], True: []}

    def hook(fast):
        def on_event(kind, label):
            if label.startswith("visited."):
                seen[fast].append(label)
            return len(seen[fast]) >= 5
        return on_event
    labels = frozenset(a for a in table.controllable | table.uncontrollable
                       if a.startswith("visited."))
    a, _ = fly(table, grid, False, passes=0, on_event=hook(False), on_event_labels=labels)
    b, _ = fly(table, grid, True, passes=0, on_event=hook(True), on_event_labels=labels)
    assert seen[False] == seen[True] and len(seen[True]) == 5
    same_mission(a, b)


def test_dynamic_sensors_are_never_skipped(compiled):
    """Find Nemo's `nemo` sensor has state (answers yes twice): its question is not skipped,
    the static `roi` one is."""
    table = load_controller(compiled.module("find_nemo"))
    grid, _ = compiled.map("find_nemo")
    (a, _), (b, eb) = fly(table, grid, False), fly(table, grid, True)
    assert list(eb.skip_sensors.labels) == ["is.next.roi"]
    same_mission(a, b)


def test_large_map_skips_in_bulk(compiled):
    """Fire Patrol over 200 x 200 cells with 6 patrol cells: ~40,000 skip cycles per pass."""
    table = load_controller(compiled.module("fire_patrol"))
    data = {"name": "big", "cols": 200, "rows": 200, "home": {"cell": "A1"},
            "sensors": {"inP": ["B2", "CZ120", "FA30", "GR190", "K7", "EE77"],
                        "fire": ["K7"]}}
    grid = load_map(data=data)
    (a, _), (b, _) = fly(table, grid, False), fly(table, grid, True)
    same_mission(a, b)
    assert b.counts["skipped"] == 40_000 - 6
    assert sum(1 for e in b.log if e.label.startswith("fast skip")) <= 7
