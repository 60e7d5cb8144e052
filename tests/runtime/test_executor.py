"""Full missions on the built-in simulator with the hand-written Fire Patrol controller."""

import json
import math

import numpy as np
import pytest

from iterplan_compiler.runtime.bindings import BindingError, Bindings, canon
from iterplan_compiler.runtime.controller import Controller, ControllerTable, run_bindings
from iterplan_compiler.runtime.executor import Executor, RunConfig, ideal_distance, load_controller
from iterplan_compiler.runtime.mapfile import load_map
from iterplan_compiler.runtime.planner import PlannerMode
from iterplan_compiler.runtime.sim import SimParams, SimVehicle
from tests.runtime.fire_patrol import TABLE

MAP = {"name": "fire-patrol-test", "cols": 10, "rows": 8, "home": {"cell": "A1"},
       "arrival_heading": 0,
       "sensors": {"inP": ["B2", "C3", "D3", "E5", "F2", "G7", "H6", "I4", "J8", "A5", "C7", "E1"],
                   "fire": ["C3", "E5", "H6", "B7", "J1"]}}


def fly(sorter="distance", ideal=True, data=MAP, table=TABLE, **kw):
    grid = load_map(data=data)
    v = SimVehicle(SimParams(seed=1), home=grid.home)
    cfg = RunConfig(sorter=sorter, ideal_compute=ideal, **kw)
    return grid, Executor(table, grid, v, config=cfg).run()


@pytest.mark.parametrize("sorter", ["distance", "last", "random"])
def test_fire_patrol_visits_every_patrol_cell_and_photographs_fires(sorter, tmp_path):
    grid, r = fly(sorter)
    assert r.ok, r.reason
    patrol = set(grid.sensors["inP"].tolist())
    fire = set(grid.sensors["fire"].tolist())
    assert len(patrol) >= 10 and fire & patrol and fire - patrol
    visited = [c for _, c, _, _ in r.arrivals]
    assert sorted(visited) == sorted(patrol)                 # each patrol cell exactly once
    assert sorted(c for _, c, _, _ in r.photos) == sorted(fire & patrol)
    # Photos are taken inside the fire cell.
    for _, c, x, y in r.photos:
        assert grid.cell_at(x, y) == c
    s = r.summary
    assert s["arrivals"] == len(patrol) and s["passes"] == 1 and s["misses"] <= 2
    assert s["distance_m"] >= s["ideal_distance_m"] > 0
    assert s["duration_s"] >= s["ideal_duration_s"] and s["overhead_pct"] >= 0
    # Event log: every arrival is an uncontrollable 'arrived' right after a planner arrival.
    labels = [e.label for e in r.log if e.kind in "cu"]
    assert labels.count("arrived") == len(patrol) and labels.count("take.photo") == len(r.photos)
    assert labels[:2] == ["has.next", "y.next"]
    # Outputs.
    r.write_track_csv(tmp_path / "track.csv")
    r.write_geojson(tmp_path / "track.geojson")
    r.write_events_csv(tmp_path / "events.csv")
    r.plot(tmp_path / "track.png")
    assert (tmp_path / "track.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    gj = json.loads((tmp_path / "track.geojson").read_text())
    kinds = [f["properties"]["kind"] for f in gj["features"]]
    assert kinds.count("photo") == len(r.photos) and kinds[0] == "track"
    assert len((tmp_path / "track.csv").read_text().splitlines()) == len(r.track) + 1


def test_distance_sorter_beats_random_and_is_deterministic():
    _, a = fly("distance")
    _, b = fly("distance")
    _, c = fly("random")
    assert a.summary == b.summary and np.array_equal(a.track, b.track)
    assert a.summary["duration_s"] < c.summary["duration_s"]


def test_compute_time_is_charged_to_the_simulated_clock():
    _, r = fly("distance", ideal=False)
    assert r.ok and r.summary["compute_s"] > 0
    _, q = fly("distance", ideal=True)
    assert q.summary["compute_s"] == 0.0


def test_refused_event_ends_mission_safely():
    # This controller only accepts 'no' from the patrol sensor; the first patrol cell offered
    # makes the sensor answer yes.next.inP, which it refuses.
    t = ControllerTable.from_transitions(
        "Bad", 5, [(0, "has.next", 1), (1, "y.next", 2), (1, "n.next", 0),
                   (2, "is.next.inP", 3), (3, "no.next.inP", 4), (4, "remove.next", 0)],
        {"has.next", "is.next.inP", "remove.next"},
        {"y.next", "n.next", "yes.next.inP", "no.next.inP"})
    _, r = fly(table=t)
    assert not r.ok and "unexpected event" in r.reason and "yes.next.inP" in r.reason
    assert any(e.kind == "x" and e.label.startswith("safe end") for e in r.log)


def test_bad_answers_waiting_for_nothing_and_deadlock_are_reported():
    t = ControllerTable.from_transitions("Wait", 2, [(0, "has.next", 1), (1, "mystery", 0)],
                                         {"has.next"}, {"mystery", "y.next", "n.next"})
    _, r = fly(table=t)
    assert not r.ok and "refuses 'y.next'" in r.reason
    t1 = ControllerTable.from_transitions("W", 2, [(0, "take.photo", 1), (1, "mystery", 0)],
                                          {"take.photo"}, {"mystery"})
    _, r1 = fly(table=t1)
    assert not r1.ok and "waits for mystery" in r1.reason
    t2 = ControllerTable.from_transitions("Dead", 2, [(0, "take.photo", 1)], {"take.photo"}, set())
    _, r2 = fly(table=t2)
    assert not r2.ok and "deadlocked" in r2.reason
    t3 = ControllerTable.from_transitions("Odd", 1, [(0, "has.next", 0)], {"has.next"},
                                          {"y.next", "n.next"})
    b = Bindings().bind("has.next", lambda ctx, label: "no.such.answer")
    grid = load_map(data=MAP)
    r3 = Executor(t3, grid, SimVehicle(home=grid.home), bindings=b,
                  config=RunConfig(ideal_compute=True)).run()
    assert not r3.ok and "binding answered 'no.such.answer'" in r3.reason


@pytest.mark.parametrize("ideal", [True, False])
def test_livelock_is_detected(ideal):
    # Never removes: asks about the same location forever.
    t = ControllerTable.from_transitions(
        "Loop", 4, [(0, "has.next", 1), (1, "y.next", 2), (1, "n.next", 0),
                    (2, "is.next.inP", 3), (3, "no.next.inP", 0), (3, "yes.next.inP", 0)],
        {"has.next", "is.next.inP"}, {"y.next", "n.next", "yes.next.inP", "no.next.inP"})
    _, r = fly(table=t, ideal=ideal, livelock_limit=2000)
    assert not r.ok and "livelock" in r.reason


def test_missing_sensor_is_a_clear_error():
    t = ControllerTable.from_transitions(
        "S", 3, [(0, "has.next", 1), (1, "y.next", 2), (2, "is.next.smoke", 0)],
        {"has.next", "is.next.smoke"}, {"y.next", "n.next", "yes.next.smoke", "no.next.smoke"})
    with pytest.raises(BindingError, match="sensor 'smoke'"):
        fly(table=t)


def test_custom_sensor_and_action_bindings():
    grid = load_map(data=MAP)
    shots = []
    b = Bindings().sensor("inP", lambda cell: cell in (11, 12)).bind(
        "take_photo", lambda ctx, label: shots.append(ctx.current_cell()))
    v = SimVehicle(SimParams(), home=grid.home)
    r = Executor(TABLE, grid, v, bindings=b, config=RunConfig(ideal_compute=True)).run()
    assert r.ok and sorted(c for _, c, _, _ in r.arrivals) == [11, 12]
    assert shots == [] and canon("Has_Next?") == "has.next"


def test_label_spellings_are_matched():
    # Underscore spellings (as in MTSA's Patrol benchmark) bind the same way.
    ren = {lab: lab.replace(".", "_") for lab in TABLE.controllable | TABLE.uncontrollable}
    t = ControllerTable.from_transitions(
        "U", TABLE.num_states,
        [(s, ren[a], d) for s, m in TABLE.delta.items() for a, d in m.items()],
        {ren[a] for a in TABLE.controllable}, {ren[a] for a in TABLE.uncontrollable})
    grid, r = fly(table=t)
    assert r.ok and len(r.arrivals) == len(grid.sensors["inP"])


def test_progress_lines():
    lines = []
    fly(progress=lines.append, progress_every=30.0)
    assert len(lines) >= 3 and "visited" in lines[-1]


def test_ideal_distance():
    pts = [(100.0, 0.0), (0.0, 0.0), (50.0, 0.0)]
    assert ideal_distance(pts, (0.0, 0.0)) == pytest.approx(100.0)
    assert ideal_distance([], (0.0, 0.0)) == 0.0


def test_run_bindings_protocol():
    c = Controller(TABLE)
    answers = {"has.next": lambda: "y.next", "is.next.inP": lambda: "no.next.inP",
               "remove.next": lambda: None}
    out = run_bindings(c, answers, max_steps=10)
    assert out["trace"][:5] == ["has.next", "y.next", "is.next.inP", "no.next.inP",
                                "remove.next"]
    assert out["steps"] == 10


def test_load_controller(tmp_path):
    src = tmp_path / "ctl.py"
    src.write_text("from tests.runtime.fire_patrol import TABLE\n")
    assert load_controller(src) is TABLE
    bad = tmp_path / "bad.py"
    bad.write_text("x = 1\n")
    with pytest.raises(ValueError, match="defines no controller"):
        load_controller(bad)
    broken = tmp_path / "broken.py"
    broken.write_text("def (\n")
    with pytest.raises(ValueError, match="cannot import"):
        load_controller(broken)
    assert math.isfinite(1.0)


def test_takeoff_land_bindings_and_on_event_stop():
    t = ControllerTable.from_transitions(
        "TL", 8, [(0, "takeoff", 1), (1, "takeoff.ended", 2), (2, "has.next", 3),
                  (3, "y.next", 4), (3, "n.next", 5), (4, "remove.next", 2), (5, "land", 6),
                  (6, "landed", 7), (7, "restart", 0)],
        {"takeoff", "has.next", "remove.next", "land", "restart"},
        {"takeoff.ended", "n.next", "y.next", "landed"})
    grid = load_map(data=MAP)
    v = SimVehicle(SimParams(), home=grid.home)
    seen = []

    def on_event(kind, label):
        seen.append((kind, label))
        return label == "landed"

    cfg = RunConfig(ideal_compute=True, passes=0, on_event=on_event)
    r = Executor(t, grid, v, config=cfg).run()
    assert r.ok and "on_event" in r.reason
    assert v.mode == "LANDED" and v.alt == 0.0
    labels = [lab for _, lab in seen]
    assert labels[:2] == ["takeoff", "takeoff.ended"] and labels[-2:] == ["land", "landed"]
    assert labels.count("remove.next") == len(grid.cells)


def test_compute_clock_is_used_and_think_time_becomes_flight_time():
    # A clock running 2000x fast: a very slow "onboard computer".  Its think time is charged to
    # the simulated clock while the aircraft flies on.
    # A pass over a map with nothing to patrol never waits for the aircraft: with ideal compute
    # it takes no mission time at all, with the slow computer exactly its think time.
    data = {**MAP, "sensors": {"inP": [], "fire": []}}
    import time

    _, slow = fly(ideal=False, compute_clock=lambda: time.perf_counter() * 2000.0, data=data)
    _, ideal = fly(ideal=True, data=data)
    assert slow.ok and ideal.ok and slow.summary["arrivals"] == 0
    assert ideal.summary["duration_s"] == 0.0
    assert slow.summary["compute_s"] > 0.5
    assert slow.summary["duration_s"] == pytest.approx(slow.summary["compute_s"], abs=0.01)
    assert slow.summary["distance_m"] > 0.9 * 18.2 * slow.summary["compute_s"]


@pytest.mark.parametrize("mode", list(PlannerMode))
def test_fire_patrol_in_strong_gusty_wind(mode):
    # 6.7 m/s wind (37 % of airspeed) plus gusts: with the wind-aware planning radius every
    # patrol cell is still visited, inside the cell, without misses piling up.
    grid = load_map(data=MAP)
    v = SimVehicle(SimParams(wind_east=6.0, wind_north=-3.0, gust_std=0.5, seed=2),
                   home=grid.home)
    cfg = RunConfig(ideal_compute=True, planner_mode=mode, wind=7.7)
    r = Executor(TABLE, grid, v, config=cfg).run()
    assert r.ok, r.reason
    assert sorted(c for _, c, _, _ in r.arrivals) == sorted(grid.sensors["inP"].tolist())
    for _, c, x, y in r.arrivals:
        assert grid.cell_at(x, y) == c
    assert r.summary["misses"] <= 2


def test_realtime_paces_the_simulator_and_observe_sees_every_tick():
    import time

    seen = {"ticks": 0, "final": 0, "t": []}

    def observe(ex, final):
        seen["final" if final else "ticks"] += 1
        seen["t"].append(ex.vehicle.time)

    t0 = time.monotonic()
    grid, r = fly(realtime=400.0, observe=observe)
    wall = time.monotonic() - t0
    sim_s = r.summary["duration_s"]
    assert r.ok and seen["final"] == 1 and seen["ticks"] > 100
    assert seen["t"] == sorted(seen["t"])
    # Paced: at least the simulated time / 400 of wall time.
    assert wall >= 0.9 * sim_s / 400.0, (wall, sim_s)
    assert r.summary == fly()[1].summary     # pacing changes nothing observable
