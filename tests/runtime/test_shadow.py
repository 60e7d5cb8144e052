"""HeadingChoice.PREDICT: a shadow run of the plan (runtime/shadow.py) predicts the next go.next
targets on a fork of the Iterator, stops at what it cannot predict honestly, leaves the real
mission's events unchanged, and its think time is flight time (issue #15, the first patrol
loop)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from iterplan_compiler.experiments import missions
from iterplan_compiler.experiments.sweeps import Case, layout
from iterplan_compiler.runtime.bindings import Bindings
from iterplan_compiler.runtime.controller import ControllerTable
from iterplan_compiler.runtime.executor import Executor, RunConfig, load_controller
from iterplan_compiler.runtime.grid import DynamicSensor
from iterplan_compiler.runtime.iterator import Iterator
from iterplan_compiler.runtime.planner import ArrivalHeadings, HeadingChoice, MotionPlanner
from iterplan_compiler.runtime.shadow import Shadow, ShadowStop
from iterplan_compiler.runtime.sim import SimVehicle
from iterplan_compiler.runtime.skip import static_sensors
from iterplan_compiler.runtime.sorter import Pose, RandomSorter
from iterplan_compiler.runtime.sorters import make_sorter


@pytest.fixture(scope="module")
def patrol(tmp_path_factory):
    from iterplan_compiler.experiments.pipeline import compile_example

    path, _ = compile_example("ordered_patrol", tmp_path_factory.mktemp("ctrl"))
    return load_controller(path)


def _iterator(sorter, n=900, seed=3):
    rng = np.random.default_rng(seed)
    return Iterator(np.arange(n), rng.uniform(0, 1500, n), rng.uniform(0, 1500, n), sorter,
                    Pose(0.0, 0.0, 0.3), block=64, prune_min=256)


def _state(it: Iterator):
    return (it.next, it.num_done, it.remaining().tolist(), it.done.copy())


@pytest.mark.parametrize("kind", ["distance", "random", "last", "tour"])
def test_fork_is_an_independent_copy(kind):
    interesting = np.zeros(900, dtype=bool)
    interesting[[5, 77, 400]] = True
    make = lambda: make_sorter(kind, radius=43.9, interesting=interesting, seed=7)  # noqa: E731
    real, ref = _iterator(make()), _iterator(make())
    for it in (real, ref):
        for _ in range(10):
            it.remove_next()
        it.resort(Pose(700.0, 300.0, 1.0))
    twin = real.fork()
    assert twin.next == real.next and twin.peek_order(50).tolist() == real.peek_order(50).tolist()
    ref.peek_order(50)
    before = _state(real)
    for _ in range(300):                    # the twin moves on: removes, re-sorts, resets
        twin.remove_next()
    twin.resort(Pose(100.0, 1200.0, -2.0))
    twin.skip_run(40)
    twin.reset(Pose(1500.0, 0.0, 0.0))
    twin.remove_next()
    after = _state(real)
    assert after[:3] == before[:3] and np.array_equal(after[3], before[3])
    # ... and the real one goes on exactly as an iterator that was never forked
    for it in (real, ref):
        it.resort(Pose(200.0, 900.0, 2.0))
    order = []
    for it in (real, ref):
        seq = []
        while it.has_next() and len(seq) < 400:
            seq.append(it.next)
            it.remove_next()
        order.append(seq)
    assert order[0] == order[1]


def test_random_fork_draws_from_its_own_generator():
    s = RandomSorter(5)
    twin = s.fork()
    a = twin.keys(np.zeros(4), np.zeros(4), np.arange(4), Pose(0, 0, 0))
    b = s.keys(np.zeros(4), np.zeros(4), np.arange(4), Pose(0, 0, 0))
    assert np.array_equal(a, b)             # same state, separate generators


def _executor(table, case: Case, choice=HeadingChoice.PREDICT, *, visits=4, clock=None,
              bindings=None, sorter=None, fast_skip=True):
    grid = missions.build_grid(case)
    v = SimVehicle(missions.sim_params(missions.VehicleKind.SITL), home=grid.home,
                   heading=layout(case).heading)
    seen = {"p0": 0}
    events: list[tuple[str, str, int]] = []
    holder: dict = {}

    def on_event(kind, label):
        ex = holder["ex"]
        cell = ex.iterator.next if label == "go.next" else -1
        events.append((kind, label, -1 if cell is None else cell))
        seen["p0"] += label == "visited.p.0"
        return seen["p0"] >= visits

    cfg = RunConfig(sorter=sorter or case.sorter, seed=case.seed, passes=0, max_time=3600.0,
                    headings=ArrivalHeadings.GRID, heading_choice=choice, fast_skip=fast_skip,
                    on_event=on_event, on_event_labels=None if not fast_skip else frozenset(
                        a for a in table.controllable | table.uncontrollable
                        if a.startswith("visited.") or a in ("go.next", "arrived")),
                    **({"compute_clock": clock} if clock else {"ideal_compute": True}))
    ex = Executor(table, grid, v, bindings, cfg)
    holder["ex"] = ex
    return ex, events


def test_prediction_is_what_the_real_run_then_visits(patrol):
    case = Case("fig3b", 3000, 3, "distance", 2, loops=2)
    ex, events = _executor(patrol, case)
    res = ex.run()
    assert res.ok, res.reason
    gone = [cell for kind, label, cell in events if label == "go.next"]
    preds = ex.ctx.predictions
    assert preds and ex.ctx.shadow is not None and ex.ctx.shadow.runs == len(preds)
    first = preds[0]
    assert first.start == gone[0] and first.stop is ShadowStop.CLOSED and first.closes
    assert list(first.targets) == gone[1:1 + len(first.targets)]
    assert gone[1 + len(first.targets)] == first.start
    p = [int(missions.build_grid(case).sensors[f"p.{i}"][0]) for i in range(3)]
    assert [first.start, *first.targets] == p
    # the cycle is known from then on: no further shadow runs
    assert len(preds) == 1


def test_event_log_is_unchanged_by_the_shadow(patrol):
    """The controller-observable events (labels, and the cells offered to go.next) are those of
    the same mission without prediction; `random` also checks that the shadow draws from its own
    generator (the order does not depend on the pose)."""
    for sorter in ("last", "random"):
        case = Case("fig3b", 500, 3, sorter, 4, loops=2)
        logs = {}
        for choice in (HeadingChoice.SHORTEST, HeadingChoice.REPEAT, HeadingChoice.PREDICT):
            ex, events = _executor(patrol, case, choice, fast_skip=False)
            assert ex.run().ok
            logs[choice] = events
            if choice is HeadingChoice.PREDICT:
                assert ex.ctx.predictions
        assert logs[HeadingChoice.PREDICT] == logs[HeadingChoice.SHORTEST]
        assert logs[HeadingChoice.PREDICT] == logs[HeadingChoice.REPEAT]


def test_shadow_touches_nothing_of_the_real_mission(patrol):
    """At a go.next decision, a shadow run leaves the controller, the Iterator (and its random
    sorter's generator) and the log as they were."""
    case = Case("fig3b", 2000, 3, "random", 1, loops=2)
    ex, _ = _executor(patrol, case, HeadingChoice.SHORTEST)
    checked = []

    def on_event(kind, label):
        if label != "go.next":
            return False
        it = ex.iterator
        snap = (ex.controller.state, it.next, it.remaining().tolist(), it.done.copy(),
                it.sorter.rng.bit_generator.state, len(ex.log), dict(ex.counts))
        sh = Shadow(ex.table, ex.bindings, ex.skip_sensors, ex.ctx.arrival_pose)
        p = ex.vehicle.pose()
        pred = sh.predict(ex.controller.state, it, it.next, Pose(p.x, p.y, p.course))
        now = (ex.controller.state, it.next, it.remaining().tolist(), it.done.copy(),
               it.sorter.rng.bit_generator.state, len(ex.log), dict(ex.counts))
        assert now[:3] == snap[:3] and np.array_equal(now[3], snap[3]) and now[4:] == snap[4:]
        checked.append(pred)
        return len(checked) >= 3

    ex.cfg.on_event = on_event
    ex.cfg.on_event_labels = None
    assert ex.run().ok
    assert len(checked) == 3 and all(p.targets for p in checked)


def test_shadow_stops_at_a_dynamic_sensor(patrol):
    """p.1 as a dynamic map sensor (its answers run out) is not a static mask: the shadow
    stops at its first question and predicts nothing after p.0; the mission flies on."""
    from iterplan_compiler.runtime.bindings import map_rule_bindings

    case = Case("fig3b", 400, 3, "distance", 0, loops=2)
    grid = missions.build_grid(case)
    dyn = map_rule_bindings(grid, dynamic={"p.1": DynamicSensor(yes_answers=100)})
    ex, events = _executor(patrol, case, bindings=dyn, visits=3)
    assert "is.next.p.1" not in ex.skip_sensors.labels
    assert ex.run().ok
    assert ex.ctx.predictions
    assert all(p.stop is ShadowStop.SENSOR and p.targets == () for p in ex.ctx.predictions
               if p.start == int(grid.sensors["p.0"][0]))


def test_shadow_stops_at_a_user_sensor(patrol):
    case = Case("fig3b", 400, 3, "last", 0, loops=2)
    grid = missions.build_grid(case)
    p2 = int(grid.sensors["p.2"][0])
    user = Bindings().sensor("p.2", lambda c: c == p2)
    ex, _ = _executor(patrol, case, bindings=user, visits=2)
    assert ex.run().ok
    first = ex.ctx.predictions[0]
    assert first.stop is ShadowStop.SENSOR and first.targets == (int(grid.sensors["p.1"][0]),)


@pytest.mark.parametrize("action, answer", [("takeoff", "takeoff.ended"), ("land", "landed"),
                                            ("take.photo", None), ("my.action", None)])
def test_shadow_stops_at_actions_with_effects(action, answer):
    """After the arrival the plan's next action has an effect (or is a user's binding): the
    shadow stops there without taking it."""
    trans = [(0, "go.next", 1), (1, "arrived", 2), (2, action, 3)]
    trans += [(3, answer, 0)] if answer else [(3, "go.next", 1)]
    unc = {"arrived"} | ({answer} if answer else set())
    table = ControllerTable.from_transitions("t", 4, trans, {"go.next", action}, unc)
    user = Bindings().bind("my.action", lambda ctx, label: None)
    bindings = user.resolve(table.controllable, table.uncontrollable, {}, 16)
    it = _iterator(make_sorter("last", interesting=np.zeros(900, bool)))
    sh = Shadow(table, bindings, static_sensors(bindings), lambda pose, c: Pose(0, 0, 0))
    before = _state(it)
    pred = sh.predict(1, it, it.next, Pose(0.0, 0.0, 0.0))
    assert pred.stop is ShadowStop.EFFECT and pred.targets == ()
    assert _state(it)[:3] == before[:3]


def test_shadow_think_time_is_charged_to_the_mission_clock(patrol, monkeypatch):
    """A shadow run that costs 30 s of compute: the aircraft flies those 30 s before the leg
    is planned, and the mission's compute time has them."""
    fake = [0.0]
    real_predict = Shadow.predict

    def slow(self, *a, **kw):
        fake[0] += 30.0
        return real_predict(self, *a, **kw)

    planned_at: list[float] = []
    real_go = MotionPlanner.go

    def go(self, *a, **kw):
        planned_at.append(self.vehicle.time)
        return real_go(self, *a, **kw)

    monkeypatch.setattr(Shadow, "predict", slow)
    monkeypatch.setattr(MotionPlanner, "go", go)
    case = Case("fig3b", 400, 3, "distance", 0, loops=2)
    ex, events = _executor(patrol, case, clock=lambda: fake[0], visits=2)
    res = ex.run()
    assert res.ok
    runs = ex.ctx.shadow.runs
    assert runs >= 1 and ex.compute_s == pytest.approx(30.0 * runs)
    go_t = [e.t for e in ex.log if e.kind == "c" and e.label == "go.next"]
    first_plan = next(t for t in planned_at if t - ex.t0 >= go_t[0] - 1e-9)
    assert first_plan - ex.t0 == pytest.approx(go_t[0] + 30.0, abs=0.3)
    assert math.isfinite(res.summary.get("compute_s", 0.0))
