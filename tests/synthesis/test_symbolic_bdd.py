"""Helpers of ``symbolic/bdd.py`` and the chained fixpoint on a scalable game."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from iterplan_compiler.symbolic.bdd import declare_interleaved, new_manager, value_cubes
from iterplan_compiler.synthesis.encode import prepare
from iterplan_compiler.synthesis.fixpoint import gr1_winning
from iterplan_compiler.synthesis.game import SymbolicGame, subgame


@pytest.mark.parametrize("backend", ["cudd", "autoref"])
@pytest.mark.parametrize("n", [1, 2, 5, 16, 17, 32])
def test_value_cubes_match_single_cubes(backend, n):
    try:
        bdd = new_manager(backend=backend)
    except ImportError:
        pytest.skip(f"dd.{backend} not installed")
    cur, _ = declare_interleaved(bdd, "x", 5)
    assert value_cubes(bdd, cur, n) == [cur.eq(bdd, v) for v in range(n)]
    with pytest.raises(ValueError):
        value_cubes(bdd, cur, 33)


def _door_patrol(n):
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
    try:
        from synthesis_bench import door_patrol
    finally:
        sys.path.pop(0)
    return door_patrol(n)


def test_chained_fixpoint_fewer_steps_same_region():
    # DoorPatrol_4: 4 assumptions, 4 guarantees — where the chained μY pays off
    g = SymbolicGame(prepare(_door_patrol(4)))
    reach = g.reachable()
    goals = [gj | g.failures for gj in g.guarantees]
    chained = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach)
    layered = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach, keep_iterates=True)
    assert chained.winning == layered.winning
    assert (chained.winning & g.init) != g.bdd.false
    assert chained.iterations["x"] < layered.iterations["x"]


def test_subgame_membership_all_winning_and_partial():
    g = SymbolicGame(prepare(_door_patrol(3)))
    reach = g.reachable()
    live = reach & ~g.error
    full = subgame(g, live)
    assert all(full.inside[: len(full.tuples) - (full.error is not None)])
    # drop one reachable non-initial state: exactly that state is outside, it is not expanded
    some = next(iter(g.bdd.pick_iter(live & ~g.init, care_vars=g.cur_vars)))
    dropped = g.decode(some, g.cur)
    part = subgame(g, live & ~g.state_cube(dropped))
    outside = [t for s, t in enumerate(part.tuples) if t is not None and not part.inside[s]]
    assert outside == [dropped]
    assert part.edges[part.tuples.index(dropped)] == []
